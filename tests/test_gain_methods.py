"""Drive gains (issue 29 item 6): swapped runs named, the two methods compared per joint, refusals
naming the option that changes them; the shared UR10e pair (skipped with a message when absent).

Truth: the twin records currents through known gains (as in test_drive_gains.py).
"""
from __future__ import annotations

import json
import re
import warnings
from dataclasses import replace

import numpy as np
import pytest

import rx90sym
from conftest import SHARED
from identify.app import cli
from identify.gains.drive_gains import drive_gains
from identify.gains.methods import AGREE_SIGMAS, compare_methods
from identify.io.recordings import write_recording
from identify.fitting.plausibility import PlausibilityError
from identify.signal.pairing import pair_runs
from rx90sym.twin import CurrentSensor

from motions import multisine

K_TRUE = (0.5, 0.6, 0.4, 0.3, 0.25, 0.2)  # N m/A, motor side
SENSOR = CurrentSensor(K_TRUE, "motor", offsets=(0.1, -0.05, 0.02, 0.0, 0.03, -0.01), noise=0.02)
UR = SHARED / "data" / "ur10e"
needs_ur = pytest.mark.skipif(not (UR / "ur-20_02_19_14harm50sec.csv").exists(),
                              reason=f"UR10e logs not found in {UR} (../shared is absent)")


@pytest.fixture(scope="module")
def pair(rx90):
    """One motion run empty and loaded (payload of Table 4), 10 s, currents through K_TRUE."""
    f = multisine(rx90, 0)
    sim = rx90sym.twin.simulate
    empty = sim(rx90, f, duration=10.0, noise="quantised", seed=0, currents=SENSOR)
    loaded = sim(rx90, f, duration=10.0, noise="quantised", seed=100, payload="tables_4", currents=SENSOR)
    return replace(empty, source="empty.csv"), replace(loaded, source="loaded.csv")


@pytest.fixture(scope="module")
def mass():
    return rx90sym.load_payload("tables_4")["Mc"]


def test_swapped_runs_are_named_even_with_a_bridged_sample(rx90, pair, mass):
    """The issue's case: the run given as loaded (the empty one) has a bridged sample, which ended
    on "measured must have shape" in the pairing; now the swap itself is named, both files too."""
    empty, loaded = pair
    measured = np.ones(empty.n_samples, dtype=bool)
    measured[700] = False
    empty = replace(empty, measured=measured)
    with pytest.raises(PlausibilityError) as info:
        drive_gains(rx90, [loaded], [empty], mass, method="same-motion")
    flag = info.value.flags[0]
    assert flag.code == "runs_swapped" and flag.action == "swap --empty and --loaded"
    assert "the payload is in loaded.csv (given as --empty), not in empty.csv" in flag.message
    # The right way round the same runs give the true gains: the criterion is their sign.
    res = drive_gains(rx90, [empty], [loaded], mass, method="same-motion")
    assert np.all(np.abs(res.gains.gains - K_TRUE) < 3 * res.gains.std)


def _drifted(rec):
    """The run with joint 2 drifting linearly to 0.025 rad at its end (a replay that drifted)."""
    return replace(rec, q=rec.q + np.array([0, 0.025, 0, 0, 0, 0]) * np.linspace(0, 1, rec.n_samples)[:, None])


def test_a_position_gap_names_the_tolerance_that_accepts_it(rx90, pair, mass):
    empty, loaded = pair
    drifted = _drifted(loaded)
    with pytest.raises(ValueError) as info:
        drive_gains(rx90, [empty], [drifted], mass, method="same-motion")
    msg = str(info.value)
    assert "more than --position-tol 0.02 rad" in msg
    assert "--method global needs no pairing" in msg and "method 4" not in msg
    # The tolerance it names does accept the pair, and is a round figure just above the gap.
    tol = float(re.search(r"--position-tol (\S+) accepts this pair", msg).group(1))
    (pair,) = pair_runs(empty, drifted, position_tol=tol)
    gap = pair.gap
    assert gap <= tol < 1.1 * gap and 0.02 < gap < 0.026
    # Payload method 3 names its own alternative.
    with pytest.raises(ValueError, match="--method 4 needs no pairing"):
        pair_runs(empty, drifted)


def _result(res, gains):
    return replace(res, gains=replace(res.gains, gains=np.asarray(gains, dtype=float)))


def test_the_verdict_is_the_two_sigma_rule_without_the_weighing_error(rx90, pair, mass):
    empty, loaded = pair
    a = drive_gains(rx90, [empty], [loaded], mass, method="same-motion", mass_std=0.05)
    # The weighing error is common to both methods: left out of the comparison's sigma.
    sigma = np.abs(a.gains.gains) * np.fmax(a.rel_std_ls_pct, a.rel_std_boot_pct) / 100
    assert np.all(sigma < a.gains.std)
    # A second result whose joint 3 is 3 combined sigma off and joint 5 1 combined sigma off.
    shifted = a.gains.gains.copy()
    shifted[2] += 3 * np.sqrt(2) * sigma[2]
    shifted[4] -= 1 * np.sqrt(2) * sigma[4]
    b = _result(replace(a, method="global"), shifted)
    sigma_b = np.abs(shifted) * np.fmax(a.rel_std_ls_pct, a.rel_std_boot_pct) / 100
    cmp = compare_methods(a, b)
    expected = np.abs(a.gains.gains - shifted) / np.hypot(sigma, sigma_b)
    np.testing.assert_allclose(cmp.z, expected, rtol=1e-12)
    assert list(cmp.agree) == [True, True, False, True, True, True] and AGREE_SIGMAS == 2.0
    assert "disagree on joint 3" in cmp.table()
    # A fixed gain is not compared.
    fixed = drive_gains(rx90, [empty], [loaded], mass, method="same-motion", fix={6: K_TRUE[5]})
    assert np.isnan(compare_methods(fixed, fixed).z[5]) and compare_methods(fixed, fixed).agree[5]


