"""What every ``rx90`` command shares: errors, progress lines, output checks, robot loading.

Standard library only at module level (``rx90 --help`` imports every command module): the model
and the method are imported inside the functions that use them.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

from rx90sym.defaults import ACCELERATION_DEFAULT_TEXT, MAX_SNAP_LENGTH_M, MAX_SNAP_RAD, SNAP_LENGTH_M, SNAP_RAD

if TYPE_CHECKING:  # annotations only
    import numpy as np

    import rx90sym

PROG = "rx90"


class UsageError(ValueError):
    """Conflicting or missing options."""


def progress(message: str) -> None:
    """One progress line on stderr (stdout keeps the tables)."""
    print(f"[{PROG}] {message}", file=sys.stderr, flush=True)


def check_output(path: str | None) -> None:
    """Refuse an output path whose folder does not exist before doing any work."""
    if path is not None and not Path(path).resolve().parent.is_dir():
        raise UsageError(f"output folder of {path} does not exist")


def floats(text: str, what: str, count: int | None = None) -> np.ndarray:
    """Comma-separated finite numbers of option ``what`` (``count`` of them when given)."""
    import numpy as np

    try:
        values = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise UsageError(f"{what}: expected comma-separated numbers, got {text!r}") from None
    if count is not None and values.size != count:
        raise UsageError(f"{what}: expected {count} numbers, got {values.size}")
    if not np.all(np.isfinite(values)):
        raise UsageError(f"{what}: values must be finite, got {text!r}")
    return values


def load_robot(args: argparse.Namespace, offsets: bool = False, recordings: Sequence[str] = ()) -> rx90sym.Robot:
    """The robot of ``--robot``, else the one the recordings' headers name (all the same), else a
    UsageError: no command that reads recordings guesses a robot. Prints the robot it uses."""
    import rx90sym
    from identify.io.recordings import declared_robot

    acceleration = getattr(args, "acceleration", None)
    spec = args.robot if args.robot is not None else getattr(args, "default_robot", None)
    if spec is None:
        names = {p: declared_robot(p) for p in recordings}
        named = sorted({n for n in names.values() if n is not None})
        if len(named) > 1:
            raise UsageError("the recordings name different robots (" + ", ".join(
                f"{Path(p).name}: {n}" for p, n in names.items() if n) + "): give --robot")
        if not named:
            raise UsageError("no robot: give --robot NAME|FILE.toml|FILE.urdf (the recordings name none "
                             "in a '# robot: NAME' line; the toolkit does not guess one)")
        spec = named[0]
        if spec not in rx90sym.bundled_robots():
            raise UsageError(f"the recordings name robot {spec!r}, which is not a bundled robot: give its "
                             f"file with --robot FILE.toml|FILE.urdf")
    robot = rx90sym.load_robot(spec, offsets=offsets, tip=getattr(args, "tip", None),
                               acceleration=None if acceleration is None else floats(acceleration, "--acceleration"),
                               **snap_options(args, spec))
    announce_robot(robot, "from --robot" if args.robot is not None else
                   "default" if getattr(args, "default_robot", None) is not None else "named by the recordings")
    return robot


def announce_robot(robot: rx90sym.Robot, how: str) -> None:
    """One line on stderr: the robot used (name, file, joint count) and where its choice came from."""
    progress(f"robot {robot.name} ({robot.source or 'built in'}; {robot.n} joints; {how})")


SPRING_MODES = ("default", "none", "identify", "identify-k")


def spring_options(sp: argparse.ArgumentParser) -> None:
    """``--spring``, ``--spring-joint``, ``--spring-orders`` (see docs/robot-files.md)."""
    sp.add_argument("--spring", default="default",
                    help="default (the robot file's spring) | none | FILE.csv (angle [rad, model], "
                         "torque [N m]) | identify (a Fourier series in the joint angle, identified "
                         "with the other parameters) | identify-k (k only, the robot file's geometry)")
    sp.add_argument("--spring-joint", type=int, help="joint of the spring for FILE.csv / identify "
                    "(default: the robot file's [spring] joint)")
    sp.add_argument("--spring-orders", help="harmonic orders of --spring identify, comma list "
                    "(default 1,2,3,4; orders the rigid-body model spans are grouped with it)")


def spring_notice(robot: rx90sym.Robot) -> None:
    """Say on stderr when the robot's spring is a placeholder (invented constants)."""
    if robot.spring is not None and robot.spring.placeholder:
        progress(f"warning: {robot.spring.label()}; on a real robot use --spring FILE.csv or "
                 f"--spring identify")


