"""The observation of another friction form on the rows of one already built: only the friction
columns evaluated and parallel-filtered again.

A friction form changes the own-joint Coulomb columns of W only
(:class:`identify.observation.friction_model.FrictionBase`): sign(v) becomes the speed v ("probe")
or tanh(v/vs); every other column, the torques and the rows stay. The friction choice scores a
form per fold at that fold's velocity scales (:mod:`identify.estimation.friction_choice`):
instead of building the whole observation again (the regressor on every sample, every column
through the parallel filter), the form's columns are evaluated, set to 0 at rest as the fit's rest
policy says, parallel-filtered alone (the filter treats every column alone: the same numbers as in
the whole observation) and put in place of the Coulomb columns on the same rows.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any, Sequence

import numpy as np

import rx90sym

from identify.observation.defaults import DEFAULT_DECIMATE_TO
from identify.observation.friction import friction_columns
from identify.observation.friction_model import coulomb_terms, friction_base, own_terms
from identify.observation.matrix import Observation, filtered_motions, observation_matrix
from identify.observation.processing import FrictionForm, has_policy

__all__ = ["with_friction_form"]

#: Forms whose columns replace the Coulomb column alone (Stribeck adds a column: built whole).
_IN_PLACE = ("probe", "tanh")


def with_friction_form(robot: rx90sym.Robot, recordings: Sequence[Any], obs: Observation, base: Any,
                       form: FrictionForm | str, scales: Sequence[float] | None = None,
                       **options: Any) -> Observation:
    """``obs`` (:func:`identify.observation_matrix` of ``recordings`` with the columns ``base`` and the
    observation ``options``) with the own-joint Coulomb columns of ``form`` ("probe": the filtered
    driver speed; "tanh"; or one form per joint, "coulomb" joints kept) at the velocity ``scales``
    [rad/s, per joint]: the same numbers as ``observation_matrix`` of the form's
    :class:`~identify.observation.friction_model.FrictionBase`, which builds it where the form adds
    columns (Stribeck) or a joint rests "presliding" (its columns FPj)."""
    terms = own_terms(coulomb_terms(robot, base.names))
    form_of = (lambda row: form) if isinstance(form, str) else (lambda row: form[row])
    changed = [t for t in terms if form_of(t.row) != "coulomb"]
    presliding = options.get("min_velocity") is not None and has_policy(options.get("rest"), "presliding")
    if any(form_of(t.row) not in _IN_PLACE for t in changed) or presliding or tuple(obs.names) != tuple(base.names):
        return observation_matrix(robot, recordings, base=friction_base(base, terms, form, scales), **options)
    if not changed:
        return obs

    def regressor(Q: np.ndarray, QD: np.ndarray, QDD: np.ndarray) -> np.ndarray:
        """(S, n, k): each changed term's column in its joint's row, as FrictionBase.regressor_batch fills it."""
        QD = np.asarray(QD, dtype=float)
        out = np.zeros(QD.shape + (len(changed),))
        for k, t in enumerate(changed):
            v = QD @ np.asarray(t.driver)
            out[:, t.row, k] = v if form_of(t.row) == "probe" else friction_columns("tanh", v, scales[t.row])[0][:, 0]
        return out

    names = tuple(t.name for t in changed)   # their rest masks found as in the whole observation
    motions, _, _ = filtered_motions(robot, recordings, obs.cutoffs[0], options.get("decimate_to", DEFAULT_DECIMATE_TO),
                                     options.get("spring", True), regressor, names, options.get("min_velocity"),
                                     options.get("rest", "drop"), options.get("delay", 0.0))
    Phi = np.concatenate([m.Phi for m in motions])
    if Phi.shape[0] != obs.n_samples:
        raise RuntimeError(f"friction form {form!r}: {Phi.shape[0]} samples filtered, the observation has {obs.n_samples}")
    W = obs.W.copy()
    for k, t in enumerate(changed):
        rows = np.flatnonzero(obs.joint == t.row)
        W[rows, t.column] = Phi[obs.samples[rows], t.row, k]
    return replace(obs, W=W)
