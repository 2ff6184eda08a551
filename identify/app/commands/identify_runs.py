"""The fit of ``rx90 identify``: the recordings read, filtered and fitted block by block, here or on Dask.

Every log goes through ``identify.fit(..., block=..., client=...)``, whose memory is bounded by the
block (docs/long-logs.md); a log within one block is one block.
"""
from __future__ import annotations

import argparse
import os
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # for annotations only: the method is imported when a fit runs
    import rx90sym
    from identify.fitting.fit_result import Fit
    from identify.observation.processing import Processing

from ..common import progress


def fit_recordings(args: argparse.Namespace, robot: rx90sym.Robot, processing: Processing, base: Any, gains: Any,
                   **model_options: Any) -> Fit:
    """The fit of ``args.recordings`` block by block (on Dask with ``--scheduler``); ``model_options``:
    those of the identified model (its prior, the prior's weight, the divergence)."""
    from identify.fitting.fit import fit

    progress(f"identifying ({args.method}) on {len(args.recordings)} recording(s) block by block ({args.block} "
             f"samples per block"
             + (f", Dask scheduler {args.scheduler}" if args.scheduler else "") + ")"
             + ("; the processing chosen first by cross-validation, one pass over the logs per candidate"
                if processing.cross_validates else ""))
    options = dict(base=base, gains=gains, convention=args.convention, spring_source=args.spring,
                   block=args.block, bootstrap_seed=args.bootstrap_seed, **model_options)
    if args.scheduler is None:
        return fit(robot, args.recordings, processing, args.method, **options)
    from excitation.multistart import dask_client

    local = args.scheduler == "local"
    with dask_client(workers=(os.cpu_count() or 2) if local else None,
                     scheduler=None if local else args.scheduler) as client:
        return fit(robot, args.recordings, processing, args.method, client=client, **options)


def add_block_option(sp: argparse.ArgumentParser) -> None:
    """``--block`` of the commands that read runs in blocks (gains, payload)."""
    from identify.io.defaults import DEFAULT_BLOCK

    sp.add_argument("--block", type=block_option, default=DEFAULT_BLOCK,
                    help=f"raw samples read, filtered and fitted at a time (default {DEFAULT_BLOCK}; memory grows "
                         f"with it, not with the logs)")


def block_option(text: str, unit: str = "samples") -> int:
    """``--block``: a whole number of samples (``unit``: lines, for convert), at least 1000."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--block takes a whole number of {unit}, got {text!r}") from None
    if value < 1000:
        raise argparse.ArgumentTypeError(f"--block must be at least 1000 {unit}, got {value}")
    return value


def rollout_option(sp: argparse.ArgumentParser, what: str) -> None:
    """``--rollout L[,L2]``: window lengths [s] of the rollout validation (identify.rollout)."""
    from identify.rollout.defaults import MAX_STEP_S

    def lengths(text: str) -> tuple[float, ...]:
        from identify.rollout.defaults import window_lengths

        try:
            return window_lengths(text)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    sp.add_argument("--rollout", metavar="L[,L2]", type=lengths,
                    help=f"also roll the fit's model (the MJCF of rx90 export --mjcf) out in MuJoCo over {what} in "
                         f"windows of L seconds while the arm moves, from the recorded state under the recorded "
                         f"torques (steps of at most {1e3 * MAX_STEP_S:g} ms); per joint the RMS end-position and "
                         f"end-velocity errors beside the constant-velocity guess and the description's bodies "
                         f"(docs/rollout.md)")
