"""``rx90 predict``: torques of a recording predicted with an identification, with its own filtering.

The identification JSON (``rx90 identify --json``) records its model (robot file and hash, friction
form, offsets, gains, rest threshold, cut-off, decimation, delay): the prediction reuses all of it,
so a held-out file is processed exactly like the fitted one.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np

import rx90sym
from rx90sym.files import atomic_write, write_json
from identify import IdentificationResult, predict
from identify.fit_model import FitModel
from identify.io.gains import DriveGains

from ..common import announce_robot, check_output, progress
from .identify_cmd import read_recordings


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
    sp.add_argument("--json", help="prediction errors as JSON")


def load_identification(path: str) -> tuple[IdentificationResult, FitModel]:
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as exc:
        raise ValueError(f"{path}: cannot read the identification ({exc.strerror})") from None
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path}: not valid JSON ({exc})") from None
    if not isinstance(data, dict) or "model" not in data:
        raise ValueError(f"{path}: no 'model' record (write it with rx90 identify --json)")
    try:
        return IdentificationResult.from_dict(data), FitModel.from_dict(data["model"], path)
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}".replace(f"{path}: {path}: ", f"{path}: ")) from None


def robot_of(model: FitModel, spec: str | None) -> rx90sym.Robot:
    """The robot the identification used (``spec`` overrides its file), with its friction form and offsets."""
    source = spec or (model.robot_file if model.robot_file and Path(model.robot_file).is_file() else model.robot)
    if model.spring in ("identify", "identify-k"):
        raise ValueError(f"the identification used --spring {model.spring}: predict cannot rebuild an "
                         "identified spring yet; validate with rx90 identify --validate instead")
    tip = model.tip if str(source).lower().endswith(".urdf") else None
    robot = rx90sym.load_robot(source, offsets=model.offsets, tip=tip)
    if model.coulomb_sign is not None and robot.coupling is not None:
        robot = robot.with_options(coupling=rx90sym.Coupling(robot.coupling.joints, model.coulomb_sign))
    if model.spring == "none":
        robot = robot.with_options(spring=None)
    elif model.spring != "default":
        from rx90sym.spring import read_spring_table

        joint = robot.spring.joint if robot.spring is not None else 1
        robot = robot.with_options(spring=rx90sym.Spring(joint=joint, table=read_spring_table(model.spring)))
    return robot


def gains_of(model: FitModel) -> DriveGains | None:
    if model.gains is None:
        return None
    g = model.gains
    std = None if g.get("std") is None else [np.nan if s is None else s for s in g["std"]]
    return DriveGains(np.asarray(g["gains"], dtype=float), side=str(g.get("side", "joint")),
                      current_offsets=g.get("current_offsets"), std=std, robot=str(g.get("robot", "")),
                      source="identification JSON")


def write_prediction(path: str, val: Any) -> None:
    n = val.measured.shape[1]
    header = ",".join(["t"] + [f"tau{j}" for j in range(1, n + 1)] + [f"pred{j}" for j in range(1, n + 1)]
                      + [f"moving{j}" for j in range(1, n + 1)])
    table = np.column_stack([val.t, val.measured, val.predicted, val.moving.astype(float)])
    atomic_write(path, lambda fh: (fh.write(header + "\n"),
                                   np.savetxt(fh, table, delimiter=",", fmt="%.17g")))


def run(args: argparse.Namespace) -> int:
    for out in (args.out, args.json):
        check_output(out)
    result, model = load_identification(args.identification)
    robot = robot_of(model, args.robot)
    # FS+ / FS- columns in the result: the fit used asymmetric Coulomb friction on those joints.
    asymmetric = tuple(j for j in range(robot.n) if f"FSP{j + 1}" in result.names)
    if asymmetric != tuple(robot.asymmetric_coulomb):
        robot = robot.with_options(asymmetric_coulomb=asymmetric)
    announce_robot(robot, "from --robot" if args.robot else "recorded by the identification")
    warning = model.check_robot(robot)
    if warning:
        progress(f"warning: {warning}")
    rec = read_recordings([args.recording], robot, args.convention or model.convention, gains_of(model))[0]
    val = predict(robot, result, rec, **model.filtering())
    print(val.table())
    if args.out:
        write_prediction(args.out, val)
    if args.json:
        write_json(args.json, {"identification": str(args.identification), "robot_warning": warning,
                               **val.to_dict()})
    return 0
