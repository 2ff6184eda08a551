"""The contact monitor on the real UR10e logs (issue 30): every push found, nothing while the arm moves freely.

The logs have no licence: read in place from ../shared, skipped when absent. Figures:
``python benchmarks/ur10e_contacts.py`` and docs/contact-monitor.md.
"""
from __future__ import annotations

import numpy as np
import pytest

from conftest import SHARED, benchmark_module

DATA = SHARED / "data" / "ur10e"
pytestmark = pytest.mark.skipif(not (DATA / "collision" / "ur-20_01_22-push_pose_1.csv").exists(),
                                reason=f"UR10e logs not found in {DATA} (../shared is absent)")


@pytest.fixture(scope="module")
def ur10e():
    b = benchmark_module("ur10e_contacts")
    F, empty, gains = b.ur10e_fit(DATA)
    return b, F, empty


def test_every_push_is_an_event_and_nothing_else(ur10e):
    """Measured: 3 pushes labelled from the currents (4.78-6.26, 8.54-9.95, 11.99-13.51 s), 3 events
    (4.92-5.78, 8.91-9.35, 12.15-13.10 s, thresholds of the held-out blocks), peaks 58, 54, 73 N·m on joint 2."""
    from identify.monitor.log import monitor_log

    b, F, _ = ur10e
    push = b.read(DATA / b.PUSH)
    pushes = b.label_pushes(push)
    res = monitor_log(F, push)
    assert len(pushes) >= 3
    for s, e in pushes:
        assert any(x.start_s <= e and x.end_s >= s for x in res.events), (s, e, res.table())
    for x in res.events:  # every event inside a labelled push
        assert any(x.start_s <= e and x.end_s >= s for s, e in pushes), (x, pushes)


def test_no_event_on_the_free_runs(ur10e):
    """The fitted 14-harmonic run (moving) and ur-20_01_17-p4.csv (at rest): no event."""
    from identify.monitor.log import monitor_log

    b, F, _ = ur10e
    for name, rows in (b.g.EMPTY, ("ur-20_01_17-p4.csv", None)):
        res = monitor_log(F, b.read(DATA / name, rows))
        assert res.events == (), (name, res.table())


def test_online_monitor_on_currents_equals_the_log_mode(ur10e):
    """ContactMonitor.update on the push log's currents (the fit's gains) and recorded velocities."""
    from identify import ContactMonitor
    from identify.monitor.log import monitor_log

    b, F, _ = ur10e
    push = b.read(DATA / b.PUSH)
    res = monitor_log(F, push, keep=True)
    mon = ContactMonitor(F, push.rate)
    r = np.array([mon.update(t, q, v, i)[0] for t, q, v, i in zip(push.t, push.q, push.dq, push.current)])
    assert np.abs(r - res.residual).max() < 1e-9 * np.abs(res.residual).max()
