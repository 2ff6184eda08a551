"""Payload identification, section IV: the four methods on the twin (issue 6)."""
from __future__ import annotations

import numpy as np
import pytest

import identify
import rx90sym
from identify.payloads.methods import grouping_relations, payload
from identify.monitor.payload import PayloadMonitor

from motions import multisine

PAYLOADS = ("tables_4", "tables_5")


@pytest.fixture(scope="module")
def robot_fit(rx90, rx90_base, twin_empty):
    return identify.fit(rx90, twin_empty, identify.Processing(min_velocity=0.1, rest="drop", estimate_delay=False), base=rx90_base).result


@pytest.fixture(scope="module")
def estimates(rx90, rx90_base, twin_empty, twin_loaded, robot_fit):
    out = {}
    for name in PAYLOADS:
        loaded = twin_loaded[name]
        empty = twin_empty[:2]  # the same two motions, run empty
        out[name] = {m: payload(rx90, m, empty=empty if m != 1 else [], loaded=loaded,
                                robot_params=robot_fit if m == 1 else None,
                                a_priori=name, base=rx90_base, min_velocity=0.1) for m in (1, 2, 3, 4)}
    return out


@pytest.mark.parametrize("name", PAYLOADS)
@pytest.mark.parametrize("method", (1, 2, 3, 4))
def test_each_method_recovers_the_payload(estimates, name, method):
    est = estimates[name][method]
    ap = rx90sym.load_payload(name)
    assert abs(est["Mc"] - ap["Mc"]) / ap["Mc"] < 0.01
    assert abs(est["MZc"] - ap["MZc"]) / ap["MZc"] < 0.03
    assert abs(est["XXc"] - ap["XXc"]) / ap["XXc"] < 0.10
    assert abs(est["YYc"] - ap["YYc"]) / ap["YYc"] < 0.10


@pytest.mark.parametrize("name", PAYLOADS)
def test_the_four_methods_agree_within_their_2_sigma(estimates, name):
    for key in ("XXc", "YYc", "MZc", "Mc"):
        ests = [estimates[name][m] for m in (1, 2, 3, 4)]
        for a in ests:
            for b in ests:
                i = a.names.index(key)
                gap = abs(a.values[i] - b.values[i])
                assert gap <= 2 * np.hypot(a.std[i], b.std[i]) + 1e-12, (key, a.method, b.method)


def test_parameters_near_zero_are_reported_as_unreliable(estimates):
    # The paper: XYc, XZc, YZc, MXc, MYc (a priori 0) are not identifiable: large relative sigma.
    for name in PAYLOADS:
        est = estimates[name][3]
        for key in ("XYc", "YZc", "MYc"):
            assert est.rel_std_pct[est.names.index(key)] > 20
        assert est.rel_std_pct[est.names.index("Mc")] < 1


def test_table_is_printed_like_table_4(estimates):
    text = estimates["tables_4"][3].table()
    assert "A priori" in text and "0.107" in text and "4.275" in text and "XYc" in text
    assert "ZZ1R" in estimates["tables_4"][4].table()  # method 4 also prints the robot part


def test_grouping_relations_are_eqs_24_to_27(rx90, rx90_base):
    """Delta beta = K_c chi_c derived from the symbolic K equals eqs. 24-27 typed in."""
    Kc = dict(zip(rx90_base.names, grouping_relations(rx90, rx90_base)))
    d3, rl4 = 0.45, 0.45
    idx = {k: i for i, k in enumerate(rx90sym.PAYLOAD_NAMES)}
    expect = {"ZZ1R": {"Mc": d3**2}, "XX2R": {"Mc": -d3**2}, "ZZ2R": {"Mc": d3**2},
              "MX2R": {"Mc": d3}, "XX3R": {"Mc": rl4**2}, "ZZ3R": {"Mc": rl4**2},
              "MY3R": {"Mc": -rl4}, "XX5R": {"YYc": 1}, "ZZ5R": {"YYc": 1}, "MY5R": {"MZc": -1},
              "XX6R": {"XXc": 1, "YYc": -1}}
    for base_name, row in Kc.items():
        ref = np.zeros(10)
        for k, v in expect.get(base_name, {}).items():
            ref[idx[k]] = v
        for direct in ("XY", "XZ", "YZ", "ZZ", "MX", "MY"):   # body-6 parameters not grouped
            if base_name == f"{direct}6":
                ref[idx[f"{direct}c"]] = 1
        assert np.allclose(row, ref), base_name


def test_constrained_variant_is_consistent_when_the_plain_one_is_not(rx90, rx90_base):
    """Short motion, small load, noisy torques: the plain estimate breaks the pseudo-inertia
    PSD condition, the constrained one does not and honours the weighed mass."""
    small = {"XXc": 0.004, "XYc": 0.0, "XZc": 0.0, "YYc": 0.004, "YZc": 0.0, "ZZc": 0.001,
             "MXc": 0.0, "MYc": 0.0, "MZc": 0.05, "Mc": 0.5}
    noisy = rx90sym.twin.NoiseProfile("noisy", "torque noise only", torque_noise=0.05)
    traj = multisine(rx90, 11, duration=5.0)
    empty = rx90sym.twin.simulate(rx90, traj, duration=5.0, noise=noisy, seed=1)
    loaded = rx90sym.twin.simulate(rx90, traj, duration=5.0, payload=small, noise=noisy, seed=2)
    plain = payload(rx90, 3, empty=[empty], loaded=[loaded], base=rx90_base)
    J = identify.pseudo_inertia(plain.values)
    assert np.linalg.eigvalsh(J).min() < -1e-6
    con = payload(rx90, 3, empty=[empty], loaded=[loaded], base=rx90_base, constrained=True,
                  mass=0.5, mass_tol=0.05)
    assert np.linalg.eigvalsh(identify.pseudo_inertia(con.values)).min() >= -1e-9
    assert abs(con["Mc"] - 0.5) <= 0.05 + 1e-9


