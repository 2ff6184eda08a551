"""``rx90 export``: the one command for artefacts made from a JSON.

- a fit (``rx90 identify --json ID.json``: its identified model) -> ``--urdf`` and/or
  ``--mjcf`` (with ``--payload PAYLOAD.json``: the payload as a body on the flange);
- a payload (``rx90 payload --json PAYLOAD.json``) -> ``--ur`` (URScript ``set_target_payload``)
  and/or ``--franka`` (libfranka's ``setLoad`` arguments as JSON).

Every output is checked before anything is written: a refused link or payload writes nothing.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from ..common import UsageError, check_output, progress


def register(sub: Any) -> None:
    sp = sub.add_parser("export", help="URDF / MJCF from a consistent fit, controller payloads from a payload JSON",
                        description="make the artefacts a user needs from a JSON: a consistent fit -> URDF, "
                                    "MJCF; a payload -> UR's set_target_payload, Franka's load")
    sp.set_defaults(func=run)
    sp.add_argument("input", help="ID.json (rx90 identify --json: its identified model) or PAYLOAD.json "
                                  "(rx90 payload --json)")
    sp.add_argument("--robot", help="with ID.json: the robot (default: the one the fit records; another "
                                    "robot is refused)")
    sp.add_argument("--urdf", metavar="OUT.urdf", help="URDF (and OUT.actuation.json beside it)")
    sp.add_argument("--mjcf", metavar="OUT.xml", help="MJCF for MuJoCo (and OUT.mjcf.actuation.json beside it)")
    sp.add_argument("--payload", metavar="PAYLOAD.json", help="with --urdf/--mjcf: add this payload (rx90 "
                                                              "payload --json) as a body on the flange")
    sp.add_argument("--ur", metavar="OUT.script", help="from PAYLOAD.json: URScript set_target_payload line")
    sp.add_argument("--franka", metavar="OUT.json", help="from PAYLOAD.json: Franka's load (libfranka setLoad)")


def _read(path: str) -> dict:
    from rx90sym.files import read_json

    data = read_json(path)
    if not isinstance(data, dict):
        raise ValueError(f"{path}: expected a JSON object")
    return data


def is_payload_file(data: dict) -> bool:
    """A payload JSON (rx90 payload --json) rather than a fit."""
    return isinstance(data.get("payload"), list) and isinstance(data.get("method"), int)


def run(args: argparse.Namespace) -> int:
    outputs = [args.urdf, args.mjcf, args.ur, args.franka]
    if not any(outputs):
        raise UsageError("nothing to export: give --urdf, --mjcf (from a fit) or --ur, --franka (from a payload)")
    for out in outputs:
        check_output(out)
    if args.urdf and args.mjcf and Path(args.urdf).resolve() == Path(args.mjcf).resolve():
        raise UsageError(f"--urdf and --mjcf name the same file {args.urdf}: give them different names")
    data = _read(args.input)
    if is_payload_file(data):
        return _payload(args, data)
    if args.ur or args.franka:
        raise UsageError(f"--ur/--franka take a payload JSON (rx90 payload --json); {args.input} is not one")
    return _model(args, data)


def _payload(args: argparse.Namespace, data: dict) -> int:
    from rx90sym.files import atomic_write
    from rx90sym.flange_payload import FlangePayload, controller_family, franka_load, ur_script

    if args.urdf or args.mjcf or args.payload or args.robot:
        raise UsageError(f"{args.input} is a payload JSON: it exports --ur and --franka only "
                         f"(--urdf/--mjcf take a consistent fit, with --payload {args.input})")
    if "flange" not in data:
        raise ValueError(f"{args.input}: no 'flange' block (the payload in the flange frame): written by an "
                         f"older rx90 payload; run it again")
    load = FlangePayload.from_dict(data["flange"], args.input)
    if load.problem is not None:
        raise ValueError(f"{args.input}: the payload is not a physical rigid body ({load.problem}): a controller "
                         f"refuses it; identify it with rx90 payload --constrained")
    if controller_family(load.robot) is None:
        progress(f"warning: the robot name '{load.robot}' does not tell its controller: check that the payload's "
                 f"flange frame ({load.frame}) is the one the controller expects")
    texts = {}
    if args.ur:
        texts[args.ur] = ur_script(load)
    if args.franka:
        texts[args.franka] = json.dumps(franka_load(load), indent=1) + "\n"
    for path, text in texts.items():
        atomic_write(path, lambda fh, text=text: fh.write(text))
        progress(f"wrote {path}")
    return 0


def _model(args: argparse.Namespace, data: dict) -> int:
    from rx90sym.model_export import write_model
    from identify import load_fit
    from identify.export.models import model_text, not_identified

    if data.get("method") != "consistent" and not data.get("identified"):  # every fit made now has its model
        raise ValueError(f"{args.input}: this {data.get('method') or 'unknown'} fit holds base parameters only, no "
                         f"physical bodies (a fit file written before the identified model): identify again and "
                         f"export its JSON")
    fit = load_fit(args.input, args.robot)
    warning = fit.model.check_robot(fit.robot)
    if warning.startswith("the identification is of robot"):
        raise ValueError(f"{args.input}: {warning}")
    if warning:
        progress(f"warning: {warning}")
    payload = None
    if args.payload:
        pdata = _read(args.payload)
        if not is_payload_file(pdata):
            raise ValueError(f"{args.payload}: not a payload JSON (rx90 payload --json)")
        payload = {p["name"]: p["value"] for p in pdata["payload"]}
    artefacts = []  # every text first: a refused link or payload writes nothing
    if args.urdf:
        artefacts.append((args.urdf, *model_text(fit, "urdf", args.urdf, payload)))
    if args.mjcf:
        artefacts.append((args.mjcf, *model_text(fit, "mjcf", args.mjcf, payload)))
    for note in not_identified(fit):
        progress(f"warning: {note}")
    for path, text, side in artefacts:
        progress("wrote " + " and ".join(str(p) for p in write_model(path, text, side)))
    return 0
