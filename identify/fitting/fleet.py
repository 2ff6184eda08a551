"""A fleet: the logs of many robots fitted in one call, one fit per robot and a table of them.

Each robot's logs go through :func:`identify.fit` block by block (memory bounded by the block,
docs/long-logs.md); with a Dask ``client`` the blocks of every robot run on its workers.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import rx90sym
from rx90sym.threads import one_blas_thread

from identify.fitting.fit import fit
from identify.fitting.fit_result import Fit
from identify.observation.processing import Processing
from identify.io.blocks import DEFAULT_BLOCK

__all__ = ["FleetFit", "fit_fleet"]


@dataclass(frozen=True, eq=False)
class FleetFit:
    """fits: robot label -> its :class:`identify.Fit`; seconds: label -> wall time of its fit [s]."""

    fits: dict[str, Fit]
    seconds: dict[str, float]

    def table(self) -> str:
        """One line per robot: parameters, equations, σρ (eq. 12), cond(W), residual RMS per joint [N·m]."""
        lines = [f"{'robot':<16} {'params':>6} {'equations':>10} {'sigma_rho':>9} {'cond':>10} {'time s':>7}  "
                 f"residual RMS per joint [N m]"]
        for label, f in self.fits.items():
            r = f.result
            rms = " ".join(f"{v:.3g}" for v in r.residual_rms)
            lines.append(f"{label:<16} {len(r.names):>6} {r.rows:>10} {r.sigma_rho:>9.4g} {r.cond:>10.4g} "
                         f"{self.seconds[label]:>7.1f}  {rms}")
        return "\n".join(lines)


@one_blas_thread()
def fit_fleet(fleet: Mapping[str, tuple[rx90sym.Robot, Sequence[Any]]], processing: Processing | None = None,
              method: str = "wls", *, block: int = DEFAULT_BLOCK, client: Any = None, **options: Any) -> FleetFit:
    """Fit every robot of ``fleet`` (label -> (robot, its recordings or CSV paths)) on its own logs.

    processing, method and ``options`` (base, gains, convention, ...) go to :func:`identify.fit` for
    every robot, with ``block`` samples per block; ``client`` spreads every robot's blocks over a
    Dask cluster.
    BLAS on one thread inside the call, the caller's count back after it (rx90sym.threads).
    """
    if not fleet:
        raise ValueError("fit_fleet: no robot given")
    fits, seconds = {}, {}
    for label, (robot, recordings) in fleet.items():
        if not recordings:
            raise ValueError(f"fit_fleet: robot {label!r} has no recordings")
        start = time.perf_counter()
        fits[label] = fit(robot, list(recordings), processing, method, block=block, client=client, **options)
        seconds[label] = time.perf_counter() - start
    return FleetFit(fits, seconds)
