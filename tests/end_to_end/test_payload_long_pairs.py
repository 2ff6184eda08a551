"""Payloads and drive gains on logs of any length and any number of segments (issue 38 item 1).

A short twin pair (one motion of the RX90 run empty and with the payload of Table 4, torques and
motor currents) and a long pair made of the same motion repeated, each copy a segment of its own
(its clock shifted by the run's span + 1 s) and read in blocks smaller than a segment: the four
payload methods and both gain methods give the short pair's estimates (the rows are the short pair's
rows repeated; only each joint's weight differs, by the degrees of freedom of its residual: r − c
against K r − c), and eq. 13's σ shrinks as 1/√K. Runs whose segments do not pair are refused.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import identify
import rx90sym
from identify.gains.drive_gains import drive_gains
from identify.io.resampling import concatenate
from rx90sym.twin import CurrentSensor

from motions import multisine

COPIES = 3
DURATION = 5.0
BLOCK = 1000  # raw samples: a 1250-sample segment is read in two blocks
SENSOR = CurrentSensor((0.5, 0.6, 0.4, 0.3, 0.25, 0.2), "motor", offsets=(0.1, -0.05, 0.02, 0.0, 0.03, -0.01),
                       noise=0.02)


def repeated(rec, copies: int = COPIES):
    """``rec`` repeated, each copy's clock shifted by its span + 1 s: one segment per copy."""
    shift = rec.t[-1] - rec.t[0] + 1.0
    return concatenate([replace(rec, t=rec.t + k * shift) for k in range(copies)], f"long-{rec.source}",
                       measured=False)


@pytest.fixture(scope="module")
def runs(rx90):
    """{"torques"|"currents": (short empty, short loaded, long empty, long loaded)}."""
    motion = multisine(rx90, 4, duration=DURATION)
    out = {}
    for kind, sensor in (("torques", None), ("currents", SENSOR)):
        e = rx90sym.twin.simulate(rx90, motion, duration=DURATION, noise="quantised", seed=1, currents=sensor)
        l = rx90sym.twin.simulate(rx90, motion, duration=DURATION, noise="quantised", seed=2, payload="tables_4",
                                  currents=sensor)
        e, l = replace(e, source=f"e-{kind}"), replace(l, source=f"l-{kind}")
        out[kind] = (e, l, repeated(e), repeated(l))
    return out


@pytest.fixture(scope="module")
def known(rx90, runs):
    """Method 1's robot: a fit of the empty runs (its columns and processing)."""
    e = runs["torques"][0]
    return identify.fit(rx90, [e], identify.Processing(cutoff=12.0, min_velocity=None, estimate_delay=False),
                        bootstrap_seed=None)


def _payload(rx90, method, empty, loaded, known):
    return identify.payload(rx90, method, empty=[] if method == 1 else [empty], loaded=[loaded],
                            robot_params=known if method == 1 else None, block=BLOCK)


# Measured on motions of seeds 4 and 5: |long − short| up to 0.017 σ (methods 1, 3, 4) and 0.043 σ
# (method 2: two fits of 60 columns, whose weights move most), Mc up to 6.5e-5 relative, σ·√K / σ up to
# 1.021; the gains up to 1.3e-4 σ, their σ·√K / σ up to 1.009.
@pytest.mark.parametrize("method", (1, pytest.param(2, marks=pytest.mark.slow), 3, pytest.param(4, marks=pytest.mark.slow)))
def test_a_long_pair_of_segments_gives_the_short_pairs_payload(rx90, runs, known, method):
    e, l, long_e, long_l = runs["torques"]
    assert long_e.n_segments == COPIES and long_l.n_segments == COPIES
    short = _payload(rx90, method, e, l, known)
    long = _payload(rx90, method, long_e, long_l, known)
    # The same rows K times: the same estimate up to the joints' weights (their residuals' degrees of freedom).
    assert np.all(np.abs(long.values - short.values) <= 0.1 * short.std), (long.values - short.values) / short.std
    assert abs(long["Mc"] - short["Mc"]) <= 3e-4 * short["Mc"]
    np.testing.assert_allclose(long.std * np.sqrt(COPIES), short.std, rtol=0.05)
    if method == 3:
        assert len(long.pairs) == COPIES and len({round(p.lag, 9) for p in long.pairs}) == 1
        assert [p.empty for p in long.pairs] == [f"long-e-torques#{k + 1}" for k in range(COPIES)]


