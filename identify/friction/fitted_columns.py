"""The friction columns a fit uses, searched on its own rows block by block.

:class:`FrictionHook` gives the fit's passes (:func:`identify.fitting.passes.run_passes`) the friction
columns once the torques are in step: the form chosen per joint by the cross-validation where it is left
open (:mod:`identify.friction.choice`), a smooth form's (tanh, Stribeck, or one per joint) velocity
scales, and the presliding travels (:mod:`identify.friction.travels`). The probe rows (each own Coulomb
column the filtered, decimated driver speed, :class:`~identify.friction.columns.FrictionBase` form
"probe") are made block by block by the fit's own row code (:func:`identify.observation.block_rows.piece`)
and folded into the tables of :mod:`identify.friction.scale_table` (two passes: the coarse grid, then
the fine one); the fit then uses the form's exact columns at the scales found. Memory: the tables, per
joint (c + 37)² doubles, whatever the log's length.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Callable, Sequence

import numpy as np

import rx90sym

from identify.estimation.consistency.errors import SolverError
from identify.friction.columns import friction_base, friction_probe
from identify.friction.scale_search import find_scales
from identify.friction.scale_table import ScaleTable
from identify.friction.scales import as_velocity_scales, smooth_joints, smooth_probe
from identify.observation.block_rows import in_order, piece, plan_windows, windows_in_order
from identify.observation.processing import FrictionForm, Processing, drops_rest, friction_label, has_smooth_friction
from identify.observation.rest import coulomb_terms, presliding_base

__all__ = ["FrictionHook", "probe_feed"]


def _probe_task(robot: rx90sym.Robot, rec: Any, window: Any, plan: Any, processing: Processing,
                left_out: Sequence[int], probe: Any, table: ScaleTable, folds: tuple[float, float, int] | None) -> list[tuple]:
    """One block of probe rows: per (time block, joint) the table's factor, row count and |v| histogram."""
    from identify.selection.folds import time_folds

    m = piece(robot, rec, window, plan, processing, probe.regressor_batch, probe.names, 0, (), left_out).motion
    keep = m.rows(processing.min_velocity is not None and drops_rest(processing.rest))
    ids = np.zeros(m.t.size, dtype=int) if folds is None else time_folds(m.t, *folds)
    out = []
    for b in np.unique(ids):
        for j in range(m.Phi.shape[1]):
            rows = keep[:, j] & (ids == b)
            W = m.Phi[rows, j, :]
            out.append((int(b), j, *table.block_part(j, table.rows_of(j, W, m.Y[rows, j]), W)))
    return out


def probe_feed(robot: rx90sym.Robot, sources: Sequence[Any], plans: Sequence[Any], processing: Processing,
               left_out: Sequence[int], probe: Any, client: Any = None,
               folds: tuple[float, float, int] | None = None) -> Callable[[ScaleTable], None]:
    """``feed(table)``: one pass over the recordings adding every probe row to the table (folds: the time
    span (start, length [s], blocks) of the cross-validation's time blocks; None: one block)."""
    def feed(table: ScaleTable) -> None:
        empty = table.empty()
        shared = client.scatter([robot, probe], broadcast=True, hash=False) if client is not None else (robot, probe)
        tasks = ((shared[0], rec, window, plan, processing, tuple(left_out), shared[1], empty, folds)
                 for plan, window, rec, _ in windows_in_order(sources, plans))
        for parts in in_order(_probe_task, tasks, client, 4 if client is not None else 1):
            for b, j, factor, count, hist in parts:
                table.add_factor(b, j, factor, count, hist)
    return feed


