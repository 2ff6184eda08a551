"""The momentum observer and the contact monitor on the twin (identify.monitor)."""
from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

import rx90sym
from identify import ContactMonitor
from identify.monitor.log import monitor_log
from monitor_twin import ideal_response, pulses, twin_fit, twin_run, with_external


@pytest.mark.parametrize("name", ["rx90", "panda"])
def test_ideal_twin_residual_is_the_filtered_external_torque(name):
    """On the ideal twin (no noise, the arm on its motion) fitted by the toolkit, the residual equals
    the injected pulses through K/(s + K): within 3 % of their RMS (what is left: the fit's errors,
    the discretisation) and < 5 % of the largest pulse anywhere after the start (the Coulomb step of
    the motion's first and last samples, FS·sign(q̇) from or to q̇ = 0, left out: 0.25 s at each end)."""
    robot = rx90sym.load_robot(name)
    F = twin_fit(name, "ideal")
    rec = twin_run(name, 7, "ideal", 10.0)
    ext, plist = pulses(robot, rec.t, seed=7)
    res = monitor_log(F, with_external(rec, ext), 1e6, keep=True)
    ideal = ideal_response(rec.t, plist, robot.n, res.gain)
    tt = rec.t - rec.t[0]
    err = (res.residual - ideal)[(tt > 0.25) & (tt < tt[-1] - 0.25)]
    assert np.sqrt(np.mean(err ** 2)) < 0.03 * np.sqrt(np.mean(ideal ** 2))
    assert np.abs(err).max() < 0.05 * np.abs(ext).max()


@pytest.mark.parametrize("name", ["rx90", "panda"])
def test_online_monitor_equals_log_mode(name):
    """ContactMonitor.update sample by sample gives the log mode's residual and events; the log mode
    does not depend on its block size."""
    robot = rx90sym.load_robot(name)
    F = twin_fit(name)
    rec = twin_run(name, 3, "realistic", 6.0)
    ext, _ = pulses(robot, rec.t, seed=3, every=1.2)
    inj = with_external(rec, ext)
    T = np.full(robot.n, 2.0)
    whole = monitor_log(F, inj, T, keep=True)
    small = monitor_log(F, inj, T, keep=True, block=257)
    assert np.array_equal(whole.residual, small.residual) and whole.events == small.events
    mon = ContactMonitor(F, rec.rate, thresholds=T)
    qd = np.gradient(inj.q, inj.t, axis=0, edge_order=2)  # as monitor_log differentiates
    r = np.array([mon.update(t, q, v, e)[0] for t, q, v, e in zip(inj.t, inj.q, qd, inj.tau)])
    assert np.abs(r - whole.residual).max() < 1e-9 * max(1.0, np.abs(whole.residual).max())
    mon._tracker.finish()
    assert [e.joints for e in mon.history] == [e.joints for e in whole.events]
    assert len(whole.events) >= 3


def test_current_effort_through_the_fit_gains():
    """With drive gains in the fit, update() takes currents: the same residual as with the torques."""
    from dataclasses import replace

    from identify.io.gains import DriveGains

    robot = rx90sym.load_robot("rx90")
    F = twin_fit("rx90")
    k = np.array([0.5, 0.6, 0.4, 0.3, 0.25, 0.2])
    gains = DriveGains(k, side="motor", current_offsets=np.full(6, 0.05))
    Fg = replace(F, model=replace(F.model, gains=gains.to_dict()))
    rec = twin_run("rx90", 3, "realistic", 6.0)
    current = np.linalg.solve(np.asarray(robot.Rt) @ np.diag(k), rec.tau.T).T + 0.05
    qd = np.gradient(rec.q, rec.t, axis=0)
    a, b = ContactMonitor(F, rec.rate, thresholds=2.0), ContactMonitor(Fg, rec.rate, thresholds=2.0)
    assert b.model.effort == "current"
    for t, q, v, tau, i in list(zip(rec.t, rec.q, qd, rec.tau, current))[:400]:
        ra, rb = a.update(t, q, v, tau)[0], b.update(t, q, v, i)[0]
    assert np.abs(ra - rb).max() < 1e-9 * max(1.0, np.abs(ra).max())


