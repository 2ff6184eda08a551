"""A fit's model in MuJoCo: the MJCF ``rx90 export --mjcf`` writes, loaded from its text, and the terms
of the fit's model that MuJoCo's joints cannot hold, applied beside it as generalised forces.

What the MJCF holds (rx90sym.mjcf_export): bodies, rotor inertia (``armature``), viscous friction
(``damping``), Coulomb friction (``frictionloss``), the coupled wrist (a tendon), torque offsets and
asymmetric Coulomb friction's half difference (a constant actuator force). What it cannot hold is
applied from the fit each step (:meth:`SimulatorModel.extra_force`): the spring (a function of q), a
smooth friction form (tanh, Stribeck: a function of q̇, in place of that joint's ``frictionloss``)
and the coupled wrist's Coulomb term of the "paper" form (eqs. 17-18: FSM sign(q̇b) on joint a and
FSM sign(q̇a) on joint b, in place of the tendon's ``frictionloss`` on sign(q̇a + q̇b): on the RX90
twin's exact torques the true model ends 27 and 60 mrad off on joints 5 and 6 after 0.25 s with the
tendon's, 1.3 and 3.4 mrad with this). :attr:`SimulatorModel.terms` names each, for the report.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any, Mapping, Sequence

import numpy as np

import rx90sym
from rx90sym.mjcf_export import mjcf_export
from rx90sym.model_export import parameter_vector
from rx90sym.parameters import INERTIAL, split_name

from identify.io.bags import MissingExtra

__all__ = ["SimulatorModel", "SmoothFriction", "load_mujoco", "nominal_model", "simulator_model",
           "simulator_parameters", "result_parameters"]

#: The extra that loads an MJCF (pyproject's optional dependencies).
MUJOCO_EXTRA = ".[mujoco]"


def load_mujoco() -> Any:
    """The mujoco module, or MissingExtra naming the extra to install."""
    try:
        import mujoco
    except ImportError:
        raise MissingExtra(f"the rollout runs the model in MuJoCo: pip install '{MUJOCO_EXTRA}'") from None
    return mujoco


def simulator_parameters(fit: Any) -> tuple[rx90sym.Robot, dict[str, float]]:
    """(robot, standard parameters) of a fit's model in a simulator: what ``rx90 export`` writes and
    the rollout rolls out (``fit``: an identify.Fit): :func:`result_parameters` of its identified model
    (``Fit.model_result``). ValueError for a fit without bodies (a fit file written before the
    identified model)."""
    result = getattr(fit, "model_result", fit.result)
    if not getattr(result, "standard", None):
        raise ValueError(f"this {fit.result.method} fit holds base parameters only, no physical bodies (a fit file "
                         f"written before the identified model): identify again to export or simulate a model")
    return result_parameters(fit.robot, result)


def result_parameters(robot: rx90sym.Robot, result: Any) -> tuple[rx90sym.Robot, dict[str, float]]:
    """(robot, standard parameters) of a physically consistent ``result``: its ``standard`` table, and the
    torque offsets it fits beyond the robot's own parameters (its columns OFFj) making the robot one with
    offsets (0 on the other joints). ValueError for a result without bodies."""
    standard = getattr(result, "standard", None)
    if not standard:
        raise ValueError(f"a {result.method} result holds base parameters, not physical bodies: nothing to export "
                         f"or simulate")
    offsets = {n: float(v) for n, v in zip(result.names, result.values)
               if n.startswith("OFF") and n not in robot.parameter_names}
    if offsets and not robot.offsets:
        robot = robot.with_options(offsets=True)
    names = set(robot.parameter_names)  # the model's other columns (Stribeck levels, presliding) are applied apart
    return robot, rx90sym.nominal_parameters(robot, {**{k: v for k, v in standard.items() if k in names}, **offsets})


@dataclass(frozen=True)
class SmoothFriction:
    """A joint's smooth Coulomb friction applied from the fit: ``form`` "tanh" (FS tanh(q̇/vs)) or
    "stribeck" ((FS (1 - e) + FST e) sign(q̇), e = exp(-(q̇/vs)²)); joint 0-based, scale vs [rad/s],
    fs, fst [N m] (identify.friction.forms.friction_columns)."""

    joint: int
    form: str
    scale: float
    fs: float
    fst: float = 0.0


def _smooth_torques(smooth: Sequence[SmoothFriction]) -> Any:
    """f(qvel, out): the friction of the joints ``smooth`` at the speeds qvel [rad/s] subtracted from
    ``out`` in place (it opposes the motion): the columns of identify.friction.forms.friction_columns
    times FS (and FST). Plain floats: a few joints at MuJoCo's every step cost less than an array call."""
    tanh = tuple((f.joint, f.fs, f.scale) for f in smooth if f.form == "tanh")
    stribeck = tuple((f.joint, f.fs, f.fst, f.scale) for f in smooth if f.form == "stribeck")

    def subtract(qvel: Any, out: np.ndarray) -> None:
        for j, fs, vs in tanh:
            out[j] -= fs * math.tanh(qvel[j] / vs)
        for j, fs, fst, vs in stribeck:
            v = qvel[j]
            if v != 0:
                e = math.exp(-(v / vs) ** 2)
                out[j] -= (fs * (1 - e) + fst * e) * math.copysign(1.0, v)
    return subtract