@pytest.mark.parametrize("method", ("same-motion", pytest.param("global", marks=pytest.mark.slow)))
def test_a_long_pair_of_segments_gives_the_short_pairs_gains(rx90, runs, method):
    e, l, long_e, long_l = runs["currents"]
    mass = rx90sym.load_payload("tables_4")["Mc"]
    short = drive_gains(rx90, [e], [l], mass, method=method, fix={6: SENSOR.gains[5]}, block=BLOCK)
    long = drive_gains(rx90, [long_e], [long_l], mass, method=method, fix={6: SENSOR.gains[5]}, block=BLOCK)
    free = slice(0, 5)
    k_short, k_long = short.gains.gains[free], long.gains.gains[free]
    assert np.all(np.abs(k_long - k_short) <= 0.01 * short.gains.std[free]), (k_long - k_short) / short.gains.std[free]
    ls = short.gains.gains * short.rel_std_ls_pct / 100
    np.testing.assert_allclose((long.gains.gains * long.rel_std_ls_pct / 100)[free] * np.sqrt(COPIES), ls[free],
                               rtol=0.03)


def test_segments_that_do_not_pair_are_refused_naming_both_counts(rx90, runs, tmp_path, capsys):
    e, l, long_e, _ = runs["torques"]
    with pytest.raises(ValueError, match=f"has {COPIES} segments and l-torques 1"):
        identify.payload(rx90, 3, empty=[long_e], loaded=[l])
    with pytest.raises(ValueError, match=f"has {COPIES} segments and l-currents 1"):
        drive_gains(rx90, [runs["currents"][2]], [runs["currents"][1]], 4.275)
    # The command: exit 2, the reason, nothing written.
    identify.write_recording(tmp_path / "e.csv", long_e, rx90)
    identify.write_recording(tmp_path / "l.csv", l, rx90)
    from identify.app.cli import main

    out = tmp_path / "p.json"
    assert main(["payload", "--method", "3", "--empty", str(tmp_path / "e.csv"), "--loaded", str(tmp_path / "l.csv"),
                 "--json", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"e.csv has {COPIES} segments and l.csv 1" in err and not out.exists()


@pytest.mark.slow
def test_dask_workers_give_the_serial_estimates(rx90, runs):
    """The blocks as Dask tasks on two worker processes (the runs' columns and row builders pickled):
    the serial payload (method 3, its bootstrap too) and gains."""
    from dask.distributed import Client, LocalCluster

    e, l, long_e, long_l = runs["torques"]
    ce, cl = runs["currents"][2:]
    serial = identify.payload(rx90, 3, empty=[long_e], loaded=[long_l], block=BLOCK)
    gains = drive_gains(rx90, [ce], [cl], 4.275, fix={6: SENSOR.gains[5]}, block=BLOCK)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        spread = identify.payload(rx90, 3, empty=[long_e], loaded=[long_l], block=BLOCK, client=client)
        spread_gains = drive_gains(rx90, [ce], [cl], 4.275, fix={6: SENSOR.gains[5]}, block=BLOCK, client=client)
    np.testing.assert_allclose(spread.values, serial.values, rtol=1e-12)
    np.testing.assert_allclose(spread.bootstrap_std, serial.bootstrap_std, rtol=1e-12)
    np.testing.assert_allclose(spread_gains.gains.gains, gains.gains.gains, rtol=1e-12)