def test_update_allocates_nothing_that_stays():
    """1e5 calls of update(): no net memory growth (tracemalloc), contact-free samples."""
    robot = rx90sym.load_robot("rx90")
    mon = ContactMonitor(twin_fit("rx90"), 250.0, thresholds=1e6)
    rec = twin_run("rx90", 3, "realistic", 6.0)
    qd = np.gradient(rec.q, rec.t, axis=0)
    rows = list(zip(rec.q, qd, rec.tau))
    for k in range(2000):  # warm-up: caches, first-call allocations
        mon.update(k / 250.0, *rows[k % len(rows)])
    tracemalloc.start()
    before = tracemalloc.take_snapshot()
    for k in range(2000, 102_000):
        mon.update(k / 250.0, *rows[k % len(rows)])
    after = tracemalloc.take_snapshot()
    tracemalloc.stop()
    growth = sum(s.size_diff for s in after.compare_to(before, "filename"))
    assert growth < 10_000, f"{growth} bytes kept over 1e5 updates"
    assert robot.n == mon.n


def test_reset_restarts_the_observer():
    F = twin_fit("rx90")
    rec = twin_run("rx90", 3, "realistic", 6.0)
    qd = np.gradient(rec.q, rec.t, axis=0)
    mon = ContactMonitor(F, rec.rate, thresholds=2.0)
    first = [mon.update(t, q, v, e)[0] for t, q, v, e in list(zip(rec.t, rec.q, qd, rec.tau))[:300]]
    mon.reset()
    again = [mon.update(t, q, v, e)[0] for t, q, v, e in list(zip(rec.t, rec.q, qd, rec.tau))[:300]]
    assert np.array_equal(np.array(first), np.array(again))


@pytest.mark.parametrize("form", ["coulomb", "tanh", "stribeck"])
def test_observer_uses_the_fits_own_model(form):
    """With the effort the fit's own model predicts at q̈ = 0 (its base regressor, friction form, spring:
    Φ_b(q, q̇, 0) β − spring = C q̇ + g + f), the observer's u = τ + spring − f − β must be (C + Cᵀ) q̇ =
    Ṁ q̇, the derivative of its own p along q̇ (central differences); moving samples (no rest mask)."""
    from dataclasses import replace

    from identify.estimation.results import IdentificationResult
    from identify.monitor.observer import observer_model
    from identify.observation.rest import coulomb_terms
    from identify.friction.columns import friction_base

    F = twin_fit("rx90")
    robot = F.robot
    base = F.base
    if form != "coulomb":
        base = friction_base(base, coulomb_terms(robot, base.names), form, [0.05 * (j + 1) for j in range(robot.n)])
    rng = np.random.default_rng(0)
    values = dict(zip(F.result.names, F.result.values))
    vals = np.array([values.get(nm, rng.uniform(1.0, 5.0)) for nm in base.names])  # FSTj: random levels
    c = len(base.names)
    result = IdentificationResult(tuple(base.names), vals, np.ones(c), np.ones(c), 1.0, 1.0, 1.0, np.ones(robot.n),
                                  np.ones(robot.n), 100, "wls")
    Fm = replace(F, base=base, result=result)
    model = observer_model(Fm, "torque")
    Q = rng.uniform(-1.5, 1.5, (20, robot.n))
    QD = rng.uniform(0.3, 1.5, (20, robot.n)) * rng.choice([-1, 1], (20, robot.n))
    model_tau = np.einsum("snc,c->sn", base.regressor_batch(Q, QD, np.zeros_like(Q)), vals)
    model_tau -= robot.spring_torque_batch(Q)[:, :, 0]
    params = model.params(np.full(robot.n, 25.0), np.full(robot.n, 1.0), 0.5)
    n, h = robot.n, 1e-6
    for q, v, tau in zip(Q, QD, model_tau):
        out = np.asarray(model.step(q, v, tau, model.initial_state(), 0.0, params).full()).ravel()
        p_plus = np.asarray(model.step(q + h * v, v, tau, model.initial_state(), 0.0, params).full()).ravel()[:n]
        p_minus = np.asarray(model.step(q - h * v, v, tau, model.initial_state(), 0.0, params).full()).ravel()[:n]
        mdot_qd = (p_plus - p_minus) / (2 * h)
        assert np.abs(out[n:2 * n] - mdot_qd).max() < 1e-5 * max(1.0, np.abs(tau).max())


