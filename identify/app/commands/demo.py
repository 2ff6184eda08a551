"""``rx90 demo``: the whole mission on the embedded RX90, with an HTML report."""
from __future__ import annotations

import argparse
from typing import Any


def register(sub: Any) -> None:
    sp = sub.add_parser("demo", help="run the whole mission on the embedded RX90 and write a report",
                        description="run the whole mission on the embedded RX90 and write a report")
    sp.set_defaults(func=run)
    sp.add_argument("--out", default="demo-output", help="output folder (default demo-output)")
    sp.add_argument("--quick", action="store_true", help="shorter motions and one start (for tests)")


def run(args: argparse.Namespace) -> int:
    from ..demo import run_demo

    return run_demo(args.out, quick=args.quick)
