"""What every exported model file shares: the bodies, the joints in the controller's angles, the
actuation terms (rotor inertia, friction, the coupled wrist) and the companion file.

An exported model (URDF, MJCF) is driven by the recordings' joint angles (the controller's):
q_controller = q_model + offset, so joint j sits at Rot(x, alpha_j) Trans(x, d_j)
Rot(z, theta_j - offset_j) Trans(z, r_j) (revolute; prismatic: Trans(z, r_j - offset_j)) and
then moves about (along) its own z. The child frame is then exactly Khalil frame j, in which
the standard parameters are given: link j's body needs no conversion.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from .description import Robot
from .parameters import LINK_PARAMETERS
from .physical import body_problem, parameter_problems
from .rigid_body import RigidBody, physical_problem

_K = len(LINK_PARAMETERS)
COMPANION_FORMAT = "rx90sym-actuation/1"


def companion_path(path: str | Path) -> Path:
    """Where an exported model's companion goes, named per format so that the URDF and the MJCF
    of one fit may share a name: ``NAME.urdf`` -> ``NAME.actuation.json``, any other (MJCF,
    ``NAME.xml``) -> ``NAME.mjcf.actuation.json``."""
    path = Path(path)
    kind = "" if path.suffix.lower() == ".urdf" else ".mjcf"
    return path.with_name(path.stem + kind + ".actuation.json")


def write_model(path: str | Path, text: str, side: dict) -> list[Path]:
    """Write an exported model file and its companion (each atomically); the paths written."""
    from .files import atomic_write, write_json

    out = Path(path)
    atomic_write(out, lambda fh: fh.write(text))
    return [out, write_json(companion_path(out), side)]


def parameter_vector(robot: Robot, params: Mapping[str, float] | Sequence[float]) -> np.ndarray:
    """chi of ``robot`` from a name -> value mapping (all names) or a vector."""
    if isinstance(params, Mapping):
        return robot.parameter_vector(dict(params), strict=True)
    chi = np.asarray(params, dtype=float)
    if chi.shape != (len(robot.parameter_names),):
        raise ValueError(f"params: expected {len(robot.parameter_names)} standard parameters of "
                         f"robot {robot.name!r}, got shape {chi.shape}")
    return chi


def checked_parameters(robot: Robot, params: Mapping[str, float] | Sequence[float]) -> np.ndarray:
    """:func:`parameter_vector`, refused (ValueError naming every link and parameter) unless
    physical: rx90sym.physical.parameter_problems at margin 0, the consistent fit's own check (it
    checks its margin, so a consistent fit always passes). No exported file then holds a negative
    armature, damping or frictionloss."""
    from .urdf_carried import carried_bodies

    chi = parameter_vector(robot, params)
    labels, carried = None, carried_bodies(robot)
    if robot.urdf is not None:
        labels = {str(k + 1): f"parameters of link {k + 1} (URDF link {link!r})" for k, link in enumerate(robot.urdf.links)}
        for body, (_, links) in carried.items():
            labels[body] += f" minus the inertials of the links it carries {list(links)}"
    problems = parameter_problems(robot.parameter_names, chi, labels=labels,
                                  carried={body: p10 for body, (p10, _) in carried.items()})
    if problems:
        raise ValueError("; ".join(problems) + "; export the physically consistent fit (method consistent)")
    return chi


def fmt(x: float) -> str:
    """Shortest exact text of a float (0 as "0")."""
    x = float(x)
    return "0" if x == 0 else repr(x)


def joint_origin(robot: Robot, j: int) -> tuple[np.ndarray, np.ndarray]:
    """(R, p) of joint j's (0-based) frame at zero controller angle in frame j-1 (module doc)."""
    off = float(robot.controller_offsets[j])
    theta, r = robot.theta[j], robot.r[j]
    if robot.sigma[j] == 0:
        theta -= off
    else:
        r -= off
    ca_, sa = math.cos(robot.alpha[j]), math.sin(robot.alpha[j])
    ct, st = math.cos(theta), math.sin(theta)
    Rx = np.array([[1.0, 0, 0], [0, ca_, -sa], [0, sa, ca_]])
    Rz = np.array([[ct, -st, 0], [st, ct, 0], [0, 0, 1.0]])
    return Rx @ Rz, np.array([robot.d[j], -sa * r, ca_ * r])


