"""``rx90 model``: the robot's geometric table, and its base parameters (Table 2, eq. 19)."""
from __future__ import annotations

import argparse
from typing import Any

from ..common import check_output, load_robot, robot_option


def register(sub: Any) -> None:
    sp = sub.add_parser("model", help="print the robot's model (and base parameters)",
                        description="print the robot's model (and base parameters)")
    sp.set_defaults(func=run)
    robot_option(sp)
    sp.add_argument("--base", action="store_true", help="also print the base parameters (Table 2, eq. 19)")
    sp.add_argument("--json", help="write the model summary as JSON")


def run(args: argparse.Namespace) -> int:
    import numpy as np

    import rx90sym
    from rx90sym.files import write_json

    robot = load_robot(args)
    check_output(args.json)
    lines = [f"robot {robot.name}: {robot.n} joints, {len(robot.parameter_names)} standard parameters",
             " j  sigma  alpha[deg]      d[m]  theta[deg]      r[m]"]
    for j in range(robot.n):
        # :g keeps every digit of the robot file (d = 0.0825, not 0.083); the angles too (e.g. 12.5).
        lines.append(f"{j + 1:2d}  {robot.sigma[j]:5d}  {np.degrees(robot.alpha[j]):10.6g}  {robot.d[j]:8.6g}"
                     f"  {np.degrees(robot.theta[j]):10.6g}  {robot.r[j]:8.6g}")
    print("\n".join(lines))
    out: dict[str, Any] = {"robot": robot.name, "n": robot.n, "parameters": list(robot.parameter_names)}
    if args.base:
        bp = rx90sym.base_parameters(robot)
        print(bp.table())
        out["base"] = {"names": list(bp.names), "expressions": dict(bp.expressions)}
    if args.json:
        write_json(args.json, out)
    return 0