def _columns(robot: rx90sym.Robot, sources: Sequence[Any], plans: Sequence[Any], processing: Processing,
             left_out: Sequence[int], base: Any, client: Any, form: FrictionForm) -> tuple[Any, dict]:
    """(the columns of the smooth ``form`` at the scales found on every row, the fit file's ``model.friction``)."""
    probe, terms = smooth_probe(robot, base, form)
    own, forms = smooth_joints(terms, form)
    # The probe's FPj columns with "presliding", as observation_matrix adds them in memory.
    probe = presliding_base(robot, probe, processing.rest if processing.min_velocity is not None else None)
    feed = probe_feed(robot, sources, plans, processing, left_out, probe, client)
    scales = as_velocity_scales(find_scales(feed, robot.n, len(probe.names), own, forms)[0], form, robot.n)
    unsearched = [j for j in forms if not np.isfinite(scales.scales[j])]  # no rows: a torque left out
    if unsearched:  # those joints keep Coulomb's sign column
        form = tuple("coulomb" if j in unsearched else forms.get(j, "coulomb") for j in range(robot.n))
        scales = replace(scales, form=form)
    if not scales.converged:  # a failed search is reported, never fitted with
        raise SolverError(f"fit: the velocity-scale search of friction form {friction_label(form)!r} did not "
                          f"converge; use friction 'coulomb'", status="not_converged", solver="grid")
    columns = friction_base(base, coulomb_terms(robot, probe.base.names), form, scales.scales)
    return columns, {"form": form if isinstance(form, str) else list(form), **scales.to_json()}


def _travels(robot: rx90sym.Robot, sources: Sequence[Any], plans: Sequence[Any], processing: Processing,
             left_out: Sequence[int], base: Any, client: Any) -> tuple[Any, dict]:
    """(``base`` with the presliding travels chosen per joint, their record): one pass of the
    :func:`~identify.friction.travels.travel_columns` rows into per-joint factors (the fit's own pass,
    :func:`identify.estimation.joint_factors.joint_factors`)."""
    from identify.estimation.joint_factors import joint_factors
    from identify.friction.travels import travel_columns, travels_of
    from identify.observation.rest import defaulted_travels

    columns = travel_columns(robot, base)
    factors = joint_factors(robot, sources, plans, processing, columns, left_out=left_out, client=client)[0]
    found = travels_of(robot, factors.R, factors.rows, columns.names)
    terms = coulomb_terms(robot, friction_probe(robot, base)[0].names)
    return friction_base(base, terms, presliding=True, travels=defaulted_travels(found.travels)), found.to_json()


@dataclass(eq=False)
class FrictionHook:
    """The ``friction`` argument of :func:`~identify.fitting.passes.run_passes`: the friction columns of a
    fit read block by block, as :func:`identify.friction.columns.friction_base` makes them.
    form: the form given (one, or one per joint); choose: the form chosen per joint by the cross-validation
    block by block instead (:func:`identify.friction.choice.choose_friction` on the fit's
    :class:`~identify.friction.folds.FoldRows`, the processing choice's time blocks);
    then a smooth form's velocity scales, and with the rest policy "presliding" the travels.
    ``choice``: the :class:`FrictionChoice` once called (None: the form was given)."""

    form: FrictionForm = "coulomb"
    choose: bool = False
    choice: Any = None

    def __call__(self, robot: rx90sym.Robot, sources: Sequence[Any], scans: Sequence[Any], processing: Processing,
                 block: int, left_out: Sequence[int], base: Any, client: Any,
                 choose: bool = True) -> tuple[Any, dict | None]:
        """(the columns, the fit file's ``model.friction``) of the rows of ``sources`` (``scans``: their first
        pass) made with ``processing`` (its cut-off and delay chosen) in blocks of ``block`` samples, the
        joints ``left_out`` out of W; ``choose`` False: the form given, not chosen (the processing's choice
        fell back on the fixed defaults)."""
        from identify.observation.processing import has_policy

        plans = [plan_windows(s, processing, block)[0] for s in scans]
        form = self.form
        if self.choose and choose:
            from identify.friction.choice import choose_friction
            from identify.friction.folds import FoldRows

            rows = FoldRows.of(robot, sources, scans, processing, block, left_out, client)
            self.choice = choose_friction(robot, rows, base, robot.n * sum(s.samples for s in scans))
            form = self.choice.chosen
        record = None
        if has_smooth_friction(form):
            base, record = _columns(robot, sources, plans, processing, left_out, base, client, form)
        if processing.min_velocity is not None and has_policy(processing.rest, "presliding"):
            base, travels = _travels(robot, sources, plans, processing, left_out, base, client)
            record = {**(record or {"form": form if isinstance(form, str) else list(form)}), **travels}
        return base, record