def test_rx90_gains_runs_both_methods_and_prints_the_verdict(rx90, pair, mass, tmp_path, capsys):
    empty, loaded = pair
    for name, rec in (("e.csv", empty), ("l.csv", _drifted(loaded))):  # the replay drifted 0.025 rad
        write_recording(tmp_path / name, rec, rx90)
    runs = ["--robot", "rx90", "--empty", str(tmp_path / "e.csv"), "--loaded", str(tmp_path / "l.csv"),
            "--mass", str(mass)]
    with warnings.catch_warnings():
        warnings.simplefilter("always")  # the command prints warnings as lines (tests make them errors)
        # Global: the same-motion comparison is refused, naming the tolerance that accepts the pair.
        code = cli.main(["gains", *runs, "--method", "global", "--json", str(tmp_path / "global.json")])
        stdout = capsys.readouterr().out
        assert code == 0 and "methods not compared: same-motion refused the runs" in stdout
        tol = re.search(r"--position-tol (\S+) accepts this pair", stdout).group(1)
        glob = json.loads((tmp_path / "global.json").read_text())
        assert "not_compared" in glob["comparison"]
        # Same-motion with that tolerance: global run too, and the verdict printed.
        code = cli.main(["gains", *runs, "--position-tol", tol, "--json", str(tmp_path / "g.json")])
    stdout = capsys.readouterr().out
    assert code == 0 and "Methods compared" in stdout and "verdict" in stdout
    data = json.loads((tmp_path / "g.json").read_text())
    cmp = data["comparison"]
    assert cmp["methods"] == ["same-motion", "global"] and len(cmp["agree"]) == 6
    # The comparison's global gains are those of rx90 gains --method global on the same runs.
    np.testing.assert_allclose(cmp["gains"][1], glob["gains"], rtol=1e-12)
    np.testing.assert_allclose(cmp["gains"][0], data["gains"], rtol=1e-12)


def test_conflicting_options_only_without_the_comparison(tmp_path, capsys):
    code = cli.main(["gains", "--empty", "e.csv", "--loaded", "l.csv", "--mass", "1", "--method", "global",
                     "--position-tol", "0.03", "--no-compare"])
    assert code == 2 and "--position-tol is for --method same-motion" in capsys.readouterr().err


@needs_ur
@pytest.mark.slow
def test_ur10e_pair_both_methods_agree_within_two_sigma(tmp_path):
    """The shared pair (rows of the source repository, 100 Hz): both methods, the verdict per joint.
    Measured: same-motion 13.28/12.06/10.12/10.38/10.11/10.31, global 11.05/12.24/9.98/10.53/10.52/10.49
    N m/A, z 1.31/0.70/0.69/0.64/1.82/0.84 (docs/drive-gains.md)."""
    from conftest import benchmark_module

    b = benchmark_module("ur10e_gains")
    robot = b.ur10e_robot()
    e, l = b.load_run(UR / b.EMPTY[0], b.EMPTY[1]), b.load_run(UR / b.LOADED[0], b.LOADED[1])
    res = {m: drive_gains(robot, [e], [l], b.MASS, method=m, mass_std=b.MASS_STD) for m in ("same-motion", "global")}
    cmp = compare_methods(res["same-motion"], res["global"])
    assert cmp.agree.all(), cmp.table()
    # And the controller's own constants (independent) lie within 12 % of both on joints 2-6.
    ctrl = b.controller_constants(e)
    assert np.all(np.abs(cmp.gains[:, 1:] / ctrl[1:] - 1) < 0.12)
    with pytest.raises(PlausibilityError, match="the payload is in") as info:
        drive_gains(robot, [l], [e], b.MASS, method="same-motion")
    assert info.value.flags[0].code == "runs_swapped"


@pytest.mark.slow
def test_global_tells_swapped_runs_from_reversed_currents(rx90, pair, mass):
    """Both flip every gain; the robot's viscous friction (identified by global) flips only with the
    runs: currents all logged with their sign reversed are not called a swap."""
    empty, loaded = pair
    with pytest.raises(PlausibilityError) as info:
        drive_gains(rx90, [loaded], [empty], mass, method="global")
    assert info.value.flags[0].code == "runs_swapped"
    reversed_ = [replace(r, current=-r.current) for r in (empty, loaded)]
    with pytest.raises(PlausibilityError) as info:
        drive_gains(rx90, [reversed_[0]], [reversed_[1]], mass, method="global")
    flag = info.value.flags[0]
    assert flag.code == "gains_negative" and "the runs are not swapped" in flag.action
    assert "viscous friction is positive" in flag.action
