"""Writes the notebooks in notebooks/ (no stored outputs). Re-run after editing the cells here."""
from __future__ import annotations

from pathlib import Path

import nbformat
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

OUT = Path(__file__).resolve().parents[1] / "notebooks"

COMMON = """import numpy as np
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import rx90sym, identify, excitation
from pathlib import Path
np.set_printoptions(precision=4, suppress=True)"""

MOTION = '''def multisine(robot, seed, duration=20.0, fraction=0.6):
    """A hand-made motion: sines of a few frequencies per joint, inside the limits."""
    rng = np.random.default_rng(seed)
    lo, hi = np.maximum(robot.limits.q_min, -np.pi), np.minimum(robot.limits.q_max, np.pi)
    centre, amp_q = (lo + hi) / 2, fraction * (hi - lo) / 2
    w = rng.choice(np.arange(1, 9), size=(3, robot.n)) / duration * 2 * np.pi
    ph = rng.uniform(0, 2 * np.pi, (3, robot.n))
    a = amp_q * rng.uniform(0.5, 1, (3, robot.n))
    a /= a.sum(axis=0) / amp_q
    a *= np.minimum(1, np.minimum(0.6 * robot.limits.qd_max / (a * w).sum(0),
                                  0.6 * robot.limits.qdd_max / (a * w**2).sum(0)))
    def traj(t):
        t = np.atleast_1d(t)[:, None, None]
        return (centre + (a * (np.sin(w * t + ph) - np.sin(ph))).sum(1),
                (a * w * np.cos(w * t + ph)).sum(1), -(a * w**2 * np.sin(w * t + ph)).sum(1))
    return traj'''

