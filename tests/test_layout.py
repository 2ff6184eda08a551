"""The layout: identify's top level holds only its subpackages; imports follow the data flow, with no circle.

Every import is read from the source (module level and inside functions), so a lazy import that
would close a circle or point up the flow fails here as an eager one does.
"""
from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: identify's stages in the order data flow through them: a stage imports only stages before it
#: (or itself). Stages of one rank are side by side and import nothing of each other.
IDENTIFY_FLOW = {
    "io": 0,            # files in: recordings, logs (their clocks, gaps, resampling), column maps, bags, gains files
    "signal": 1,        # filtering, derivatives, pairing of runs
    "observation": 2,   # one Processing, W and Y (eqs. 6-8), rest rows, spring and offset columns, logs read block by block
    "estimation": 3,    # (W)LS, sigma, essential, bootstrap, consistency, the torque delay
    "selection": 4,     # the blocked cross-validation against the raw torques and what it chooses: processing, prior weight
    "friction": 5,      # forms and columns, velocity scales and presliding travels searched, the form chosen per joint
    # The exported MJCF rolled out in MuJoCo against the recorded motion: a validation the Fit runs
    # (Fit.predict(..., rollout=...)), so before it; it needs only the model's MJCF writer (rx90sym),
    # the signals and the torque shift, and the parameters and processing a fit hands it.
    "rollout": 6,
    "fitting": 7,       # the Fit, its file, the identified model, prediction and validation, plausibility, fleets
    "payloads": 8,      # section IV
    "gains": 8,         # drive gains from a payload of known mass
    "export": 9,        # URDF, MJCF
    "monitor": 9,       # the model at work: payload and contact monitors
    "app": 10,          # the rx90 command, demo, report
}
#: Packages in the order they may import each other: the model knows neither trajectories nor
#: data, the method (excitation, identify) knows no application, the application knows all.
PACKAGES = {"rx90sym": 0, "excitation": 1, "identify": 1, "identify.app": 2}


def package(module: str) -> str:
    return "identify.app" if module.startswith("identify.app") else module.split(".")[0]


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports_of(path: Path) -> set[str]:
    """Absolute names of every module ``path`` imports (relative imports resolved), anywhere in it."""
    name = module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    tree = ast.parse(path.read_text(), str(path))
    typing_only = {id(n) for block in ast.walk(tree) if isinstance(block, ast.If) and _is_type_checking(block.test)
                   for stmt in block.body for n in ast.walk(stmt)}
    for node in ast.walk(tree):
        if id(node) in typing_only:  # annotations only: never imported at run time
            continue
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            found.add(target)
            # ``from pkg import sub`` imports the submodule pkg.sub when there is one
            found.update(f"{target}.{a.name}" for a in node.names)
    return found


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def project_graph() -> dict[str, set[str]]:
    modules = {module_name(p): p for pkg in ("rx90sym", "excitation", "identify") for p in (ROOT / pkg).rglob("*.py")}
    graph = {}
    for name, path in modules.items():
        graph[name] = {m for m in imports_of(path) if m in modules and m != name}
    return graph


def stage(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if parts[0] == "identify" and len(parts) > 2 else None


def test_identify_top_level_holds_only_subpackages():
    loose = sorted(p.name for p in (ROOT / "identify").glob("*.py") if p.name != "__init__.py")
    assert not loose, f"identify/ holds modules outside its subpackages: {loose}"
    packages = {p.name for p in (ROOT / "identify").iterdir() if (p / "__init__.py").exists()}
    assert packages == set(IDENTIFY_FLOW), f"subpackages {sorted(packages)} vs the flow {sorted(IDENTIFY_FLOW)}"


def test_no_import_points_up_the_data_flow():
    upward = []
    for a, targets in project_graph().items():
        for b in targets:
            pa, pb = package(a), package(b)
            if PACKAGES[pb] > PACKAGES[pa] or (pa != pb and PACKAGES[pa] == PACKAGES[pb]):
                upward.append(f"{a} -> {b}")
            sa, sb = stage(a), stage(b)
            if sa and sb and sa != sb and IDENTIFY_FLOW[sb] >= IDENTIFY_FLOW[sa]:
                upward.append(f"{a} -> {b}")
    assert not upward, "imports against the data flow:\n" + "\n".join(sorted(upward))


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_circle():
    graph = {m: {t for t in ts if not m.startswith(t + ".")} for m, ts in project_graph().items()}
    found = cycles(graph)
    assert not found, "import circles:\n" + "\n".join(" <-> ".join(c) for c in found)


def test_the_checks_catch_a_circle_and_an_upward_arrow():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []
    assert IDENTIFY_FLOW[stage("identify.signal.delay")] < IDENTIFY_FLOW[stage("identify.observation.matrix")]
