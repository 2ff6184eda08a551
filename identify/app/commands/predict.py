"""``rx90 predict``: torques of a recording predicted with an identification, with its own filtering.

The identification JSON (``rx90 identify --json``) records its model (robot file and hash, friction
form, offsets, gains, rest threshold, cut-off, decimation, delay): the prediction reuses all of it,
so a held-out file is processed exactly like the fitted one.
"""
from __future__ import annotations

import argparse
from typing import Any

from identify.io.defaults import DEFAULT_BLOCK

from ..common import announce_robot, check_output, progress
from .identify_runs import block_option, rollout_option


def register(sub: Any) -> None:
    sp = sub.add_parser("predict", help="predict the torques of a recording with an identification",
                        description="predict the torques of a recording with the parameters and the "
                                    "processing (filtering, rest threshold, delay, gains) of an identification")
    sp.set_defaults(func=run)
    sp.add_argument("recording", help="recording CSV")
    sp.add_argument("--identification", required=True, help="JSON written by rx90 identify --json")
    sp.add_argument("--robot", help="robot name or file (default: the one the identification records)")
    sp.add_argument("--convention", choices=("controller", "model", "staubli", "khalil"), default=None,
                    help="joint angles of the file (default: the identification's, else the file's header)")
    sp.add_argument("--out", help="CSV: t, measured tau1..n, predicted pred1..n, moving1..n (1/0)")
    sp.add_argument("--json", help="prediction errors as JSON (with --rollout: its figures under 'rollout')")
    sp.add_argument("--report", metavar="FILE.html", help="self-contained HTML report: the held-out errors and, "
                                                          "with --rollout, a few windows and the rollout's table")
    rollout_option(sp, "the recording")
    sp.add_argument("--block", type=block_option, default=DEFAULT_BLOCK,
                    help=f"samples read, filtered and predicted at a time, at least 1000 (default {DEFAULT_BLOCK}; "
                         f"the fit's figures do not depend on it, the plain baseline's sign(q̇) at rest is the sign "
                         f"of round-off)")


def write_prediction(path: str, val: Any) -> None:
    import numpy as np

    from rx90sym.files import atomic_write

    n = val.measured.shape[1]
    header = ",".join(["t"] + [f"tau{j}" for j in range(1, n + 1)] + [f"pred{j}" for j in range(1, n + 1)]
                      + [f"moving{j}" for j in range(1, n + 1)])
    table = np.column_stack([val.t, val.measured, val.predicted, val.moving.astype(float)])
    atomic_write(path, lambda fh: (fh.write(header + "\n"),
                                   np.savetxt(fh, table, delimiter=",", fmt="%.17g")))


def run(args: argparse.Namespace) -> int:
    from rx90sym.files import write_json
    from identify.fitting.fit_result import load_fit

    for out in (args.out, args.json, args.report):
        check_output(out)
    f = load_fit(args.identification, args.robot)
    announce_robot(f.robot, "from --robot" if args.robot else "recorded by the identification")
    warning = f.model.check_robot(f.robot)
    if warning:
        progress(f"warning: {warning}")
    # Block by block, any length; with --rollout the fit's model in MuJoCo too (every figure before any output).
    val = f.predict(args.recording, block=args.block, convention=args.convention, rollout=args.rollout)
    if val.still_message():
        progress(f"warning: {val.still_message()}")
    print(val.table())
    record = {"identification": str(args.identification), "robot_warning": warning, **val.to_dict()}
    if args.out:
        write_prediction(args.out, val)
    if args.json:
        write_json(args.json, record)
    if args.report:
        from ..report.rollout_page import write_predict_report

        write_predict_report(args.report, record, val)
    return 0