NOTEBOOKS = {
    "01_model_and_base_parameters.ipynb": [
        ("md", "# The RX90 model and its base parameters\n\nKhalil–Kleinfinger geometry (Table 1), "
               "symbolic Newton–Euler in CasADi, the regressor (eq. 2) and the base parameters "
               "(Table 2, eq. 19) derived two ways."),
        ("code", COMMON),
        ("code", 'robot = rx90sym.load_robot("rx90")\nprint(robot.n, len(robot.parameter_names))\n'
                 'print(robot.parameter_names[:13])'),
        ("md", "The inverse dynamic model and the regressor are CasADi functions; Γ = Φ·χ."),
        ("code", 'chi = robot.parameter_vector(rx90sym.default_parameters(robot))\n'
                 'q = robot.to_model(np.zeros(6)); qd = np.ones(6) * 0.5; qdd = np.zeros(6)\n'
                 'tau = np.array(robot.inverse_dynamics(q, qd, qdd, chi)).ravel()\n'
                 'Phi = np.array(robot.regressor(q, qd, qdd))\n'
                 'print(tau, np.abs(Phi @ chi - tau).max())\n'
                 'print("spring torque at Staubli zero:", np.array(robot.spring_torque(q)).ravel())'),
        ("md", "Cross-check with Pinocchio (`rnea`) on the rigid-body part:"),
        ("code", 'import pinocchio as pin\n'
                 'rigid = chi.copy()\nfor j in range(6): rigid[13*j+10:13*j+13] = 0\nrigid[78:] = 0\n'
                 'model = rx90sym.pinocchio_model(robot, rigid)\n'
                 'print(np.abs(pin.rnea(model, model.createData(), q, qd, qdd) - '
                 'np.array(robot.inverse_dynamics(q, qd, qdd, rigid)).ravel()).max())'),
        ("md", "## Base parameters\n\nSymbolic (regrouping rules, D3 and RL4 kept as symbols) and numeric (QR):"),
        ("code", 'bp = rx90sym.base_parameters(robot, "symbolic")\nprint(bp.table())'),
        ("code", 'bn = rx90sym.base_parameters(robot, "numeric")\n'
                 'print(bn.nb, bn.names == bp.names, np.abs(bn.K - bp.K).max())\n'
                 'print("K at another geometry (D3=0.5, RL4=0.4):", np.array(bp.K_symbolic([0.5, 0.4])).shape)'),
        ("code", 'robot.export_c("generated_c")\nsorted(p.name for p in Path("generated_c").iterdir())'),
    ],
    "02_excitation.ipynb": [
        ("md", "# Optimal excitation trajectory\n\nFinite Fourier series, condition number of the "
               "base observation matrix, IPOPT with exact derivatives. (A short optimisation here; "
               "`rx90 excite` runs the full 20 s one.)"),
        ("code", COMMON),
        ("code", 'robot = rx90sym.load_robot("rx90")\nchi = robot.parameter_vector(rx90sym.default_parameters(robot))\n'
                 'traj = excitation.optimise(robot, duration=10.0, harmonics=4, seed=0, starts=1, '
                 'chi_nominal=chi, time_budget=90.0)\nprint("cond at 250 Hz:", round(traj.cond, 2))'),
        ("code", 'rand = excitation.random_trajectory(robot, 10.0, 4, seed=1, chi_nominal=chi)\n'
                 'print("random feasible trajectory:", round(rand.cond, 1))'),
        ("code", 'print(traj.summary())\ntraj.plot();'),
        ("code", 'traj.save("excitation.csv"); print(open("excitation.csv").readline())'),
    ],
    "03_identification_and_essential_parameters.ipynb": [
        ("md", "# Identification on the twin: WLS, standard deviations, essential parameters\n\n"
               "Recordings simulated with the realistic noise profile; the truth is known."),
        ("code", COMMON),
        ("code", MOTION),
        ("code", 'robot = rx90sym.load_robot("rx90"); bp = rx90sym.base_parameters(robot)\n'
                 'recs = [rx90sym.twin.simulate(robot, multisine(robot, s), duration=20.0, seed=s) for s in range(3)]\n'
                 'drop = identify.Processing(min_velocity=0.1, rest="drop", estimate_delay=False)  # rest rows dropped\n'
                 'res = identify.fit(robot, recs, drop, base=bp).result\nprint(res.table())'),
        ("code", 'truth = dict(zip(bp.names, bp.beta(robot.parameter_vector(rx90sym.default_parameters(robot)))))\n'
                 'z = np.array([(v - truth[n]) / s for n, v, s in zip(res.names, res.values, res.std)])\n'
                 'print("parameters within 3 sigma of the truth:", int(np.sum(np.abs(z) < 3)), "of", len(z))'),
        ("code", 'ess = identify.essential_parameters(res)\nprint(ess.table())'),
        ("code", 'other = rx90sym.twin.simulate(robot, multisine(robot, 9), duration=20.0, seed=9)\n'
                 'val = identify.validate(robot, ess, other, base=bp)\nprint(val.table())'),
    ],
    "04_physical_consistency.ipynb": [
        ("md", "# Physically consistent least squares (LMIs through cvxpy)\n\n"
               "Each link's 4×4 pseudo-inertia is PSD (Wensing et al. 2017); the fit is on β = Kχ."),
        ("code", COMMON),
        ("code", MOTION),
        ("code", 'robot = rx90sym.load_robot("rx90"); bp = rx90sym.base_parameters(robot)\n'
                 'noisy = rx90sym.twin.NoiseProfile("noisy", "large torque noise", torque_noise=0.3)\n'
                 'rec = rx90sym.twin.simulate(robot, multisine(robot, 9, 6.0, 0.15), duration=6.0, noise=noisy, seed=3)\n'
                 'con = identify.fit(robot, [rec], identify.Processing(decimate_to=None, min_velocity=None, estimate_delay=False),\n'
                 '                   "consistent", base=bp).result\n'
                 'print("WLS estimate consistent?", con.wls_was_consistent)\n'
                 'print("cost of the constraints: %.2f %% of the WLS residual" % con.cost_increase_pct)'),
        ("code", 'chi = np.array([con.standard[n] for n in robot.parameter_names])\n'
                 'print(identify.consistency_report(chi, robot.parameter_names).ok)\n'
                 'for j in range(6):\n    print(j + 1, np.linalg.eigvalsh(identify.pseudo_inertia(chi[13*j:13*j+10])).min())'),
    ],
    "05_payload_methods.ipynb": [
        ("md", "# The payload: the four methods of section IV\n\nThe 7.025 kg payload of Table 5 on the twin."),
        ("code", COMMON),
        ("code", MOTION),
        ("code", 'robot = rx90sym.load_robot("rx90"); bp = rx90sym.base_parameters(robot)\n'
                 'trajs = [multisine(robot, s) for s in range(2)]\n'
                 'empty = [rx90sym.twin.simulate(robot, tr, duration=20.0, seed=10 + i) for i, tr in enumerate(trajs)]\n'
                 'loaded = [rx90sym.twin.simulate(robot, tr, duration=20.0, payload="tables_5", seed=20 + i) for i, tr in enumerate(trajs)]\n'
                 'res = identify.fit(robot, empty, identify.Processing(min_velocity=0.1, rest="drop", estimate_delay=False),\n'
                 '                   base=bp).result'),
        ("code", 'for m in (1, 2, 3, 4):\n    p = identify.payload(robot, m, empty=empty if m != 1 else [], loaded=loaded,\n'
                 '                         robot_params=res if m == 1 else None, '
                 'a_priori="tables_5", base=bp, min_velocity=0.1)\n    print(p.table() if m == 3 else '
                 'f"method {m}: Mc = {p[\'Mc\']:.3f}, MZc = {p[\'MZc\']:.3f}, XXc = {p[\'XXc\']:.4f}, YYc = {p[\'YYc\']:.4f}")'),
        ("md", "Monitoring: the estimate after each new loaded motion (the paper's conclusion)."),
        ("code", 'mon = identify.PayloadMonitor(robot, empty=empty, base=bp)\nfor rec in loaded:\n'
                 '    est = mon.update(rec)\n    print(f"Mc = {est[\'Mc\']:.4f} ± {2 * est.std[-1]:.4f}")'),
    ],
    "06_tx40_real_data.ipynb": [
        ("md", "# Real data: Stäubli TX40\n\nMotor-side positions and torques at 5 kHz (FIGAROH), "
               "converted with the gear and coupling matrices; the paper's model plus torque offsets; "
               "validation on the last third of the motion."),
        ("code", COMMON),
        ("code", '# Shipped with the package (FIGAROH examples, Apache-2.0): see data.readme for the source.\n'
                 'data = rx90sym.datasets.tx40()\nprint(data.positions.parent)'),
        ("code", 'tx = rx90sym.load_robot("tx40", offsets=True)\n'
                 'rec = identify.read_motor_recording(data.positions, data.torques, tx, period=data.period)\n'
                 'fit, held = identify.split(rec, 2 / 3)\nobs = identify.observation_matrix(tx, [fit], decimate_to=100.0, min_velocity=None)\nprint(obs.summary())'),
        ("code", 'processing = identify.Processing(decimate_to=100.0, min_velocity=None, estimate_delay=False)  # that of obs\n'
                 'res = identify.fit(tx, [fit], processing, observation=obs).result\nprint(res.table())'),
        ("code", 'val = identify.validate(tx, res, held, decimate_to=100.0)\nprint(val.table())\n'
                 'fig, axes = plt.subplots(6, 1, figsize=(9, 10), sharex=True)\n'
                 'for j, ax in enumerate(axes):\n    ax.plot(val.t, val.measured[:, j], lw=0.7); ax.plot(val.t, val.predicted[:, j], lw=0.7)'),
    ],
}


def main() -> None:
    OUT.mkdir(exist_ok=True)
    for name, cells in NOTEBOOKS.items():
        nb = new_notebook(cells=[new_markdown_cell(src) if kind == "md" else new_code_cell(src)
                                 for kind, src in cells])
        for k, cell in enumerate(nb.cells):
            cell.id = f"cell-{k:02d}"  # fixed ids: regenerating gives identical files (no merge noise)
        nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
        nbformat.write(nb, OUT / name)


if __name__ == "__main__":
    main()
