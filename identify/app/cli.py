"""The ``rx90`` command: model, excite, simulate, convert, identify, payload, demo.

Exit codes: 0 success, 2 bad input (one line on stderr naming the problem), 1 a failure that
is not the user's (a solver that did not converge is reported, never returned as a result).
"""
from __future__ import annotations

import argparse
import re
import sys
import warnings
from typing import Sequence

import rx90sym  # its __init__ holds the version and a table of lazy names: the model is not imported

from .commands import COMMANDS
from .common import PROG


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog=PROG, description="Dynamic identification of serial robots "
                                "(Staubli RX90 and its payload) with CasADi.")
    p.add_argument("--version", action="version", version=f"%(prog)s {rx90sym.__version__}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for command in COMMANDS:
        command.register(sub)
    return p


# A value list that starts with a minus sign ("-1.5,0,..." or "-2:2,...") after an option, or a
# negative number in exponent form ("-1e-6": argparse reads it as an option).
_NEGATIVE_LIST = re.compile(r"^-\.?\d(.*[,:]|[\d.]*[eE][-+]?\d+$)")


def join_negative_values(argv: Sequence[str]) -> list[str]:
    """``--start-pose -1.5,0,...`` as ``--start-pose=-1.5,0,...``: argparse takes a plain negative
    number as a value but reads a comma or colon list starting with '-' (or ``-1e-6``) as an
    unknown option ("expected one argument"), which refused every pose or range whose first value
    is negative, and hid the reason of a refused negative tolerance."""
    out: list[str] = []
    for arg in argv:
        before = out[-1] if out else ""
        if before.startswith("--") and "=" not in before and _NEGATIVE_LIST.match(arg):
            out[-1] = f"{before}={arg}"
        else:
            out.append(arg)
    return out


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(join_negative_values(sys.argv[1:] if argv is None else argv))
    from rx90sym.threads import command_blas_threads  # after --help and --version have exited

    # The library's BLAS rule for the whole command, entered before anything loads NumPy
    # (rx90sym.threads: one thread unless an environment variable such as OPENBLAS_NUM_THREADS names the count).
    with command_blas_threads():
        return _run(args)


def _run(args: argparse.Namespace) -> int:
    """The parsed command run: its exit code (0, 1 a failed solver, 2 bad input, one line on stderr)."""
    from identify.estimation.consistency.errors import SolverError

    def show_warning(message, category, filename, lineno, file=None, line=None) -> None:
        print(f"[{PROG}] warning: {message}", file=sys.stderr, flush=True)

    try:
        with warnings.catch_warnings():
            warnings.showwarning = show_warning  # one plain line, restored on exit
            return int(args.func(args) or 0)
    except SolverError as exc:
        # A solver that failed is not the user's input: reported, exit 1, nothing written.
        print(f"{PROG} {args.command}: solver failed: {str(exc).splitlines()[0]}", file=sys.stderr)
        return 1
    except (ValueError, KeyError, FileNotFoundError, IsADirectoryError, PermissionError) as exc:
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        if isinstance(exc, KeyError):
            msg = msg.strip("\"'")
        print(f"{PROG} {args.command}: error: {msg}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
