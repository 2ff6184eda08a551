"""Drive gains with a payload of known mass (issue 12) and pairing of runs (issue 11 item 5).

Truth: the twin records motor currents through known gains (rx90sym.twin.CurrentSensor), with
current noise and offsets; the gains must come back within 3 sigma over several seeds.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

import rx90sym
from identify.gains.drive_gains import drive_gains
from identify.io.gains import apply_gains, read_gains
from identify.signal.pairing import pair_runs
from rx90sym.files import write_json
from rx90sym.twin import CurrentSensor

from motions import multisine

K_TRUE = np.array([0.5, 0.6, 0.4, 0.3, 0.25, 0.2])  # N m/A, motor side
OFFSETS = (0.1, -0.05, 0.02, 0.0, 0.03, -0.01)      # A
SENSOR = CurrentSensor(tuple(K_TRUE), "motor", offsets=OFFSETS, noise=0.02)
PAYLOAD = "tables_4"


def runs(robot, seed: int, noise: str, duration: float = 20.0, sensor=SENSOR):
    """Two motions, each run empty and loaded (payload of Table 4)."""
    motions = [multisine(robot, 10 * seed + m) for m in (0, 1)]
    empty = [rx90sym.twin.simulate(robot, f, duration=duration, noise=noise, seed=seed, currents=sensor)
             for f in motions]
    loaded = [rx90sym.twin.simulate(robot, f, duration=duration, noise=noise, seed=100 + seed,
                                    payload=PAYLOAD, currents=sensor) for f in motions]
    return empty, loaded


@pytest.fixture(scope="module")
def mass():
    return rx90sym.load_payload(PAYLOAD)["Mc"]


@pytest.fixture(scope="module")
def quantised(rx90):
    return {seed: runs(rx90, seed, "quantised", duration=12.0) for seed in (0, 1, 2)}


@pytest.fixture(scope="module")
def same_motion_fits(rx90, quantised, mass):
    return {seed: drive_gains(rx90, e, l, mass, method="same-motion") for seed, (e, l) in quantised.items()}


def test_twin_currents_give_back_the_torques(rx90):
    """CurrentSensor inverts tau = Rt diag(k) (i - i0): the same seed's torque recording."""
    f = multisine(rx90, 0)
    tau = rx90sym.twin.simulate(rx90, f, duration=2.0, noise="quantised", seed=3)
    sensor = CurrentSensor(tuple(K_TRUE), "motor", offsets=OFFSETS, noise=0.0)
    cur = rx90sym.twin.simulate(rx90, f, duration=2.0, noise="quantised", seed=3, currents=sensor)
    assert cur.tau is None and cur.current is not None
    gains = read_gains(",".join(map(str, K_TRUE)), rx90)
    back = apply_gains(cur, type(gains)(K_TRUE, side="motor", current_offsets=OFFSETS), rx90)
    assert np.max(np.abs(back.tau - tau.tau)) <= 1e-9 * np.max(np.abs(tau.tau))
    np.testing.assert_array_equal(cur.q, tau.q)


@pytest.mark.parametrize("method", ("same-motion", pytest.param("global", marks=pytest.mark.slow)))
def test_gains_recovered_within_3_sigma_over_seeds(rx90, quantised, same_motion_fits, mass, method):
    for seed, (e, l) in quantised.items():
        res = same_motion_fits[seed] if method == "same-motion" else drive_gains(rx90, e, l, mass, method="global")
        z = (res.gains.gains - K_TRUE) / res.gains.std
        assert np.all(np.abs(z) < 3), (seed, z)
        if method == "global":  # current offsets come out of the torque offsets
            assert np.allclose(res.gains.current_offsets, OFFSETS, atol=0.01)


def test_weak_gain_is_flagged(same_motion_fits):
    """Same motion on the RX90: motor 6 (coupled wrist) feels the payload only through its
    unknown inertia terms, so its gain is weakly identified and flagged; the others are not."""
    for res in same_motion_fits.values():
        assert res.flagged == (6,)
        assert res.rel_std_pct[5] > res.flag_pct > np.max(res.rel_std_pct[:5])


def test_plain_least_squares_would_be_biased(rx90, quantised, same_motion_fits):
    """Why instrumental variables: the first (LS) pass is pulled toward zero by current noise."""
    res = same_motion_fits[0]
    e, l = quantised[0]
    ls = drive_gains(rx90, e, l, rx90sym.load_payload(PAYLOAD)["Mc"], method="same-motion", iterations=0)
    # LS is biased low on the weak motor beyond its sigma; IV is not.
    assert ls.gains.gains[5] < K_TRUE[5] - 3 * ls.gains.std[5]
    assert abs(res.gains.gains[5] - K_TRUE[5]) < 3 * res.gains.std[5]


