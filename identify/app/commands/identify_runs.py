"""The fit of ``rx90 identify``: whole recordings in memory, or long logs streamed block by block.

Logs no longer than ``--block`` samples are read whole (the figures of every earlier release);
a longer log, or ``--scheduler``, goes through :func:`identify.stream_fit.fit_streamed`, whose
memory is bounded by the block (docs/long-logs.md). Both give a :class:`FitRun` for the printing.
"""
from __future__ import annotations

import argparse
import os
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any, Callable

import numpy as np

import rx90sym
from identify.estimation.bootstrap import segment_bootstrap_std
from identify.io.blocks import count_rows
from identify.real_fit import fit_recordings
from identify.stream_fit import BootstrapSpec, fit_streamed, predict_streamed
from identify.validation import predict

from ..common import progress

#: Segment-bootstrap block length, s, and number of draws.
BOOTSTRAP_BLOCK_S = 0.5
BOOTSTRAP_DRAWS = 200


@dataclass(frozen=True, eq=False)
class FitRun:
    """What ``rx90 identify`` prints and writes: result, filtering, delay, bootstrap, and how to
    predict (``predict(rec_or_path, **filtering)``) and read the angle range (``spring_recs``)."""

    result: Any
    cutoff: float
    rate: float
    notes: tuple[str, ...]
    summary: str
    delay: float
    estimate: Any
    boot: np.ndarray
    boot_block_s: float
    spring_recs: list
    recordings: list          # in memory (for the report's trajectory figure); [] when streamed
    predict: Callable[..., Any]
    streamed: bool


def streamed(paths: list[str], block: int, scheduler: str | None) -> bool:
    """Whether the recordings go through the block-wise pipeline: one is longer than ``block`` samples, or Dask."""
    if scheduler is not None:
        return True
    return any(p.lower().endswith(".csv") and count_rows(p) > block for p in paths)


def fit_whole(args: argparse.Namespace, robot: rx90sym.Robot, recs: list, base: Any, spring: bool,
              decimate_to: float | None, min_velocity: float | None) -> FitRun:
    """Today's path: the recordings in memory, W whole."""
    progress(f"identifying ({args.method}) on {sum(len(r.t) for r in recs)} samples")
    fit = fit_recordings(robot, recs, method=args.method, base=base, cutoff=args.cutoff,
                         decimate_to=decimate_to, min_velocity=min_velocity, rest=args.rest,
                         delay=args.delay, spring=spring, estimate=True)
    obs, res = fit.observation, fit.result
    block = max(1, int(round(BOOTSTRAP_BLOCK_S * obs.rate)))
    boot = segment_bootstrap_std(obs.W, obs.Y, obs.joint, obs.samples, res.weights, block,
                                 BOOTSTRAP_DRAWS, args.bootstrap_seed)
    return FitRun(res, obs.cutoffs[0], obs.rate, obs.notes, obs.summary(), fit.delay, fit.delay_estimate, boot,
                  block / obs.rate, recs, recs, lambda rec, **kw: predict(robot, res, rec, base=base, **kw), False)


def fit_long(args: argparse.Namespace, robot: rx90sym.Robot, gains: Any, base: Any, spring: bool,
             decimate_to: float | None, min_velocity: float | None) -> FitRun:
    """Long logs: block by block (and on Dask with ``--scheduler``)."""
    progress(f"identifying ({args.method}) block by block ({args.block} samples per block"
             + (f", Dask scheduler {args.scheduler}" if args.scheduler else "") + ")")
    options = dict(method=args.method, base=base, cutoff=args.cutoff, decimate_to=decimate_to,
                   min_velocity=min_velocity, rest=args.rest, delay=args.delay, spring=spring, estimate=True,
                   block=args.block, bootstrap=BootstrapSpec(BOOTSTRAP_BLOCK_S, BOOTSTRAP_DRAWS, args.bootstrap_seed),
                   convention=args.convention, gains=gains)
    if args.scheduler is None:
        fit = fit_streamed(robot, args.recordings, **options)
    else:
        from excitation.multistart import dask_client

        local = args.scheduler == "local"
        with dask_client(workers=os.cpu_count() or 2 if local else None,
                         scheduler=None if local else args.scheduler) as client:
            fit = fit_streamed(robot, args.recordings, client=client, **options)
    summary = (f"{fit.result.rows} equations, {len(fit.result.names)} parameters, {fit.samples} samples after "
               f"decimation to {fit.rate:g} Hz, {fit.blocks} blocks of at most {args.block} samples")
    lo_hi = SimpleNamespace(q=fit.q_range)
    res = fit.result

    def predict_long(rec: Any, **kw: Any) -> Any:
        return predict_streamed(robot, res, rec, base=base, block=args.block, convention=args.convention,
                                gains=gains, **kw)

    return FitRun(res, fit.cutoff, fit.rate, fit.notes, summary, fit.delay, fit.delay_estimate, fit.bootstrap_std,
                  fit.bootstrap_block / fit.rate, [lo_hi], [], predict_long, True)


def block_option(text: str) -> int:
    """``--block``: a whole number of samples, at least 1000."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--block takes a whole number of samples, got {text!r}") from None
    if value < 1000:
        raise argparse.ArgumentTypeError(f"--block must be at least 1000 samples, got {value}")
    return value