@dataclass(frozen=True, eq=False)
class SimulatorModel:
    """One model in MuJoCo: ``name`` ("identified", "nominal", ...), ``robot``, ``mjcf`` (the text
    ``rx90 export --mjcf`` writes), ``model`` (mujoco.MjModel loaded from it; the smooth-friction
    joints' ``frictionloss`` set to 0), ``smooth`` (friction applied from the fit), ``spring`` (the
    robot's spring applied from the fit) and ``terms``: each term beyond MuJoCo's joint properties
    and where it is carried, in words."""

    name: str
    robot: rx90sym.Robot
    mjcf: str
    model: Any
    smooth: tuple[SmoothFriction, ...] = ()
    spring: bool = False
    terms: tuple[str, ...] = ()
    coupled: tuple[int, int, float] | None = None  # (a, b, FSM) of the "paper" form, applied from the fit
    max_step: float = float("inf")  # [s] longest explicit step the smooth friction's slope allows

    @cached_property
    def _smooth(self) -> Any:
        return _smooth_torques(self.smooth)

    @property
    def applies_forces(self) -> bool:
        """Terms computed from the state at every step (else the recorded torque alone is applied)."""
        return self.spring or bool(self.smooth) or self.coupled is not None

    def extra_force(self, qpos: np.ndarray, qvel: np.ndarray) -> np.ndarray:
        """Generalised force [N m] of the terms applied from the fit at MuJoCo's state (controller angles)."""
        return self.add_extra_force(qpos, qvel, np.zeros(self.robot.n))

    def add_extra_force(self, qpos: np.ndarray, qvel: np.ndarray, out: np.ndarray) -> np.ndarray:
        """:meth:`extra_force` added to ``out`` in place (MuJoCo's qfrc_applied at every step: no array made)."""
        if self.spring:  # the spring helps the motor: tau_motor + spring(q) = IDM (rx90sym.twin)
            out += np.asarray(self.robot.spring_torque(self.robot.to_model(qpos))).ravel()
        self._smooth(qvel, out)
        if self.coupled is not None:  # eqs. 17-18, "paper" form: each joint's row takes the other's sign
            a, b, fsm = self.coupled
            out[a] -= fsm * np.sign(qvel[b])
            out[b] -= fsm * np.sign(qvel[a])
        return out


def _smooth_friction(robot: rx90sym.Robot, params: Mapping[str, float], friction: Mapping[str, Any] | None,
                     extra: Mapping[str, float]) -> tuple[SmoothFriction, ...]:
    """The joints of a smooth form in the fit file's ``model.friction`` record ({"form": one or per joint,
    "velocity_scale": per joint}); the Stribeck level FSTj from ``extra`` (the result's own values)."""
    if not friction:
        return ()
    form = friction.get("form", "coulomb")
    forms = [form] * robot.n if isinstance(form, str) else list(form)
    scales = friction.get("velocity_scale") or [None] * robot.n
    out = []
    for j, (f, vs) in enumerate(zip(forms, scales)):
        if f in ("tanh", "stribeck") and vs is not None and f"FS{j + 1}" in params:
            out.append(SmoothFriction(j, f, float(vs), float(params[f"FS{j + 1}"]), float(extra.get(f"FST{j + 1}", 0.0))))
    return tuple(out)


