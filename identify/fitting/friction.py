"""The friction part of a fit: the form chosen per joint and the columns it needs (velocity scales,
presliding travels) by separable least squares."""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

import rx90sym

from identify.estimation.consistency.errors import SolverError
from identify.observation.friction import PRESLIDING_TRAVEL
from identify.observation.friction_model import friction_base
from identify.observation.matrix import Observation, coulomb_terms
from identify.observation.processing import FrictionForm, Processing, friction_label, has_policy, has_smooth_friction

__all__ = ["chosen_friction", "defaulted_travels", "friction_columns"]


def chosen_friction(robot: rx90sym.Robot, recordings: Sequence[Any], base: Any, p: Processing, method: str,
                     choice: Any, options: dict[str, Any]) -> tuple[FrictionForm, dict | None]:
    """(the friction form, one or one per joint; the processing choice's record): chosen per joint by the
    cross-validation (identify.estimation.friction_choice) where it is left open and the processing
    cross-validated (not for the consistent method: a URDF holds Coulomb + viscous), else as asked."""
    if choice is None:
        return p.friction_form, None
    if p.friction is not None or method == "consistent":
        return p.friction_form, choice.to_dict()
    from identify.estimation.friction_choice import choose_friction

    forms = choose_friction(robot, recordings, base, options)
    record = choice.to_dict()
    # Its table printed after the processing's.
    return forms.chosen, dict(record, friction=forms.to_dict(), table=record["table"] + "\n" + forms.table())


def friction_columns(robot: rx90sym.Robot, recordings: Sequence[Any], base: Any, form: FrictionForm,
                   observation: Observation | None, options: dict[str, Any]) -> tuple[Any, dict | None]:
    """(columns, the fit file's ``model.friction``) of the friction ``form`` (one, or one per joint) and the
    rest policy in ``options``: the smooth joints' velocity scales and the presliding travel per joint by
    separable least squares (identify.estimation.separable); ``base`` and None for Coulomb, no presliding."""
    presliding = has_policy(options["rest"], "presliding") and options["min_velocity"] is not None
    smooth = has_smooth_friction(form)
    if not smooth and not presliding or observation is not None:
        if observation is not None and smooth:
            raise ValueError(f"fit: friction form {form!r} searches its velocity scales on the recordings: "
                             f"give recordings, not an observation matrix")
        return base, None
    from identify.estimation.separable import presliding_travels, velocity_scales

    record: dict[str, Any] = {"form": form if isinstance(form, str) else list(form)}
    terms = coulomb_terms(robot, base.names)
    if smooth:
        scales = velocity_scales(robot, recordings, base, form, **options)
        if not scales.converged:  # a failed search is reported, never fitted with
            raise SolverError(f"fit: the velocity-scale search of friction form {friction_label(form)!r} did not converge "
                              f"; use friction 'coulomb'", status="not_converged", solver="grid")
        base = friction_base(base, terms, form, scales.scales)
        record.update(scales.to_json())
    if presliding:
        travels = presliding_travels(robot, recordings, base, **options)
        base = friction_base(base, terms, presliding=True, travels=defaulted_travels(travels.travels))
        record.update(travels.to_json())
    return base, record


def defaulted_travels(travels: Sequence[float | None]) -> list[float]:
    """Travels [rad] with the default where none was chosen (the joint never rests: no FPj column)."""
    return [PRESLIDING_TRAVEL if v is None or not np.isfinite(v) else float(v) for v in travels]
