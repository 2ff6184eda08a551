"""Shared fixtures: robots and random physically consistent parameters."""
from __future__ import annotations

import os

# One BLAS thread per test process (and the command lines it starts), set before NumPy loads:
# OpenBLAS's second thread costs far more than it gives on the suite's tall, thin least squares
# (a 6000 x 54 QR: 17 ms of CPU alone, 730 ms with two threads on a loaded 2-core machine), and
# `make test` runs one worker per core. An explicit OPENBLAS_NUM_THREADS is kept.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import importlib.util  # noqa: E402
import re  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import rx90sym  # noqa: E402

SHARED = Path(__file__).resolve().parents[1].parent / "shared"


def benchmark_module(name: str):
    """The module benchmarks/NAME.py (benchmarks/ is not a package), loaded by path."""
    path = Path(__file__).resolve().parents[1] / "benchmarks" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="session")
def ur10e_gains_25s():
    """The shared UR10e pair (benchmarks/ur10e_gains.py), paired, and drive gains fitted on its
    first 25 s (global method): (benchmark module, robot, pair, gains result, cut sample).
    Skips when the logs are absent (they are never copied into the repository)."""
    b = benchmark_module("ur10e_gains")
    if not (b.DATA / b.EMPTY[0]).exists():
        pytest.skip(f"UR10e logs not found in {b.DATA} (../shared is absent)")
    from identify.gains.drive_gains import drive_gains
    from identify.signal.pairing import pair_runs

    robot = b.ur10e_robot()
    pair = pair_runs(b.load_run(b.DATA / b.EMPTY[0], b.EMPTY[1]), b.load_run(b.DATA / b.LOADED[0], b.LOADED[1]))
    cut = 2500  # 25 s at the benchmark's 100 Hz grid
    gains = drive_gains(robot, [pair.empty.select(slice(0, cut))], [pair.loaded.select(slice(0, cut))], b.MASS,
                        method="global")
    return b, robot, pair, gains, cut


def robot_file_without(path, name: str, *tables: str):
    """A copy of bundled robot ``name`` at ``path`` without the given [tables] (e.g. "nominal")."""
    from rx90sym.robot_file import ROBOTS_DIR

    text = (ROBOTS_DIR / f"{name}.toml").read_text()
    for table in tables:
        text = re.sub(rf"(?ms)^\[{table}\]$.*?(?=^\[|\Z)", "", text)
    path.write_text(text)
    return path


def plain_signals_by_hand(rec) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The issue notes' yardstick signals written out: (q, q̇, q̈) of q through a 4th-order zero-phase
    Butterworth at 10 Hz at the recording's rate and numpy.gradient, and the samples 0.5 s from its ends."""
    from scipy.signal import butter, filtfilt

    t = np.asarray(rec.t)
    h = np.median(np.diff(t))
    b, a = butter(4, 10.0, fs=1 / h)
    q = filtfilt(b, a, rec.q, axis=0)
    dq = np.gradient(q, h, axis=0)
    ddq = np.gradient(dq, h, axis=0)
    return q, dq, ddq, np.flatnonzero((t >= t[0] + 0.5 - 1e-9) & (t <= t[-1] - 0.5 + 1e-9))


def random_body(rng: np.random.Generator) -> np.ndarray:
    """XX XY XZ YY YZ ZZ MX MY MZ M of a random consistent body about its frame origin."""
    m = rng.uniform(0.5, 20.0)
    c = rng.uniform(-0.3, 0.3, 3)
    A = rng.normal(size=(3, 3))
    R, _ = np.linalg.qr(A)
    # Principal moments from random positive second moments: always satisfy the triangle rule.
    s = rng.uniform(0.001, 0.05, 3) * m
    Ic = R @ np.diag([s[1] + s[2], s[0] + s[2], s[0] + s[1]]) @ R.T
    I = Ic + m * (c @ c * np.eye(3) - np.outer(c, c))
    return np.array([I[0, 0], I[0, 1], I[0, 2], I[1, 1], I[1, 2], I[2, 2], *(m * c), m])