def test_monitor_updates_after_each_loaded_motion(rx90, rx90_base, twin_empty, twin_loaded):
    mon = PayloadMonitor(rx90, empty=twin_empty[:2], base=rx90_base)
    first = mon.update(twin_loaded["tables_5"][0])
    second = mon.update(twin_loaded["tables_5"][1])
    assert len(mon.history) == 2
    i = first.names.index("Mc")
    assert abs(second["Mc"] - 7.025) / 7.025 < 0.01
    assert second.std[i] < first.std[i]   # more data, smaller sigma
    # Exact accumulation: the same motions in the other order give the same estimate (a
    # recursive update with drift or forgetting would not).
    other = PayloadMonitor(rx90, empty=twin_empty[:2], base=rx90_base)
    other.update(twin_loaded["tables_5"][1])
    swapped = other.update(twin_loaded["tables_5"][0])
    assert np.allclose(second.values, swapped.values, rtol=1e-9, atol=1e-12)
    # And it is method 4 (weights fixed on the empty motions instead of refitted): within 1 sigma.
    once = payload(rx90, 4, empty=twin_empty[:2], loaded=twin_loaded["tables_5"], base=rx90_base)
    assert np.all(np.abs(second.values - once.values) <= once.std)


def test_bad_inputs_are_refused(rx90, rx90_base, twin_empty, twin_loaded):
    loaded = twin_loaded["tables_4"]
    tx40 = rx90sym.load_robot("tx40")
    with pytest.raises(ValueError, match="not 'tx40'|of robot"):
        payload(tx40, 3, empty=twin_empty[:1], loaded=loaded[:1])
    with pytest.raises(ValueError, match="no empty recordings"):
        payload(rx90, 1, empty=twin_empty[:1], loaded=loaded, robot_params={"ZZ1R": 1.0}, base=rx90_base)
    for m in (2, 3, 4):
        with pytest.raises(ValueError, match="robot_params is for method 1"):
            payload(rx90, m, empty=twin_empty[:1], loaded=loaded[:1], robot_params={"ZZ1R": 1.0}, base=rx90_base)
    with pytest.raises(ValueError, match="differ by up to"):
        payload(rx90, 3, empty=[twin_empty[2]], loaded=[loaded[0]], base=rx90_base)
    still = identify.Recording(loaded[0].t, np.tile(loaded[0].q[:1], (len(loaded[0].t), 1)) +
                               np.c_[loaded[0].q[:, :3] - loaded[0].q[:1, :3], np.zeros((len(loaded[0].t), 3))],
                               loaded[0].tau, source="nowrist.csv", robot="rx90")
    with pytest.raises(ValueError, match="payload is not excited"):
        payload(rx90, 4, empty=twin_empty[:1], loaded=[still], base=rx90_base)
    with pytest.raises(ValueError, match="robot_params"):
        payload(rx90, 1, loaded=loaded, base=rx90_base)


def test_method_3_pairs_runs_logged_separately(rx90, rx90_base, twin_empty, twin_loaded):
    """Issue 11 item 5: the loaded run on another clock, cut at both ends: paired, same estimate."""
    from dataclasses import replace

    empty, loaded = twin_empty[0], twin_loaded["tables_4"][0]
    whole = payload(rx90, 3, empty=[empty], loaded=[loaded], base=rx90_base)
    cut = replace(loaded, t=loaded.t + 250.0, source="later.csv").select(slice(137, 4600))
    res = payload(rx90, 3, empty=[empty], loaded=[cut], base=rx90_base)
    (pair,) = res.pairs
    # The loaded run tracks the reference a little later (closed loop): a few hundredths of a sample.
    assert abs(pair.lag - 250.0) < 0.02 / 250 and pair.gap < 0.02
    assert abs(res["Mc"] - whole["Mc"]) < 2 * whole.std[-1]
    entry = res.to_dict()["pairing"][0]
    assert entry["loaded"] == "later.csv" and entry["lag_s"] == pair.lag


def test_robot_estimates_of_methods_2_and_4_are_in_the_json(rx90, estimates):
    for m in (2, 4):
        d = estimates["tables_4"][m].to_dict()
        names = {p["name"] for p in d["robot"]["parameters"]}
        assert "ZZ1R" in names and all(p["std"] is not None for p in d["robot"]["parameters"])
    assert estimates["tables_4"][3].to_dict()["robot"] is None


@pytest.mark.parametrize("name", PAYLOADS)
def test_method_2_has_a_bootstrap_sigma_like_the_others(estimates, name):
    # Method 2 is a difference of two fits: its bootstrap draws each run's refits and takes the
    # spread of the payload their differences give (eqs. 23-27). On the twin's white noise it must
    # agree with eq. 13's sigma, as the bootstrap of the single-fit methods does.
    est = estimates[name][2]
    boot = est.bootstrap_std
    assert boot is not None and np.all(np.isfinite(boot)), boot
    for key in ("Mc", "MZc", "XXc", "YYc", "ZZc"):
        i = est.names.index(key)
        ratio = boot[i] / est.std[i]
        assert 0.5 < ratio < 2.0, (key, ratio)
