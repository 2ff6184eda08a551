"""Benchmark of the model (issue 2, issue 3): symbolic build time and compiled regressor speed.

Prints one table: time to build the symbolic model, regressor and base parameters of the RX90
(fresh process state: nothing cached), and the time to evaluate Phi on 10,500 samples (the
paper's 63,000 equations) compiled vs. a Python loop over pinocchio.computeJointTorqueRegressor,
both measured in this run. The target (issue 14): the default observation-matrix path (Phi_b
into the reused workspace that identify.observation_matrix uses, or streamed in chunks) at least
5x faster than the Pinocchio loop, on a 2-core machine.
"""
from __future__ import annotations

import time

import numpy as np

from timing import time_it


def _twin_twenty_seconds(robot) -> float:
    """Wall time of simulating 20 s of a multisine on the twin (closed loop, realistic noise)."""
    import rx90sym

    t = np.arange(5000) / 250.0
    w = 2 * np.pi * np.array([0.1, 0.15, 0.2, 0.25, 0.3, 0.35])
    q = 0.3 * np.sin(w * t[:, None])
    qd, qdd = 0.3 * w * np.cos(w * t[:, None]), -0.3 * w**2 * np.sin(w * t[:, None])
    rx90sym.twin.simulate(robot, (t[:50], q[:50], qd[:50], qdd[:50]), noise="realistic")  # compile/load
    return time_it(lambda: rx90sym.twin.simulate(robot, (t, q, qd, qdd), noise="realistic",
                                                  payload="tables_4"), repeat=2)


def main() -> None:
    import pinocchio as pin

    import rx90sym
    from rx90sym.pinocchio_bridge import pinocchio_model

    t0 = time.perf_counter()
    robot = rx90sym.load_robot("rx90")
    _ = robot.inverse_dynamics, robot.regressor
    t_model = time.perf_counter() - t0
    t0 = time.perf_counter()
    bp = rx90sym.base_parameters(robot)
    t_base = time.perf_counter() - t0

    rng = np.random.default_rng(0)
    N = 10_500
    Q, QD, QDD = rng.uniform(-np.pi, np.pi, (N, 6)), rng.normal(size=(N, 6)), rng.normal(size=(N, 6))
    t0 = time.perf_counter()
    robot.regressor_batch(Q[:2], QD[:2], QDD[:2])  # compile (or load from the cache)
    t_compile = time.perf_counter() - t0
    t_compiled_alloc = time_it(lambda: robot.regressor_batch(Q, QD, QDD))
    buffer = np.empty((N, 6, len(robot.parameter_names)))
    t_compiled = time_it(lambda: robot.regressor_batch(Q, QD, QDD, out=buffer))
    t_base_batch = time_it(lambda: bp.regressor_batch(Q, QD, QDD))
    workspace = bp.regressor_workspace()  # what identify.observation_matrix evaluates into
    t_observation = time_it(lambda: workspace.evaluate(Q, QD, QDD))

    def streamed() -> None:
        for _ in workspace.chunks(Q, QD, QDD):
            pass

    t_streamed = time_it(streamed)

    model = pinocchio_model(robot, np.ones(len(robot.parameter_names)))
    data = model.createData()
    out = np.empty((N, 6, 60))

    def pin_loop():
        for i in range(N):
            out[i] = pin.computeJointTorqueRegressor(model, data, Q[i], QD[i], QDD[i])

    t_pin = time_it(pin_loop, repeat=3)
    t_twin = _twin_twenty_seconds(robot)
    rows = [
        ("build model + regressor (RX90)", t_model, "< 1 s", ""),
        ("base parameters, symbolic (RX90)", t_base, "", ""),
        ("build total", t_model + t_base, "< 1 s", f"{(t_model + t_base) / 1.0:.2f} of target"),
        ("compile/load Phi C code", t_compile, "", ""),
        ("Phi on 10,500 samples, compiled", t_compiled, "", "reference (into a buffer)"),
        ("  same, fresh output array", t_compiled_alloc, "", f"{t_compiled_alloc / t_compiled:.2f}x ref"),
        ("Phi_b on 10,500 samples, compiled", t_base_batch, "", f"{t_base_batch / t_compiled:.2f}x ref"),
        ("Phi_b, observation path (workspace)", t_observation, "", f"{t_observation / t_compiled:.2f}x ref"),
        ("Phi_b, streamed in 2048-sample chunks", t_streamed, "", f"{t_streamed / t_compiled:.2f}x ref"),
        ("pinocchio regressor, Python loop", t_pin, "", f"{t_pin / t_compiled:.1f}x slower (into a buffer)"),
        ("  pinocchio / observation path", t_pin / t_observation, ">= 5", "PASS" if t_pin >= 5 * t_observation else "FAIL"),
        ("  pinocchio / streamed", t_pin / t_streamed, ">= 5", "PASS" if t_pin >= 5 * t_streamed else "FAIL"),
        ("  pinocchio / fresh array (regressor_batch)", t_pin / t_compiled_alloc, "", ""),
        ("twin: 20 s at 250 Hz, realistic, payload", t_twin, "< 5 s", "PASS" if t_twin < 5.0 else "FAIL"),
    ]
    print(f"{'item':44s} {'time [s]':>10s}  {'target':8s} ratio")
    for name, t, target, ratio in rows:
        print(f"{name:44s} {t:10.4f}  {target:8s} {ratio}")
    print(f"backend: {robot._regressor_batch.backend}")


if __name__ == "__main__":
    main()