def random_chi(robot, rng: np.random.Generator, actuation: bool = True) -> np.ndarray:
    """Random standard parameter vector: consistent bodies, positive IA, FS, FV, extras."""
    chi = np.zeros(len(robot.parameter_names))
    for j in range(robot.n):
        chi[13 * j:13 * j + 10] = random_body(rng)
        if actuation:
            chi[13 * j + 10:13 * j + 13] = rng.uniform(0.05, 3.0, 3)
    if actuation:
        chi[13 * robot.n:] = rng.uniform(0.1, 2.0, len(chi) - 13 * robot.n)
    return chi


def random_states(robot, rng: np.random.Generator, N: int):
    return (rng.uniform(-np.pi, np.pi, (N, robot.n)), rng.normal(0, 2, (N, robot.n)),
            rng.normal(0, 5, (N, robot.n)))


RANDOM_TABLE = [  # prismatic joints, non-zero d, r and generic alpha
    (0, 0.0, 0.0, 0.0, 0.0),
    (1, -np.pi / 2, 0.2, 0.3, 0.1),
    (0, 0.7, 0.4, 0.2, -0.3),
    (1, np.pi / 2, 0.1, -0.5, 0.2),
    (0, -0.4, 0.3, 0.1, 0.25),
    (0, 1.1, 0.15, 0.0, 0.05),
]


@pytest.fixture(scope="session")
def rx90():
    return rx90sym.load_robot("rx90")


@pytest.fixture(scope="session")
def tx40():
    return rx90sym.load_robot("tx40")


@pytest.fixture(scope="session")
def random_robot():
    return rx90sym.robot_from_table(RANDOM_TABLE, name="random")


# --------------------------------------------------------------------------- twin recordings
# Hand-made motions (multisines) recorded on the twin with the realistic noise profile; shared
# by the identification and payload tests (simulating costs ~1 s per 20 s motion).
EMPTY_SEEDS = (0, 1, 2, 3)


@pytest.fixture(scope="session")
def rx90_base(rx90):
    return rx90sym.base_parameters(rx90)


@pytest.fixture(scope="session")
def rx90_truth(rx90, rx90_base):
    chi = rx90.parameter_vector(rx90sym.twin.default_parameters(rx90))
    return dict(zip(rx90_base.names, rx90_base.beta(chi)))


@pytest.fixture(scope="session")
def twin_empty(rx90):
    from motions import multisine

    return [rx90sym.twin.simulate(rx90, multisine(rx90, s), duration=20.0, noise="realistic", seed=s)
            for s in EMPTY_SEEDS]


@pytest.fixture(scope="session")
def twin_loaded(rx90):
    """Loaded runs of the first two empty motions, per payload of Tables 4 and 5."""
    from motions import multisine

    return {name: [rx90sym.twin.simulate(rx90, multisine(rx90, s), duration=20.0, payload=name,
                                         noise="realistic", seed=100 + s) for s in EMPTY_SEEDS[:2]]
            for name in ("tables_4", "tables_5")}


# --------------------------------------------------------------------------- parallel runs
# `make test` runs the suite on pytest-xdist workers, one per core. A file's tests stay on one
# worker (its module- and session-scoped fixtures are made once), except in the files below whose
# tests share no fixture and each cost seconds: those are spread one test at a time. The files
# holding slow-marked tests are handed out first, so that no long file starts last and holds the
# run while the other worker idles.
SPREAD_FILES = frozenset({"test_notebooks.py"})


def pytest_xdist_make_scheduler(config, log):
    """The xdist scheduler of ``--dist loadfile`` with the tests of SPREAD_FILES scheduled one
    by one, in the workers' collection order (pytest-xdist's own ``loadgroup`` marks do not
    reach its scheduler under pytest 9)."""
    if config.getvalue("dist") != "loadfile":
        return None
    from xdist.scheduler import LoadFileScheduling

    class FileScheduling(LoadFileScheduling):
        def _split_scope(self, nodeid: str) -> str:
            path = nodeid.split("::", 1)[0]
            return nodeid if Path(path).name in SPREAD_FILES else path

    config.option.loadscopereorder = False   # keep the order below, not the count of tests
    return FileScheduling(config, log)


def pytest_collection_modifyitems(config, items):
    """On an xdist worker: the files with a slow-marked test first (a stable sort: a file's tests
    stay together and in order). A run without workers keeps pytest's order."""
    if not hasattr(config, "workerinput"):
        return
    slow_files = {item.path for item in items if item.get_closest_marker("slow")}
    items.sort(key=lambda item: item.path not in slow_files)