def test_torque_delay_of_the_fit_is_compensated():
    """Torques lagging the positions by 3 samples (12 ms at 250 Hz): with the fit's delay_s = 12 ms
    the residual is the undelayed one, 3 samples later (both modes agree); without it, larger."""
    from dataclasses import replace

    F = twin_fit("rx90", "ideal")
    rec = twin_run("rx90", 7, "ideal", 10.0)
    m = 3
    lagged = np.concatenate([np.repeat(rec.tau[:1], m, axis=0), rec.tau[:-m]])
    late = with_external(rec, rec.tau - lagged)   # tau - (tau - lagged) = lagged
    Fd = replace(F, model=replace(F.model, delay_s=m / rec.rate))
    plain = monitor_log(F, rec, 1e6, keep=True).residual
    comp = monitor_log(Fd, late, 1e6, keep=True).residual
    raw = monitor_log(F, late, 1e6, keep=True).residual
    core = slice(100, -100)
    shifted = comp[m:][core]
    assert np.abs(shifted - plain[:-m][core]).max() < 0.05 * np.abs(raw[core] - plain[core]).max()
    mon = ContactMonitor(Fd, rec.rate, thresholds=1e6)
    qd = np.gradient(late.q, late.t, axis=0, edge_order=2)  # as monitor_log differentiates
    online = np.array([mon.update(t, q, v, e)[0] for t, q, v, e in zip(late.t, late.q, qd, late.tau)])
    assert np.abs(online - comp).max() < 1e-9 * max(1.0, np.abs(comp).max())


def test_offsets_chosen_by_the_fit_are_part_of_the_observers_model():
    """Torque-sensor offsets (1-2 N·m) on the ideal twin, fitted with an offset column per joint (as the
    cross-validated choice adds them, identify.observation.offsets): the observer subtracts them, its
    residual on a held-out contact-free run stays within 3 % of the offsets, while the same run
    without the offsets in the observer's model carries them (the residual's mean is the offset)."""
    from dataclasses import replace

    from identify import fit
    from identify.observation.offsets import offset_base
    from monitor_twin import EXACT

    robot = rx90sym.load_robot("rx90")
    offsets = np.array([1.5, -2.0, 1.2, 1.0, -1.1, 1.3])
    shifted = [replace(twin_run("rx90", s, "ideal", 10.0), tau=twin_run("rx90", s, "ideal", 10.0).tau + offsets)
               for s in (100, 7)]
    F = fit(robot, [shifted[0]], EXACT, base=offset_base(rx90sym.base_parameters(robot), range(robot.n)))
    assert [nm for nm in F.result.names if nm.startswith("OFF")] == [f"OFF{j + 1}" for j in range(robot.n)]
    res = monitor_log(F, shifted[1], 1e6, keep=True)
    tt = shifted[1].t - shifted[1].t[0]
    inner = (tt > 0.5) & (tt < tt[-1] - 0.25)  # the observer's start-up (K_O = 25 rad/s) left out
    print("largest residual with the offsets modelled [N·m]:", np.abs(res.residual[inner]).max(axis=0))
    assert np.abs(res.residual[inner]).max() < 0.03 * np.abs(offsets).min()
    plain = monitor_log(twin_fit("rx90", "ideal"), shifted[1], 1e6, keep=True)
    np.testing.assert_allclose(-plain.residual[inner].mean(axis=0), offsets, rtol=0.1)
