"""Arrays to a validated :class:`Recording`: the angle conventions and the one conversion.

Joint-angle conventions: ``"controller"`` (what the robot's controller and its logs use) and
``"model"`` (Khalil's). :func:`_build` converts the angles to Khalil's (the one place the
conversion happens on reading) and runs every check of :mod:`identify.io.checks`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from rx90sym.recording import Recording, RecordingError

from identify.io.checks import _Labels, _check_shapes, _default_labels, _validate

if TYPE_CHECKING:  # for annotations only
    import rx90sym

# Joint-angle conventions: "controller" (what the robot's controller and its logs use) and
# "model" (Khalil's); q_controller = q_model + the robot file's [controller] offsets.
# "staubli" and "khalil" are accepted as their old names.
_CONVENTIONS = ("controller", "model")
_CONVENTION_ALIASES = {"staubli": "controller", "khalil": "model"}
_MEMORY = "<memory>"


def _normalise_convention(convention: str | None, what: str) -> str | None:
    if convention is None:
        return None
    c = str(convention).strip().lower().replace("ä", "a")
    c = _CONVENTION_ALIASES.get(c, c)
    if c not in _CONVENTIONS:
        raise RecordingError(f"{what}: unknown angle convention {convention!r}, expected one of "
                             f"{_CONVENTIONS} (or their old names {tuple(_CONVENTION_ALIASES)})")
    return c


def _resolve_convention(argument: str | None, declared: str | None, source: str) -> str:
    """Convention from the argument or the file; both given and different is an error."""
    arg = _normalise_convention(argument, f"{source} (argument)")
    dec = _normalise_convention(declared, source)
    if arg is not None and dec is not None and arg != dec:
        raise RecordingError(
            f"{source}: the file declares convention '{str(declared).strip()}' ({dec} angles) but "
            f"'{argument}' ({arg} angles) was requested"
        )
    # DESIGN.md: files from a controller carry its angles.
    return arg or dec or "controller"


def _to_model(q: np.ndarray, robot: rx90sym.Robot, convention: str) -> np.ndarray:
    """File angles -> Khalil angles (the one place the conversion happens on reading)."""
    return np.asarray(robot.to_model(q), dtype=float) if convention == "controller" else q


def _build(
    t: np.ndarray, q: np.ndarray, tau: np.ndarray | None, dq: np.ndarray | None,
    robot: rx90sym.Robot, labels: _Labels, source: str, convention: str,
    current: np.ndarray | None = None, aux: dict[str, np.ndarray] | None = None,
    measured: np.ndarray | None = None, segment: np.ndarray | None = None,
) -> Recording:
    q_model = _to_model(q, robot, convention)  # the offsets are constant: dq is unchanged
    segment = _check_layout(measured, segment, source)
    _validate(t, q_model, tau, dq, robot, labels, source, current, aux, segment)
    return Recording(t=t, q=q_model, tau=tau, dq=dq, source=source, robot=robot.name,
                     current=current, aux=dict(aux or {}),
                     measured=None if measured is None else measured == 1, segment=segment)


def _check_layout(measured: np.ndarray | None, segment: np.ndarray | None, source: str) -> np.ndarray | None:
    """``measured`` holds 0/1, ``segment`` whole numbers from 0 growing by steps of 0 or 1."""
    if measured is not None:
        bad = np.flatnonzero((measured != 0) & (measured != 1))
        if bad.size:
            raise RecordingError(f"{source}: column 'measured', row {bad[0] + 1}: {measured[bad[0]]:g} is not 0 or 1")
    if segment is None:
        return None
    steps = np.diff(segment, prepend=0.0)
    bad = np.flatnonzero((steps != 0) & (steps != 1) | ~np.isfinite(segment))
    if bad.size:
        raise RecordingError(f"{source}: column 'segment', row {bad[0] + 1}: {segment[bad[0]]:g} does not "
                             f"continue the previous segment number (0, 1, ... growing by steps of 1)")
    return segment.astype(np.int64)


def recording_from_arrays(
    t: Any, q: Any, tau: Any, robot: rx90sym.Robot, dq: Any = None,
    source: str = _MEMORY, convention: str = "model", current: Any = None,
    aux: dict[str, Any] | None = None,
) -> Recording:
    """Build a validated :class:`Recording` from arrays (simulator, tests, notebooks).

    Args:
        t: (N,) time, s.
        q: (N, n) joint positions, rad, in ``convention`` angles.
        tau: (N, n) joint torques, N·m, joint side, or None with ``current``.
        robot: the ``rx90sym.Robot`` the data belong to.
        dq: optional (N, n) joint velocities, rad/s.
        current: optional (N, n) motor currents, A.
        aux: optional auxiliary columns, name -> (N,) array (never a torque).
        source: name used in messages and kept in the recording.
        convention: ``"model"`` (default: arrays from the model) or ``"controller"``.

    Raises:
        RecordingError: on any check of :mod:`identify.io.checks`.
    """
    conv = _normalise_convention(convention, source)
    t_a = np.asarray(t, dtype=float)
    arrays = {name: np.asarray(v, dtype=float) for name, v in
              (("q", q), ("tau", tau), ("dq", dq), ("current", current)) if v is not None}
    _check_shapes({"t": t_a.shape, **{k: v.shape for k, v in arrays.items()}}, robot, source)
    aux_a = {str(k): np.asarray(v, dtype=float) for k, v in (aux or {}).items()}
    for name, v in aux_a.items():
        if v.shape != t_a.shape:
            raise RecordingError(f"{source}: auxiliary column 'x:{name}' must have shape {t_a.shape}, got {v.shape}")
    labels = _default_labels(source, robot.n)
    return _build(t_a, arrays["q"], arrays.get("tau"), arrays.get("dq"), robot, labels, source, conv,
                  arrays.get("current"), aux_a)