def test_the_mass_scales_every_gain_and_its_error_enters_sigma(rx90, quantised, same_motion_fits, mass):
    e, l = quantised[0]
    ref = same_motion_fits[0]
    heavy = drive_gains(rx90, e, l, 1.01 * mass, method="same-motion", mass_std=0.05)
    np.testing.assert_allclose(heavy.gains.gains / ref.gains.gains, 1.01, rtol=1e-6)
    # The larger of eq. 13's and the bootstrap's relative sigma (both scale-free), with the weighing's.
    expect = np.hypot(np.fmax(ref.rel_std_ls_pct, ref.rel_std_boot_pct), 100 * 0.05 / (1.01 * mass))
    np.testing.assert_allclose(heavy.rel_std_pct, expect, rtol=1e-6)


def test_fixed_gain_and_json_read_back(rx90, quantised, same_motion_fits, mass, tmp_path):
    e, l = quantised[1]
    res = drive_gains(rx90, e, l, mass, method="same-motion", fix={6: K_TRUE[5]})
    assert res.fixed == (6,) and res.flagged == ()
    free = same_motion_fits[1]
    z = (res.gains.gains[:5] - K_TRUE[:5]) / res.gains.std[:5]
    assert np.all(np.abs(z) < 3)
    assert res.gains.std[5] != res.gains.std[5]  # nan: a fixed gain has no sigma
    assert np.all(res.gains.std[:5] <= free.gains.std[:5] * 1.01)
    path = tmp_path / "g.json"
    write_json(path, res.to_dict())
    data = json.loads(path.read_text())
    for key in ("robot", "method", "mass", "gains", "std", "rel_std_pct", "flagged", "fixed", "side",
                "current_offsets"):
        assert key in data, key
    assert data["std"][5] is None and data["fixed"] == [6]
    back = read_gains(str(path), rx90)
    np.testing.assert_array_equal(back.gains, res.gains.gains)
    assert back.side == "motor"


def test_bad_arguments_are_refused(rx90, quantised, mass):
    e, l = quantised[0]
    with pytest.raises(ValueError, match="method"):
        drive_gains(rx90, e, l, mass, method="nope")
    with pytest.raises(ValueError, match="mass"):
        drive_gains(rx90, e, l, -1.0)
    with pytest.raises(ValueError, match="joint 7"):
        drive_gains(rx90, e, l, mass, fix={7: 1.0})
    with pytest.raises(ValueError, match="pairs each"):
        drive_gains(rx90, e, l[:1], mass)
    torque = rx90sym.twin.simulate(rx90, multisine(rx90, 0), duration=2.0, noise="ideal")
    with pytest.raises(ValueError, match="currents"):
        drive_gains(rx90, [torque], [torque], mass)


@pytest.mark.slow
def test_gains_on_the_realistic_twin(rx90, mass):
    """Closed loop, ripple, Stribeck friction, torque and current noise: both methods within 3 sigma."""
    for seed in (0,):
        e, l = runs(rx90, seed, "realistic", duration=15.0)
        for method in ("same-motion", "global"):
            res = drive_gains(rx90, e, l, mass, method=method)
            z = (res.gains.gains - K_TRUE) / res.gains.std
            assert np.all(np.abs(z) < 3), (seed, method, z)


# --------------------------------------------------------------------------- pairing
def _shifted_run(robot, shift: float, clock: float, first: int, last: int, seed: int = 0):
    """The motion of multisine(seed) sampled at t + shift, on a clock starting at ``clock``."""
    f = multisine(robot, seed)
    rec = rx90sym.twin.simulate(robot, lambda t: f(np.asarray(t) + shift), duration=19.0,
                                noise="quantised", seed=seed)
    from dataclasses import replace

    return replace(rec, t=rec.t + clock).select(slice(first, last))


@pytest.mark.parametrize("shift_samples", (0.0, 0.37, -12.6))
def test_pairing_finds_the_lag_to_a_fraction_of_a_sample(rx90, shift_samples):
    step = 1 / 250
    empty = _shifted_run(rx90, 0.5, 3.0, 10, 4500)
    loaded = _shifted_run(rx90, 0.5 + shift_samples * step, 107.0, 40, 4700)
    (p,) = pair_runs(empty, loaded)
    e, l = p.recordings(empty, loaded)
    # loaded clock at the same point of the motion: t_e - 3 + 107 - shift
    expect = 104.0 - shift_samples * step
    assert abs(p.lag - expect) < 0.02 * step
    assert p.gap < 2e-4 and e.n_samples == l.n_samples == p.samples
    np.testing.assert_array_equal(e.t, l.t)


def test_pairing_refuses_another_motion(rx90):
    a = _shifted_run(rx90, 0.0, 0.0, 0, 4000, seed=0)
    b = _shifted_run(rx90, 0.0, 0.0, 0, 4000, seed=1)
    with pytest.raises(ValueError, match="position-tol"):
        pair_runs(a, b, position_tol=0.02)