def robot_with_spring(args: argparse.Namespace, recordings: Sequence[str] = ()) -> tuple[rx90sym.Robot, Any]:
    """The robot with the spring the options ask for, and the spring model to identify (a
    SpringBasis / SpringStiffness) or None. Conflicting options are a UsageError."""
    import rx90sym
    from rx90sym.spring import SpringBasis, SpringStiffness, read_spring_table

    robot = load_robot(args, offsets=args.offsets, recordings=recordings)
    mode = args.spring if args.spring in SPRING_MODES else "file"
    if args.spring_joint is not None and mode in ("default", "none"):
        raise UsageError(f"--spring-joint goes with --spring FILE.csv or identify, not --spring {args.spring}")
    if args.spring_orders is not None and mode != "identify":
        raise UsageError("--spring-orders goes with --spring identify")
    if mode == "none":
        return robot.with_options(spring=None), None
    if mode == "default":
        return robot, None
    if mode == "identify-k":
        if robot.spring is None or robot.spring.table is not None:
            raise UsageError("--spring identify-k needs the spring's geometry (a, b, L0, angle_offset) "
                             "in the robot file's [spring]; use --spring identify otherwise")
        if args.spring_joint is not None and args.spring_joint - 1 != robot.spring.joint:
            raise UsageError(f"--spring-joint {args.spring_joint} differs from the robot file's "
                             f"spring joint {robot.spring.joint + 1} whose geometry identify-k uses")
        if robot.spring.placeholder:
            progress(f"warning: identify-k uses the geometry of {robot.spring.label()}")
        return robot.with_options(spring=None), SpringStiffness(robot.spring)
    if args.spring_joint is not None:
        if not 1 <= args.spring_joint <= robot.n:
            raise UsageError(f"--spring-joint {args.spring_joint}: robot {robot.name!r} has joints 1..{robot.n}")
        joint = args.spring_joint - 1
    elif robot.spring is not None:
        joint = robot.spring.joint
    else:
        raise UsageError(f"robot {robot.name!r} has no [spring]: give --spring-joint J")
    if mode == "identify":
        try:
            orders = (1, 2, 3, 4) if args.spring_orders is None else tuple(
                int(x) for x in args.spring_orders.split(","))
            basis = SpringBasis(joint, orders, constant=True)
        except ValueError as exc:
            raise UsageError(f"--spring-orders {args.spring_orders!r}: {exc}") from None
        return robot.with_options(spring=None), basis
    table = read_spring_table(args.spring)
    return robot.with_options(spring=rx90sym.Spring(joint=joint, table=table)), None


def robot_params(path: str) -> dict[str, float]:
    try:
        with open(path) as fh:
            data = json.load(fh)
    except (OSError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: cannot read robot parameters ({exc})") from None
    try:
        if "parameters" in data and isinstance(data["parameters"], list):
            return {p["name"]: float(p["value"]) for p in data["parameters"]}
        if "parameters" in data and isinstance(data["parameters"], dict):
            return {k: float(v) for k, v in data["parameters"].items()}
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"{path}: malformed parameter entry ({exc})") from None
    raise ValueError(f"{path}: no 'parameters' list or table (the output of rx90 identify --json)")




def convention_option(sp: argparse.ArgumentParser) -> None:
    """``--convention``: joint angles of recordings, 'controller' (the controller's, as logged) or
    'model' (Khalil's); 'staubli' and 'khalil' are their old names."""
    sp.add_argument("--convention", choices=("controller", "model", "staubli", "khalil"), default=None,
                    help="joint angles of the files: controller (as logged) or model (Khalil); "
                         "default: the file's header, else controller")


def robot_option(sp: argparse.ArgumentParser, default: str | None = "rx90", source: str = "",
                 acceleration_default: str = ACCELERATION_DEFAULT_TEXT) -> None:
    """``--robot``: a bundled robot name, a robot file or a URDF; ``--tip``: a URDF's end link.
    ``default`` None: no default robot (``source`` says where the robot is taken from instead).
    ``acceleration_default``: what the command uses when a URDF's --acceleration is not given."""
    text = (f"(default {default})" if default is not None else
            f"(default: {source})" if source else "(required)")
    # args.robot stays None unless given: the robot line says "default", not "from --robot".
    sp.set_defaults(default_robot=default)
    sp.add_argument("--robot", default=None, help=f"bundled robot name, robot file or URDF {text}")
    sp.add_argument("--tip", help="with a URDF --robot: the link ending the chain from the URDF root "
                                  "(default: the only leaf link)")
    sp.add_argument("--acceleration", metavar="A|A1,..,An",
                    help="with a URDF --robot: joint acceleration limits [rad/s^2; m/s^2 prismatic], one "
                         f"number or one per joint (a URDF has none; default {acceleration_default})")
    sp.add_argument("--snap", type=snap_value("--snap", MAX_SNAP_RAD), metavar="RAD",
                    help=f"with a URDF --robot: joint origin angles within RAD of a multiple of pi/2 are made "
                         f"exact, each change printed (default {SNAP_RAD:g}: 1.57, 1.571, 1.5708 written for "
                         f"pi/2; at most {MAX_SNAP_RAD:g}); 0 keeps the origins as written, lengths included")
    sp.add_argument("--snap-length", type=snap_value("--snap-length", MAX_SNAP_LENGTH_M), metavar="M",
                    help=f"with a URDF --robot: joint origin lengths within M of 0 are made 0 (default "
                         f"{SNAP_LENGTH_M:g} m, at most {MAX_SNAP_LENGTH_M:g})")


def snap_value(option: str, top: float) -> Any:
    """argparse type of --snap / --snap-length: a number in [0, top] (exit 2 with the reason otherwise)."""
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
        if not 0 <= value <= top:  # also refuses nan
            raise argparse.ArgumentTypeError(f"{text} is outside [0, {top:g}]"
                                             + (" rad (0 turns snapping off)" if option == "--snap" else " m"))
        return value
    parse.__name__ = option  # argparse names the type in its messages
    return parse


def snap_options(args: argparse.Namespace, robot_spec: str) -> dict[str, float]:
    """load_robot's snap= and snap_length= from --snap / --snap-length ({} when neither is given)."""
    snap, length = getattr(args, "snap", None), getattr(args, "snap_length", None)
    if snap is None and length is None:
        return {}
    if not str(robot_spec).lower().endswith(".urdf"):
        raise UsageError(f"--snap and --snap-length are for a URDF --robot, not {robot_spec!r} (a robot "
                         f"file's angles and lengths are exact)")
    if snap == 0 and length is not None and length != 0:
        raise UsageError("--snap 0 turns snapping off, lengths included: drop --snap-length or give --snap > 0")
    out = {} if snap is None else {"snap": snap}
    return out if length is None or snap == 0 else {**out, "snap_length": length}


