"""A fast start: the command's version and every command's help do not import the heavy
libraries (cvxpy alone took 1.4 s); they are imported where they are used."""
from __future__ import annotations

import json
import subprocess
import sys

HEAVY = ("cvxpy", "matplotlib", "dask.distributed")

# Run in a fresh interpreter: this test process has imported everything already.
PROBE = """
import contextlib, io, json, sys
from identify.app import cli
commands = sorted(cli.build_parser()._subparsers._group_actions[0].choices)
for argv in [["--version"]] + [[c, "--help"] for c in commands]:
    with contextlib.redirect_stdout(io.StringIO()):
        try:
            cli.main(argv)
        except SystemExit as exc:
            assert exc.code == 0, (argv, exc.code)
print(json.dumps({"commands": commands, "loaded": [m for m in %r if m in sys.modules]}))
""" % (HEAVY,)


def test_version_and_every_help_leave_the_heavy_libraries_out():
    proc = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout.splitlines()[-1])
    assert {"identify", "predict", "payload", "excite", "gains"} <= set(out["commands"])
    assert out["loaded"] == [], f"imported by --version/--help: {out['loaded']}"


def test_the_heavy_libraries_are_there_when_a_command_needs_them():
    """The probe above can fail: the consistent fit does import cvxpy (lazily, when it runs)."""
    code = ("import sys, identify\nidentify.consistent_least_squares\n"
            "print('cvxpy' in sys.modules)")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "True"


def test_every_public_name_resolves():
    """The lazy tables of the packages' __init__ name real objects (and modules stay reachable)."""
    import excitation
    import identify
    import identify.estimation.consistency as consistency
    import rx90sym

    for package in (rx90sym, identify, excitation, consistency):
        names = set(package.__all__) | set(getattr(package, "_EXPORTS", {}))
        missing = sorted(n for n in names if not hasattr(package, n))
        assert not missing, (package.__name__, missing)
    # A public name that is also a module's name stays the public object once the module is imported.
    import rx90sym.base_parameters  # noqa: F401

    assert callable(identify.payload) and callable(rx90sym.base_parameters)
    assert rx90sym.twin.simulate is not None
