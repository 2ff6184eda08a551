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
    "07_urdf_arm_loop.ipynb": [
        ("md", "# The loop on a URDF arm: UR5\n\n"
               "What a user runs on their own arm, from its URDF: plan a safe excitation and check it, "
               "identify from a log (here the twin's), export URDF and MJCF and reload the MJCF in MuJoCo, "
               "and identify a payload for the controller. Every step uses the library's defaults, "
               "those of the command named beside it; only the motion is made short (8 s, 3 harmonics, "
               "1 start) to keep the notebook quick."),
        ("code", COMMON + "\nimport warnings"),
        ("code", '# The UR5 (CB3) URDF of the tests, copied beside the notebook (data/README.md: where it comes from).\n'
                 '# rx90 ... --robot data/ur5.urdf --tip tool0; a URDF gives no acceleration limits: a default is assumed.\n'
                 'URDF = Path("data/ur5.urdf")\n'
                 'robot = rx90sym.load_robot(str(URDF), tip="tool0")\n'
                 'print(robot.name, robot.n, "joints; velocity limits", robot.limits.qd_max, "rad/s;",\n'
                 '      "torque limits", robot.limits.tau_max, "N m")'),
        ("md", "## 1. Plan an excitation, safe by default\n\n"
               "`excitation.optimise(robot)` applies `rx90 excite`'s envelope: every moving point 0.05 m "
               "above the mounting plane, the tool and capsule ends at most 1 m/s, narrowed joint ranges and "
               "scaled velocity and acceleration limits, the URDF's collision capsules kept apart, and the "
               "torque limits with the URDF's inertials. The trajectory carries its own check, on a fine grid."),
        ("code", '# rx90 excite --robot data/ur5.urdf --tip tool0 --duration 8 --harmonics 3 --starts 1\n'
                 'traj = excitation.optimise(robot, duration=8.0, harmonics=3, starts=1, seed=0)\n'
                 'print("\\n".join(excitation.envelope_lines(traj.envelope)))\n'
                 'u = traj.usage\n'
                 'print(f"criterion {traj.criterion}, cond {traj.cond:.1f}; checked at {u.rate:g} Hz:")\n'
                 'plane = traj.envelope["mounting_plane_z_m"]  # frame 0 sits 0.089 m above the URDF root\n'
                 'print(f"  lowest point z = {u.min_height:.4f} m in frame 0: {u.min_height - plane:.4f} m above the "\n'
                 '      f"mounting plane (allowed >= {u.z_min - plane:.4f} m)")\n'
                 'print(f"  fastest point {u.max_speed:.3f} m/s (allowed <= {u.speed_max:g} m/s)")\n'
                 'print(f"  smallest capsule clearance {1e3 * u.min_clearance:.1f} mm")\n'
                 'print(f"  largest use of the limits planned with: velocity {u.velocity.max():.3f}, acceleration "\n'
                 '      f"{u.acceleration.max():.3f} (both as the envelope scales them), torque {np.nanmax(u.torque):.3f}; "\n'
                 '      f"violations: {list(u.violations) or \'none\'}")\n'
                 'fig = traj.plot()'),
        ("md", "The same motion checked independently of the optimiser, with Pinocchio on the URDF itself at "
               "500 Hz (the URDF's root frame: its base plane is z = 0): every frame that moves stays 0.05 m "
               "above the base plane, the tool frame `tool0` moves at most 1 m/s (finite differences), and the "
               "joints stay within the URDF's limits. (Pinocchio's frames are the joints' and links' origins; "
               "the envelope's own check above also covers the capsules' ends, which pass lower.)"),
        ("code", 'import pinocchio as pin\n'
                 'model = pin.buildModelFromUrdf(str(URDF)); data = model.createData()\n'
                 'rate = 500.0\n'
                 't, q, qd, qdd = traj.sample(rate)\n'
                 'qc = q + robot.controller_offsets  # the controller\'s angles: the URDF\'s\n'
                 'frames = {f.name: [] for f in model.frames}\n'
                 'for row in qc:\n'
                 '    pin.framesForwardKinematics(model, data, row)\n'
                 '    for f, placement in zip(model.frames, data.oMf):\n'
                 '        frames[f.name].append(placement.translation.copy())\n'
                 'frames = {name: np.array(p) for name, p in frames.items()}\n'
                 'moving = [name for name, p in frames.items() if np.ptp(p[:, 2]) > 1e-9]  # heights that change\n'
                 'low = min(moving, key=lambda name: frames[name][:, 2].min())\n'
                 'lowest = frames[low][:, 2].min()\n'
                 'speed = np.linalg.norm(np.diff(frames["tool0"], axis=0), axis=1).max() * rate\n'
                 'inside = np.all((qc >= model.lowerPositionLimit) & (qc <= model.upperPositionLimit))\n'
                 'joint_speed = (np.abs(np.diff(qc, axis=0)) * rate / model.velocityLimit).max()  # of the URDF\'s limits\n'
                 'print(f"lowest moving frame: {low} at z = {lowest:.4f} m above the base plane (>= 0.05 m)")\n'
                 'print(f"tool0 speed at most {speed:.4f} m/s (<= 1 m/s); joints inside the URDF limits: {inside}; "\n'
                 '      f"fastest joint at {joint_speed:.3f} of its URDF velocity limit (envelope: x0.7)")\n'
                 'assert lowest >= 0.05 - 1e-6 and speed <= 1.0 * 1.01 and inside and joint_speed <= 0.7 * 1.01'),
        ("md", "## 2. A log, and the fit from it\n\n"
               "The twin runs the motion in closed loop with its default, realistic noise profile "
               "(`rx90 simulate`): the \"recorded\" log. A second safe motion (another seed) is held out "
               "for validation."),
        ("code", 'held_traj = excitation.optimise(robot, duration=8.0, harmonics=3, starts=1, seed=1, progress=False)\n'
                 'with warnings.catch_warnings():  # said once here: the twin assumes 50:1 gears for the ripple\n'
                 '    warnings.filterwarnings("ignore", message="twin: robot \'ur5\' has no gear ratios")\n'
                 '    rec = rx90sym.twin.simulate(robot, traj, seed=1)\n'
                 '    held = rx90sym.twin.simulate(robot, held_traj, seed=2)\n'
                 'print("twin: UR5 without gear ratios: the motor torque ripple assumes 50:1 gears")\n'
                 'print(f"recorded: {rec.q.shape[0]} samples of {rec.q.shape[1]} joints over {rec.t[-1] - rec.t[0]:.2f} s; "\n'
                 '      f"held out: {held.q.shape[0]} samples")'),
        ("code", '# rx90 identify recorded.csv --robot data/ur5.urdf --tip tool0 (same defaults: processing, bootstrap seed 0)\n'
                 'fit = identify.fit(robot, [rec])\n'
                 'print(f"chosen: cut-off {fit.cutoff:.3g} Hz, rows at {fit.decimate_to:.3g} Hz, torque delay "\n'
                 '      f"{1e3 * fit.delay:.2f} ms, rest: {fit.rest}")\n'
                 'print(fit.result.table())'),
        ("md", "Validation on the held-out motion, against the raw measured torques, beside the plain OLS "
               "baseline fitted on the same log (q low-passed at 10 Hz, `numpy.gradient`, rigid body plus viscous, "
               "Coulomb and an offset per joint): the last two columns. The verdict below the table says on which "
               "joints the fit beats the baseline, and by how much it loses on the others."),
        ("code", 'val = fit.validate(held)\n'
                 'print(val.table())\n'
                 'fig, axes = plt.subplots(robot.n, 1, figsize=(9, 10), sharex=True)\n'
                 'for j, ax in enumerate(axes):\n'
                 '    ax.plot(val.t, val.measured[:, j], lw=0.7, label="measured")\n'
                 '    ax.plot(val.t, val.predicted[:, j], lw=0.7, label="fit")\n'
                 '    ax.plot(val.t, val.baseline_predicted[:, j], lw=0.7, ls="--", label="plain OLS")\n'
                 '    ax.set_ylabel(f"τ{j + 1} [N m]")\n'
                 'axes[0].legend(ncol=3); axes[-1].set_xlabel("t [s]")'),
        ("md", "## 3. The physically consistent fit\n\n"
               "Standard parameters a simulator accepts (every link's pseudo-inertia positive definite, rotor "
               "inertia and friction non-negative), with the robot's own prior for what the data do not see: "
               "the URDF's inertials, as `rx90 identify --method consistent`."),
        ("code", '# rx90 identify recorded.csv --robot data/ur5.urdf --tip tool0 --method consistent --json id.json\n'
                 'cfit = identify.fit(robot, [rec], method="consistent")\n'
                 'res = cfit.result\n'
                 'print(f"WLS estimate consistent: {res.wls_was_consistent}; cost of the constraints: "\n'
                 '      f"{res.cost_increase_pct:.2f} % of the WLS residual")\n'
                 'truth = rec.meta["true_parameters"]  # the twin\'s: known here, not on a real arm\n'
                 'print("link  mass fit [kg]  twin [kg]")\n'
                 'for j in range(1, robot.n + 1):\n'
                 '    print(f"{j:4d}  {res.standard[f\'M{j}\']:13.3f}  {truth[f\'M{j}\']:9.3f}")\n'
                 'print(cfit.validate(held).table())'),
        ("md", "## 4. Export, and reload in MuJoCo\n\n"
               "`identify.export_urdf` writes the user's URDF back with the chain's `<inertial>` and "
               "`<dynamics>` replaced; `identify.export_mjcf` an MJCF whose world frame is the URDF's root. "
               "Each has a companion JSON with what the format cannot hold (docs/export.md). The exported "
               "URDF reads back with the fitted inertials."),
        ("code", '# rx90 export id.json --urdf ur5_identified.urdf --mjcf ur5_identified.xml\n'
                 'written = identify.export_urdf(cfit, "ur5_identified.urdf") + identify.export_mjcf(cfit, "ur5_identified.xml")\n'
                 'print(*written, sep="\\n")\n'
                 'chi_fit = robot.parameter_vector(res.standard)\n'
                 'back = rx90sym.load_robot("ur5_identified.urdf", tip="tool0")\n'
                 'chi_back = back.parameter_vector(rx90sym.nominal_parameters(back))\n'
                 'inertial = [i for i, n in enumerate(robot.parameter_names) if not n.startswith(("IA", "FS", "FV"))]\n'
                 'print(f"inertials read back from the URDF: largest difference "\n'
                 '      f"{np.abs(chi_back[inertial] - chi_fit[inertial]).max():.1e} (SI units)")'),
        ("md", "MuJoCo's inverse dynamics of the exported MJCF (`mj_inverse`) against the fit's model "
               "(`robot.inverse_dynamics` with the fit's standard parameters) at a few samples of the held-out "
               "motion. MuJoCo applies Coulomb friction (`frictionloss`) through its constraint solver: it is "
               "switched off there and its `FS sign(q̇)` added back. MuJoCo is an optional extra "
               "(`pip install '.[mujoco]'`): without it the cell says so and skips."),
        ("code", 'try:\n'
                 '    import mujoco\n'
                 'except ImportError:\n'
                 '    mujoco = None\n'
                 '    print("skipped: MuJoCo is not installed (an optional extra: pip install \'.[mujoco]\'); "\n'
                 '          "ur5_identified.xml was written without it")\n'
                 'if mujoco is not None:\n'
                 '    mj = mujoco.MjModel.from_xml_path("ur5_identified.xml"); md = mujoco.MjData(mj)\n'
                 '    mj.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT | mujoco.mjtDisableBit.mjDSBL_FRICTIONLOSS)\n'
                 '    FS = np.array([res.standard[f"FS{j}"] for j in range(1, robot.n + 1)])\n'
                 '    th, qh, qdh, qddh = held_traj.sample(250.0)\n'
                 '    worst = 0.0\n'
                 '    for k in np.linspace(0, th.size - 1, 6).astype(int)[1:-1]:\n'
                 '        md.qpos[:], md.qvel[:], md.qacc[:] = qh[k] + robot.controller_offsets, qdh[k], qddh[k]\n'
                 '        mujoco.mj_inverse(mj, md)\n'
                 '        tau_mujoco = md.qfrc_inverse + FS * np.sign(qdh[k])\n'
                 '        tau_fit = np.asarray(robot.inverse_dynamics(qh[k], qdh[k], qddh[k], chi_fit)).ravel()\n'
                 '        worst = max(worst, np.abs(tau_mujoco - tau_fit).max())\n'
                 '        print(f"t = {th[k]:5.2f} s  MuJoCo {tau_mujoco}  fit {tau_fit}")\n'
                 '    print(f"largest difference {worst:.1e} N m")\n'
                 '    assert worst <= 1e-8 * max(1.0, np.abs(tau_fit).max())'),
        ("md", "## 5. A payload for the controller\n\n"
               "A 1.5 kg tool on the flange (a cylinder 3 cm in radius, its centre of gravity 5 cm out along "
               "`tool0`'s z), run on the same motion. Method 4 identifies the robot and the payload together "
               "from the empty and the loaded log, constrained to a physical body. (Method 3 would pair the two "
               "logs sample by sample: on this twin the UR5's wrist 3 follows its reference only within the "
               "tracking error printed below (the twin's motor torque ripple on a wrist whose URDF gives no "
               "rotor inertia), so the two runs of one motion differ and the pairing refuses them, saying so; "
               "method 4 needs no pairing.)"),
        ("code", 'm, r, h = 1.5, 0.03, 0.10  # kg, m: the tool as a solid cylinder, its CoG at z = h / 2\n'
                 'side, axial = m * (3 * r**2 + h**2) / 12, m * r**2 / 2  # about its CoG [kg m^2]\n'
                 'tool = {"Mc": m, "MXc": 0.0, "MYc": 0.0, "MZc": m * h / 2, "XXc": side + m * (h / 2)**2,\n'
                 '        "YYc": side + m * (h / 2)**2, "ZZc": axial, "XYc": 0.0, "XZc": 0.0, "YZc": 0.0}\n'
                 'with warnings.catch_warnings():\n'
                 '    warnings.filterwarnings("ignore", message="twin: robot \'ur5\' has no gear ratios")\n'
                 '    loaded = rx90sym.twin.simulate(robot, traj, payload=tool, seed=3)\n'
                 'print("twin tracking error, largest [rad]:", np.array(rec.meta["tracking_error_max"]))\n'
                 '# rx90 payload --method 4 --constrained --empty recorded.csv --loaded loaded.csv --json payload.json\n'
                 'p = identify.payload(robot, 4, empty=[rec], loaded=[loaded], constrained=True, a_priori=tool)\n'
                 'print("parameter      tool   identified")\n'
                 'for name in rx90sym.PAYLOAD_NAMES:\n'
                 '    print(f"{name:8s} {tool[name]:10.5f} {p[name]:12.5f}")\n'
                 'print(p.headline())'),
        ("md", "In the controller's form: mass, centre of gravity from the tool flange and inertia at it in "
               "the flange's axes (the `flange` block `rx90 payload --json` writes), and the URScript line "
               "`rx90 export payload.json --ur payload.script` writes from it (`set_target_payload`: UR's "
               "e-Series and PolyScope 5 command)."),
        ("code", 'flange = rx90sym.flange_payload(robot, p.as_dict())\n'
                 'print(f"mass {flange.mass:.4f} kg, CoG {flange.cog} m, physical: {flange.problem is None}")\n'
                 'script = rx90sym.ur_script(flange)\n'
                 'Path("payload.script").write_text(script)\n'
                 'print(script)'),
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
