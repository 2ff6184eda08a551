"""The friction choice's passes over the rows, in memory or block by block: one implementation.

The friction choice (:mod:`identify.friction.choice`) reads the fit's rows in passes, each
pass a sequence of filtered motions (:class:`~identify.observation.matrix.FilteredMotion`) with the
time block of each row: :class:`MemoryRows` (recordings in memory: one motion per segment,
:func:`~identify.observation.matrix.filtered_motions`) or :class:`StreamRows` (a log read block by
block: one motion per block, :func:`identify.observation.stream.piece`). Everything else is computed
from per-(time block, joint) triangular factors, so it is the same whatever the blocks:

- :func:`fold_scales_of`: per held-back block the velocity scales searched on the other blocks
  (:mod:`identify.friction.scale_search`, two passes of the probe columns);
- :func:`held_back_errors`: the form's exact (parallel-filtered) columns at each fold's scales, all folds
  in one pass (:class:`FoldColumns`: a column FSj_f per fold f, resting like FSj), the fold fits
  (eq. 11's weights, :func:`~identify.selection.folds.fold_wls`) and the held-back errors from
  the factors.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any, Iterator, Sequence

import numpy as np

import rx90sym

from identify.estimation.compression import _qr_r
from identify.friction.scale_search import find_scales
from identify.friction.scales import VelocityScales, as_velocity_scales, smooth_joints
from identify.selection.folds import fold_wls, time_blocks, time_folds
from identify.friction.forms import friction_columns
from identify.observation.rest import STRIBECK_PREFIX
from identify.observation.processing import FrictionForm, drops_rest

__all__ = ["FoldColumns", "MemoryRows", "StreamRows", "fold_scales_of", "held_back_errors"]


class MemoryRows:
    """The rows of recordings in memory with the fit's observation ``options`` (cutoff, decimate_to,
    min_velocity, rest, spring, delay), cut into ``blocks`` time blocks; the last pass's motions kept
    (the probe's two passes filter once)."""

    def __init__(self, robot: rx90sym.Robot, recordings: Sequence[Any], options: dict[str, Any], blocks: int) -> None:
        from identify.observation.matrix import automatic_cutoff

        self.robot, self.recordings, self.blocks = robot, list(recordings), blocks
        self.options = dict(options)
        if self.options.get("cutoff") is None:
            self.options["cutoff"] = automatic_cutoff(self.recordings, self.options.get("decimate_to"))
        self.cutoff, self.rest = float(self.options["cutoff"]), self.options.get("rest", "drop")
        self.drop = self.options.get("min_velocity") is not None and drops_rest(self.rest)
        # The rest policy that adds presliding magnitudes FPj (as observation_matrix's columns): None without a threshold.
        self.presliding_rest = self.rest if self.options.get("min_velocity") is not None else None
        self._last: tuple[Any, list] | None = None

    def motions(self, columns: Any) -> Iterator[tuple[Any, np.ndarray]]:
        from identify.observation.defaults import DEFAULT_DECIMATE_TO
        from identify.observation.matrix import filtered_motions

        if self._last is None or self._last[0] is not columns:   # the same columns object: the same motions
            o = self.options
            motions = filtered_motions(self.robot, self.recordings, self.cutoff, o.get("decimate_to", DEFAULT_DECIMATE_TO),
                                       o.get("spring", True), columns.regressor_batch, columns.names,
                                       o.get("min_velocity"), self.rest, o.get("delay", 0.0))[0]
            self._last = (columns, motions)
        motions = self._last[1]
        yield from zip(motions, time_blocks([m.t for m in motions], self.blocks))


@dataclass(frozen=True, eq=False)
class StreamRows:
    """The rows of a log read block by block (:mod:`identify.observation.stream`): sources, plans (per
    recording), cut-off [Hz], settings, the time span (start, length [s], blocks) of the time blocks,
    a Dask client (None: here)."""

    robot: rx90sym.Robot
    sources: Sequence[Any]
    plans: Sequence[Any]
    cutoff: float
    settings: Any
    span: tuple[float, float, int]
    client: Any = None

    @property
    def blocks(self) -> int:
        return self.span[2]

    @property
    def rest(self) -> Any:
        return self.settings.rest

    @property
    def presliding_rest(self) -> Any:
        return self.settings.rest if self.settings.min_velocity is not None else None

    @property
    def drop(self) -> bool:
        return self.settings.min_velocity is not None and drops_rest(self.settings.rest)

    def motions(self, columns: Any) -> Iterator[tuple[Any, np.ndarray]]:
        from identify.observation.stream import in_order, piece, windows_in_order

        tasks = ((self.robot, rec, window, plan, self.cutoff, self.settings, columns.regressor_batch, columns.names, 0)
                 for plan, window, rec, _ in windows_in_order(self.sources, self.plans))
        for p in in_order(piece, tasks, self.client, 4 if self.client is not None else 1):
            yield p.motion, time_folds(p.motion.t, *self.span)


def fold_scales_of(rows: Any, probe: Any, terms: Sequence[Any], form: FrictionForm,
                   n: int) -> list[VelocityScales]:
    """Per held-back time block the scales of ``form`` searched on the other blocks only (probe columns
    ``probe``: own Coulomb columns holding the driver speed; ``terms`` its own Coulomb terms)."""
    from identify.observation.rest import presliding_base

    own, forms = smooth_joints(terms, form)
    blocks = rows.blocks
    probe = presliding_base(rows.robot, probe, rows.presliding_rest)   # FPj columns with "presliding", as in the fit

    def feed(table: Any) -> None:
        for m, ids in rows.motions(probe):
            keep = m.rows(rows.drop)
            for j in range(n):
                k = keep[:, j]
                table.add(j, m.Phi[k, j, :], m.Y[k, j], ids[k])

    sets = [[x for x in range(blocks) if x != b] for b in range(blocks)]
    return [as_velocity_scales(x, form, n) for x in find_scales(feed, n, len(probe.names), own, forms, sets, blocks,
                                                                   std=False)]


@dataclass(frozen=True, eq=False)
class FoldColumns:
    """``inner``'s columns and, per fold f and joint j of a smooth form, FSj_f (and FSTj_f for
    Stribeck): the form's columns at fold f's scale ``scales[f][j]`` [rad/s] (a column per fold, all
    filtered in one pass; the rest policy zeroes them like FSj)."""

    inner: Any
    terms: tuple[Any, ...]
    form: FrictionForm
    scales: tuple[tuple[float, ...], ...]

    def form_of(self, j: int) -> str:
        return self.form if isinstance(self.form, str) else self.form[j]

    @cached_property
    def smooth(self) -> tuple[Any, ...]:
        return tuple(t for t in self.terms if self.form_of(t.row) in ("tanh", "stribeck"))

    @cached_property
    def names(self) -> tuple[str, ...]:
        extra = [f"FS{t.row + 1}_{f}" for f in range(len(self.scales)) for t in self.smooth]
        extra += [f"{STRIBECK_PREFIX}{t.row + 1}_{f}" for f in range(len(self.scales)) for t in self.smooth
                  if self.form_of(t.row) == "stribeck"]
        return tuple(self.inner.names) + tuple(extra)

    def regressor_batch(self, Q: Any, QD: Any, QDD: Any) -> np.ndarray:
        Phi = self.inner.regressor_batch(Q, QD, QDD)
        out = np.zeros(Phi.shape[:2] + (len(self.names),))
        out[:, :, :Phi.shape[2]] = Phi
        QD = np.asarray(QD, dtype=float)
        where = {name: k for k, name in enumerate(self.names)}
        for f, scales in enumerate(self.scales):
            for t in self.smooth:
                if not np.isfinite(scales[t.row]):  # no rows to search it on (a torque left out): nothing to fit
                    continue
                cols, _ = friction_columns(self.form_of(t.row), QD @ np.asarray(t.driver), scales[t.row])
                out[:, t.row, where[f"FS{t.row + 1}_{f}"]] = cols[:, 0]
                if cols.shape[1] > 1:
                    out[:, t.row, where[f"{STRIBECK_PREFIX}{t.row + 1}_{f}"]] = cols[:, 1]
        return out


def held_back_errors(rows: Any, inner: Any, terms: Sequence[Any], form: FrictionForm,
                     scales: Sequence[Sequence[float]] | None, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(squared held-back errors, squared held-back torques) (blocks, n) of ``form`` with its exact
    columns at each fold's ``scales`` (None: the Coulomb form, ``inner``'s own columns): per fold the
    WLS on the other blocks (eq. 11's weights), the held-back block predicted; one pass."""
    from identify.observation.rest import presliding_base

    blocks = rows.blocks
    inner = presliding_base(rows.robot, inner, rows.presliding_rest)   # FPj columns with "presliding", as in the fit
    columns = inner if scales is None else FoldColumns(inner, tuple(terms), form, tuple(tuple(s) for s in scales))
    R: dict[tuple[int, int], np.ndarray] = {}
    count: dict[tuple[int, int], int] = {}
    for m, ids in rows.motions(columns):
        keep = m.rows(rows.drop)
        for b in np.unique(ids):
            for j in range(n):
                k = keep[:, j] & (ids == b)
                if not k.any():
                    continue
                part = _qr_r(np.column_stack([m.Phi[k, j, :], m.Y[k, j]]))
                R[(b, j)] = part if (b, j) not in R else _qr_r(np.vstack([R[(b, j)], part]))
                count[(b, j)] = count.get((b, j), 0) + int(k.sum())
    c = len(inner.names)
    stribeck = [t.row for t in (columns.smooth if scales is not None else ()) if columns.form_of(t.row) == "stribeck"]
    C = c + len(stribeck)
    names = list(columns.names)

    def placed(Rbj: np.ndarray, j: int, fold: int) -> np.ndarray:
        """A factor's columns for fold ``fold``'s fit: FSj ← FSj_fold, FSTj_fold appended (C + 1 columns)."""
        out = np.zeros((Rbj.shape[0], C + 1))
        out[:, :c] = Rbj[:, :c]
        out[:, C] = Rbj[:, -1]
        if scales is not None:
            for t in columns.smooth:
                if t.row == j:
                    out[:, t.column] = Rbj[:, names.index(f"FS{j + 1}_{fold}")]
                    if j in stribeck:
                        out[:, c + stribeck.index(j)] = Rbj[:, names.index(f"{STRIBECK_PREFIX}{j + 1}_{fold}")]
        return out

    err2, ref2 = np.zeros((blocks, n)), np.zeros((blocks, n))
    for b in range(blocks):
        factors = {key: (placed(Rk, key[1], b), count[key]) for key, Rk in R.items()}
        beta = fold_wls(factors, b, n)  # eq. 11's per-joint weights, as the processing's folds
        if beta is None:
            raise ValueError(f"friction choice: too few rows to fit without block {b + 1}")
        x = np.r_[beta, -1.0]
        for j in range(n):
            if (b, j) in factors:
                M = factors[(b, j)][0]
                err2[b, j], ref2[b, j] = float(np.sum((M @ x) ** 2)), float(np.sum(M[:, -1] ** 2))
    return err2, ref2
