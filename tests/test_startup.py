"""A fast start: ``rx90 --version`` and every ``COMMAND --help`` import the standard library, the
command table and the few standard-library-only modules that hold the defaults a help text shows;
never NumPy, SciPy, CasADi, the model or the method (imported by the function that runs a command).

The check is a list of modules, not a timing: it holds on any machine, however loaded.
"""
from __future__ import annotations

import ast
import fnmatch
import json
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Iterable

#: Modules outside the standard library that ``--version`` and ``--help`` may import: the command
#: table, the light package ``__init__``s on the way (lazy tables: rx90sym/__init__.py holds the
#: version) and the modules of defaults shown in help texts (each imports the standard library only).
ALLOWED = (
    "identify", "identify.app", "identify.app.cli", "identify.app.common", "identify.app.flags",
    "identify.app.commands", "identify.app.commands.*",
    "rx90sym", "rx90sym.lazy", "rx90sym.defaults",
    "excitation", "excitation.defaults",
    "identify.io", "identify.io.defaults",
    "identify.signal", "identify.signal.defaults",
    "identify.observation", "identify.observation.defaults",
    "identify.gains", "identify.gains.defaults",
    "identify.payloads", "identify.payloads.defaults",
    "identify.monitor", "identify.monitor.defaults",
    "identify.rollout", "identify.rollout.defaults",
)


def beyond_allowed(modules: Iterable[str], allowed: Iterable[str] = ALLOWED) -> list[str]:
    """The modules of ``modules`` that are neither in the standard library nor matched by ``allowed``
    (names or shell patterns), sorted."""
    patterns = tuple(allowed)
    return sorted(m for m in set(modules) if m.split(".")[0] not in sys.stdlib_module_names
                  and not any(fnmatch.fnmatchcase(m, p) for p in patterns))


# Run in a fresh interpreter (this test process has imported everything already). SETUP runs after
# the snapshot of sys.modules, before the command line is imported. For each step (--version, then
# each COMMAND --help) the modules it imported first.
PROBE = """
import contextlib, io, json, sys
before = set(sys.modules)
{setup}
from identify.app import cli
commands = sorted(cli.build_parser()._subparsers._group_actions[0].choices)
steps = {{}}
for argv in [["--version"]] + [[c, "--help"] for c in commands]:
    with contextlib.redirect_stdout(io.StringIO()):
        try:
            cli.main(argv)
        except SystemExit as exc:
            assert exc.code == 0, (argv, exc.code)
    now = set(sys.modules)
    steps[" ".join(argv)] = sorted(now - before)
    before = now
print(json.dumps({{"commands": commands, "steps": steps}}))
"""


def probe(setup: str = "") -> dict:
    proc = subprocess.run([sys.executable, "-c", PROBE.format(setup=setup)], capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout.splitlines()[-1])


def offending(out: dict) -> dict[str, list[str]]:
    """Per step of the probe, the modules it imported beyond the allowed list (steps without any left out)."""
    return {step: bad for step, loaded in out["steps"].items() if (bad := beyond_allowed(loaded))}


def test_version_and_every_help_import_only_the_standard_library_and_the_command_table():
    out = probe()
    assert {"identify", "predict", "payload", "excite", "gains", "convert", "export"} <= set(out["commands"])
    assert len(out["steps"]) == len(out["commands"]) + 1
    assert offending(out) == {}, f"imported beyond the allowed list: {offending(out)}"


def test_the_check_catches_a_command_module_importing_numpy(tmp_path):
    """A command module with ``import numpy`` at module level (as gains.py importing the drive-gain
    method once did) added to the command table: the probe names numpy and the module."""
    (tmp_path / "heavy_command.py").write_text(textwrap.dedent('''
        import numpy as np  # a command module importing the method's libraries at module level

        def register(sub):
            sub.add_parser("heavy", help=f"default {np.pi:.3f}").set_defaults(func=lambda args: 0)
        '''))
    setup = (f"sys.path.insert(0, {str(tmp_path)!r})\n"
             "import identify.app.commands as table, heavy_command\n"
             "table.COMMANDS = table.COMMANDS + (heavy_command,)")
    out = probe(setup)
    assert "heavy" in out["commands"]
    bad = offending(out)
    assert list(bad) == ["--version"], bad  # the command table is imported with the command line
    assert {"heavy_command", "numpy"} <= set(bad["--version"])
    assert not any(m.startswith("identify") for m in bad["--version"])


def test_the_allowed_list_refuses_the_method_and_its_libraries():
    loaded = ["json", "argparse", "identify.app.commands.gains", "identify.io.defaults", "identify.io.blocks",
              "identify.gains.drive_gains", "rx90sym", "rx90sym.model_export", "numpy", "scipy.ndimage", "casadi"]
    assert beyond_allowed(loaded) == ["casadi", "identify.gains.drive_gains", "identify.io.blocks", "numpy",
                                      "rx90sym.model_export", "scipy.ndimage"]


def test_the_heavy_libraries_are_there_when_a_command_needs_them():
    """The lazy tables still reach the method: the consistent fit does import cvxpy (when first used)."""
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


DEFAULTS_MODULES = ("rx90sym/defaults.py", "identify/io/defaults.py", "identify/signal/defaults.py", "identify/observation/defaults.py",
                    "identify/gains/defaults.py", "excitation/defaults.py")


def test_each_default_shown_in_a_help_is_defined_once():
    """One definition: a name of a defaults module is assigned nowhere else in the packages (the method
    modules import it), so the help text and the library cannot drift apart."""
    root = Path(__file__).resolve().parents[1]

    def assigned(path: Path) -> set[str]:
        tree = ast.parse(path.read_text(), str(path))
        targets = [t for node in tree.body if isinstance(node, (ast.Assign, ast.AnnAssign))
                   for t in (node.targets if isinstance(node, ast.Assign) else [node.target])]
        return {t.id for t in targets if isinstance(t, ast.Name)}

    defaults = {rel: assigned(root / rel) - {"__all__"} for rel in DEFAULTS_MODULES}
    assert all(defaults.values()), defaults
    elsewhere = {}
    for path in (p for pkg in ("rx90sym", "excitation", "identify") for p in (root / pkg).rglob("*.py")):
        rel = path.relative_to(root).as_posix()
        if rel not in defaults:
            for names in defaults.values():
                elsewhere.update({f"{rel}: {n}": n for n in assigned(path) & names})
    assert not elsewhere, f"defined again outside the defaults modules: {sorted(elsewhere)}"
