"""No contact event on 5 minutes of contact-free motion of the realistic twin (6 and 7 joints), with the
thresholds the toolkit makes itself (issue 30; the hour is benchmarks/monitor_false_alarms.py).

The 5 minutes are the first 15 of the benchmark's runs (tests/monitor_twin.free_run: 20 s multisines of
their own seeds, every third with rests), each monitored on its own. Thresholds: what ``rx90 identify``
stores without --validate (identify.monitor.thresholds.with_contact_thresholds: the held-out blocks of
the fitted run), and identify.monitor.log.calibrate on one other contact-free run.
"""
from __future__ import annotations

import numpy as np
import pytest

from identify.monitor.log import calibrate
from identify.monitor.thresholds import with_contact_thresholds
from monitor_twin import scan_free_motion, twin_fit, twin_run

RUNS = 15  # × 20 s


@pytest.mark.slow
@pytest.mark.parametrize("name", ["rx90", "panda"])
def test_no_event_on_five_minutes_of_free_motion(name):
    F = twin_fit(name)
    own, why = with_contact_thresholds(F, [twin_run(name, 100)])
    assert why == ""
    T = {"identify": own.contact_thresholds, "calibrate": calibrate(F, [twin_run(name, 101)])}
    scans = scan_free_motion(name, F, T, range(RUNS))
    for label, scan in scans.items():
        print(f"\n{name} {label}: {scan.seconds / 60:.1f} min, {len(scan.events)} event(s), largest "
              f"|r|/(T + d) per joint {np.round(scan.margin, 2).tolist()}")
    for label, scan in scans.items():
        assert scan.seconds >= 0.99 * 20.0 * RUNS
        assert scan.events == [], (label, [(k, e.start_s, e.joints, moving) for k, e, moving in scan.events])