def quaternion(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a rotation matrix (MuJoCo's order), w >= 0. Shepperd's
    method: the largest of 1 + trace, 1 + 2 R_ii - trace chosen as pivot, so a half turn about
    any axis (w = 0) keeps its axis's signs."""
    R = np.asarray(R, dtype=float)
    t = np.trace(R)
    pivots = [1.0 + t, 1.0 + 2 * R[0, 0] - t, 1.0 + 2 * R[1, 1] - t, 1.0 + 2 * R[2, 2] - t]
    k = int(np.argmax(pivots))
    s = 2.0 * math.sqrt(max(pivots[k], 1e-300))
    if k == 0:
        q = np.array([s / 4, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s])
    elif k == 1:
        q = np.array([(R[2, 1] - R[1, 2]) / s, s / 4, (R[0, 1] + R[1, 0]) / s, (R[0, 2] + R[2, 0]) / s])
    elif k == 2:
        q = np.array([(R[0, 2] - R[2, 0]) / s, (R[0, 1] + R[1, 0]) / s, s / 4, (R[1, 2] + R[2, 1]) / s])
    else:
        q = np.array([(R[1, 0] - R[0, 1]) / s, (R[0, 2] + R[2, 0]) / s, (R[1, 2] + R[2, 1]) / s, s / 4])
    q = q if q[0] >= 0 else -q
    return q / np.linalg.norm(q)


def flange_pose(robot: Robot) -> np.ndarray:
    """4x4 pose of the maker's tool flange in frame n: the robot file's [flange] (identity
    without one); for a URDF robot its tip link (the payload frame of a URDF robot)."""
    if robot.urdf is not None:
        R, p = robot.urdf.tip_in_frame_n
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = R, p
        return T
    return np.array(robot.flange, dtype=float) if robot.flange is not None else np.eye(4)


def payload_in_flange(robot: Robot, payload: Mapping[str, float]) -> RigidBody:
    """The payload (XXc..Mc in the payload frame: frame n of a robot file, the tip link of a URDF
    robot, which is its flange) as a body in the flange frame (not checked physical)."""
    from .payloads import validate_payload

    values = validate_payload(payload)
    body = RigidBody.from_vector(np.array([values[f"{p}c"] for p in LINK_PARAMETERS[:10]]))
    if robot.urdf is None and robot.flange is not None:
        body = body.expressed_in_child(robot.flange[:3, :3], robot.flange[:3, 3])
    return body


def payload_body(robot: Robot, payload: Mapping[str, float]) -> RigidBody:
    """:func:`payload_in_flange`, checked physical (ValueError with the reason)."""
    body = payload_in_flange(robot, payload)
    problem = physical_problem(body)
    if problem:
        raise ValueError(f"payload: not a physical rigid body ({problem})")
    return body


def link_bodies(robot: Robot, chi: np.ndarray) -> list[RigidBody]:
    """Link j's body in Khalil frame j, each checked physical (ValueError naming the link)."""
    out = []
    for j in range(robot.n):
        body = RigidBody.from_vector(chi[_K * j:_K * j + 10])
        problem = body_problem(chi[_K * j:_K * j + 10])
        if problem:
            raise ValueError(f"link {j + 1}: not a physical rigid body ({problem}); export the "
                             f"physically consistent fit (method consistent)")
        out.append(body)
    return out


def limits_in_controller_angles(robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """(lower, upper) joint limits in the controller's angles [rad or m] (inf when none)."""
    return robot.to_controller(robot.limits.q_min), robot.to_controller(robot.limits.q_max)


@dataclass(frozen=True)
class Actuation:
    """Joint-level actuation terms of an exported model.

    armature, damping, friction: per joint [kg m^2, N m s/rad, N m] as a simulator's joint holds
    them; tendon: for a coupled wrist (a, b) the motor of joint b turns with q_a + q_b (eq. 16):
    (a, b, armature, damping, frictionloss) of a fixed tendon q_a + q_b, else None;
    notes: what the model file cannot hold exactly (kept in the companion)."""

    armature: np.ndarray
    damping: np.ndarray
    friction: np.ndarray
    tendon: tuple[int, int, float, float, float] | None
    notes: tuple[str, ...]


def _values(robot: Robot, chi: np.ndarray) -> dict[str, float]:
    return dict(zip(robot.parameter_names, (float(x) for x in chi)))


def joint_terms(robot: Robot, chi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(IA, FV, FS) per joint; an asymmetric-Coulomb joint gets (FS+ + FS-)/2."""
    v = _values(robot, chi)
    IA = np.array([v[f"IA{j}"] for j in range(1, robot.n + 1)])
    FV = np.array([v[f"FV{j}"] for j in range(1, robot.n + 1)])
    FS = np.array([v[f"FS{j}"] for j in range(1, robot.n + 1)])
    for j in robot.asymmetric_coulomb:
        FS[j] = 0.5 * (v[f"FSP{j + 1}"] + v[f"FSN{j + 1}"])
    return IA, FV, FS


def actuation(robot: Robot, chi: np.ndarray, constants_held: bool = False) -> Actuation:
    """The joint and tendon terms that reproduce eqs. 5 and 16-18 in a simulator.

    Coupled wrist (a, b): eqs. 17-18 add IA_b q''_b to row a and IA_b q''_a to row b, so the
    rotor inertia matrix of the pair is [[IA_a, IA_b], [IA_b, IA_b]] = diag(IA_a - IA_b, 0) +
    IA_b (e_a + e_b)(e_a + e_b)^T: joint a's armature IA_a - IA_b, joint b's 0, a tendon
    q_a + q_b with armature IA_b. Viscous friction likewise: joints FV_a - FVM, FV_b - FVM,
    tendon FVM. Both exact when the joint terms are >= 0 (else clipped at 0, with a note).
    Coulomb: the tendon's frictionloss FSM acts on sign(q'_a + q'_b), exact for the "motor"
    form, an approximation of eqs. 17-18's sign(q'_b) / sign(q'_a) for the "paper" form.
    constants_held: the file holds :func:`constant_forces` (MJCF), named so in the notes."""
    IA, FV, FS = joint_terms(robot, chi)
    notes = list(common_notes(robot, constants_held))
    tendon = None
    if robot.coupling is not None:
        a, b = robot.coupling.joints
        v = _values(robot, chi)
        fvm, fsm = v[f"FVM{b + 1}"], v[f"FSM{b + 1}"]
        arm_a, damp_a, damp_b = IA[a] - IA[b], FV[a] - fvm, FV[b] - fvm
        for label, value, j in (("IA", arm_a, a), ("FV", damp_a, a), ("FV", damp_b, b)):
            if value < 0:
                notes.append(f"coupled wrist: joint {j + 1}'s {label} minus the coupled term is {value:.4g} < 0, "
                             f"clipped at 0 in the simulator (approximation)")
        IA[a], IA[b] = max(arm_a, 0.0), 0.0
        FV[a], FV[b] = max(damp_a, 0.0), max(damp_b, 0.0)
        tendon = (a, b, float(v[f"IA{b + 1}"]), float(fvm), float(fsm))
        if robot.coupling.coulomb_sign == "paper":
            notes.append(f"coupled wrist: FSM{b + 1} acts on sign(q'{a + 1} + q'{b + 1}) (tendon frictionloss), "
                         f"eqs. 17-18 use sign(q'{b + 1}) on row {a + 1} and sign(q'{a + 1}) on row {b + 1}")
    return Actuation(IA, FV, FS, tendon, tuple(notes))


def constant_forces(robot: Robot, chi: np.ndarray) -> np.ndarray:
    """Per joint the constant generalised force [N m or N] the environment exerts in the fit's model
    beyond what a joint's damping and frictionloss hold: -OFFj (the motor supplies the offset) and, on
    an asymmetric-Coulomb joint, -(FSPj - FSNj)/2 (FSPj [q'>0] - FSNj [q'<0] is the mean times
    sign(q') plus this half difference wherever the joint moves); 0 elsewhere."""
    v = _values(robot, chi)
    out = np.zeros(robot.n)
    for j in range(robot.n):
        out[j] -= v.get(f"OFF{j + 1}", 0.0)
        if j in robot.asymmetric_coulomb:
            out[j] -= 0.5 * (v[f"FSP{j + 1}"] - v[f"FSN{j + 1}"])
    return out


def constant_joints(robot: Robot) -> tuple[int, ...]:
    """The joints (0-based) with a term of :func:`constant_forces`: torque offsets, asymmetric Coulomb."""
    offsets = set(range(robot.n)) if robot.offsets else {j for j in range(robot.n)
                                                           if f"OFF{j + 1}" in robot.parameter_names}
    return tuple(sorted(offsets | set(robot.asymmetric_coulomb)))


def common_notes(robot: Robot, constants_held: bool = False) -> tuple[str, ...]:
    """What a model file does not hold: asymmetric Coulomb, torque offsets, the spring.
    constants_held: the file holds :func:`constant_forces` as constant actuator forces (MJCF): the
    offsets are exact, the asymmetric Coulomb exact while the joint moves."""
    if constants_held:
        notes = [f"joint {j + 1}: asymmetric Coulomb FS+/FS-: frictionloss (FS+ + FS-)/2 and actuator constant{j + 1} "
                 f"-(FS+ - FS-)/2, exact while the joint moves (at rest the fit's model has no Coulomb term, the "
                 f"constant force remains)" for j in robot.asymmetric_coulomb]
    else:
        notes = [f"joint {j + 1}: asymmetric Coulomb FS+/FS- written as their mean (companion 'other': both)"
                 for j in robot.asymmetric_coulomb]
    if robot.offsets and not constants_held:
        notes.append("torque offsets OFFj are not part of the model file (companion 'other')")
    if robot.spring is not None:
        notes.append(f"the spring of joint {robot.spring.joint + 1} is not part of the model file "
                     f"({robot.spring.label()})")
    return tuple(notes)


def export_joint_names(robot: Robot) -> tuple[str, ...]:
    """The joints' names in exported URDF/MJCF files and their companion JSON: the robot's ROS
    names (robot file ``joint_names``, a URDF's own joints), so that a ``/joint_states`` message
    drives the exported model as it is; ``joint1`` ... ``jointn`` when the robot has none."""
    return robot.ros_joint_names() or tuple(f"joint{j + 1}" for j in range(robot.n))


def companion(robot: Robot, chi: np.ndarray, model_file: str | Path, kind: str,
              notes: Sequence[str] = (), constants_held: bool = False) -> dict[str, Any]:
    """The companion JSON of an exported model file (``kind`` "urdf" or "mjcf"): every joint's
    IA, FV, FS, the other parameters, the frames and angles, and what the file cannot hold
    (``notes``: the file kind's own, e.g. from :func:`actuation`; ``constants_held``: as there)."""
    v = _values(robot, chi)
    IA, FV, FS = joint_terms(robot, chi)
    names = export_joint_names(robot)
    joints = {name: {"IA": float(IA[j]), "FV": float(FV[j]), "FS": float(FS[j])} for j, name in enumerate(names)}
    extra = {name: v[name] for name in robot.parameter_names[_K * robot.n:]}
    return {
        "format": COMPANION_FORMAT, "robot": robot.name, "model_file": Path(model_file).name, "kind": kind,
        "source": robot.source or None,
        "angles": "controller: the recordings' joint angles drive the model without conversion "
                  "(q_controller = q_model + offset; offsets below)",
        "controller_offsets": [float(x) for x in robot.controller_offsets],
        "gravity": [float(g) for g in robot.gravity_vector],
        "units": {"IA": "kg m^2 (kg, prismatic), joint side", "FS": "N m (N)", "FV": "N m s/rad (N s/m)"},
        "joints": joints,
        "other": extra,  # coupled-wrist friction FVMj FSMj, asymmetric Coulomb FSPj FSNj, offsets OFFj
        "coupling": None if robot.coupling is None else {
            "joints": [robot.coupling.joints[0] + 1, robot.coupling.joints[1] + 1],
            "coulomb_sign": robot.coupling.coulomb_sign,
            "equations": "eqs. 17-18: row a += IA_b q''_b + FVM q'_b + FSM s_a, row b += IA_b q''_a + FVM q'_a "
                         "+ FSM s_b (s: sign(q'_b), sign(q'_a) for 'paper', sign(q'_a + q'_b) for 'motor')"},
        "not_in_model_file": list(dict.fromkeys([*notes, *common_notes(robot, constants_held)])),
    }