def simulator_model(robot: rx90sym.Robot, params: Mapping[str, float] | Sequence[float], name: str = "identified",
                    payload: Mapping[str, float] | None = None, friction: Mapping[str, Any] | None = None,
                    extra: Mapping[str, float] | None = None) -> SimulatorModel:
    """The model of ``params`` (standard parameters of ``robot``) as ``rx90 export --mjcf`` writes it
    (with ``payload`` XXc..Mc on the flange), loaded in MuJoCo. friction: the fit file's
    ``model.friction`` record (smooth forms applied from the fit); extra: values beyond the standard
    parameters (the Stribeck levels FSTj). ValueError naming a body MuJoCo would refuse; MissingExtra
    without MuJoCo."""
    mujoco = load_mujoco()
    text, side = mjcf_export(robot, params, f"{robot.name}.xml", payload)
    model = mujoco.MjModel.from_xml_string(text)
    values = dict(zip(robot.parameter_names, parameter_vector(robot, params)))
    smooth = _smooth_friction(robot, values, friction, extra or {})
    coupled = None
    if robot.coupling is not None and robot.coupling.coulomb_sign == "paper":
        a, b = robot.coupling.joints
        coupled = (a, b, float(values[f"FSM{b + 1}"]))
        model.tendon_frictionloss[0] = 0.0
    terms = [f"{note} (the MJCF as written)" for note in side["not_in_model_file"]
             if "spring" not in note and not (coupled and note.startswith("coupled wrist: FSM"))]
    if robot.offsets:
        terms.append("torque offsets OFFj: the MJCF's constant actuator forces constantj")
    if coupled is not None:
        a, b, _ = coupled
        terms.append(f"coupled wrist (paper form, eqs. 17-18): FSM{b + 1} sign(q'{b + 1}) on joint {a + 1} and "
                     f"FSM{b + 1} sign(q'{a + 1}) on joint {b + 1} applied from the fit as generalised forces; the "
                     f"MJCF tendon's frictionloss (on sign(q'{a + 1} + q'{b + 1})) off in the rollout")
    for f in smooth:
        model.dof_frictionloss[model.jnt_dofadr[f.joint]] = 0.0
        terms.append(f"joint {f.joint + 1}: {f.form} friction (scale {f.scale:.3g} rad/s) applied from the fit as a "
                     f"generalised force; the MJCF's frictionloss {f.fs:.4g} N m (sign form) off in the rollout")
    if robot.spring is not None:
        terms.append(f"the spring of joint {robot.spring.joint + 1} ({robot.spring.label()}): applied from the fit as "
                     f"a generalised force at every step")
    return SimulatorModel(name, robot, text, model, smooth, robot.spring is not None, tuple(terms), coupled,
                          _stable_step(mujoco, model, smooth))


def _stable_step(mujoco: Any, model: Any, smooth: Sequence[SmoothFriction]) -> float:
    """The longest explicit step [s] under the smooth frictions' steepest slope, FS/vs at rest for tanh
    (h·FS/(vs·M_jj) <= 1/2, M_jj at the model's reference pose): inf without a tanh joint."""
    slopes = [(f.joint, f.fs / f.scale) for f in smooth if f.form == "tanh" and f.fs > 0]
    if not slopes:
        return float("inf")
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    out = float("inf")
    for j, k in slopes:  # M_jj = e_j' M e_j (mj_mulM: the same call in every MuJoCo 3.x and 4.x)
        e, Me = np.zeros(model.nv), np.zeros(model.nv)
        e[model.jnt_dofadr[j]] = 1.0
        mujoco.mj_mulM(model, data, Me, e)
        out = min(out, 0.5 * float(Me[model.jnt_dofadr[j]]) / k)
    return out


def nominal_model(robot: rx90sym.Robot, params: Mapping[str, float], payload: Mapping[str, float] | None = None,
                  friction: Mapping[str, Any] | None = None,
                  extra: Mapping[str, float] | None = None) -> tuple[SimulatorModel | None, str]:
    """(the robot description's own model, what it is) or (None, why there is none): the description's
    bodies and rotor inertias (rx90sym.nominal_parameters: its [nominal] table or URDF inertials) with
    the fitted model's friction and offsets (``params``: the fit's standard parameters)."""
    try:
        nominal = rx90sym.nominal_parameters(robot)
    except ValueError as exc:
        return None, f"no nominal model: {exc}"
    if nominal is None:
        return None, "no nominal model: the robot's description has no bodies (no [nominal] table, no URDF inertials)"
    fitted = dict(zip(robot.parameter_names, parameter_vector(robot, params)))
    values = {k: (nominal[k] if split_name(k)[0] in (*INERTIAL, "IA") else fitted[k]) for k in robot.parameter_names}
    what = "nominal: the description's bodies and rotor inertias, the fit's friction and offsets"
    try:
        return simulator_model(robot, values, "nominal", payload, friction, extra), what
    except ValueError as exc:
        return None, f"no nominal model: its bodies are refused ({exc})"
