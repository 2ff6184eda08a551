"""What a fresh clone must hold and print: the packaged TX40 record, the version, exact model
numbers, plain numbers in messages, an SPDX licence."""
from __future__ import annotations

import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

import rx90sym

ROOT = Path(__file__).resolve().parents[1]


def _cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "identify.app.cli", *args], capture_output=True,
                          text=True, cwd=ROOT, timeout=300)


def test_tx40_record_ships_with_its_licence_and_attribution():
    d = rx90sym.datasets.tx40()
    assert d.positions.is_relative_to(Path(rx90sym.__file__).parent)  # not ../shared
    head = d.positions.read_text().splitlines()[:2]
    assert head[0].split(",") == [f"Joint_{j}" for j in range(1, 7)]
    assert len(head[1].split(",")) == 6
    assert "Apache License" in d.license.read_text() and "Version 2.0" in d.license.read_text()
    assert "FIGAROH" in d.readme.read_text()
    # The sizes of the original record (45,000 rows + header), so a truncated copy fails here.
    for path in (d.positions, d.torques):
        with path.open() as f:
            assert sum(1 for _ in f) == 45_001


def test_package_data_and_licence_in_pyproject():
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert meta["project"]["license"] == "Apache-2.0"  # SPDX string, not the deprecated table
    assert any(r.startswith("setuptools>=") and int(r.split(">=")[1].split(".")[0]) >= 77
               for r in meta["build-system"]["requires"])
    data = meta["tool"]["setuptools"]["package-data"]["rx90sym"]
    for name in ("pos_read_data.csv", "curr_data.csv", "LICENSE", "README.md"):
        assert any(Path("data/tx40", name).match(g) for g in data), name


def test_version_option_prints_the_package_version():
    proc = _cli("--version")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == f"rx90 {rx90sym.__version__}"
    assert proc.stderr == ""  # no runpy warning about identify.app.cli


def test_model_table_prints_every_digit_of_the_robot_file(tmp_path):
    table = rx90sym.load_robot("rx90")
    rows = [(0, 0.0, 0.0, 0.0, 0.0), (0, -np.pi / 2, 0.0825, 0.0, 0.0), (0, 0.0, 0.45, 0.0, 0.0),
            (0, np.pi / 2, 0.0, 0.0, 0.45), (0, -np.pi / 2, 0.0, 0.0, 0.0), (0, np.pi / 2, 0.0, 0.0, 0.1234)]
    robot = rx90sym.robot_from_table(rows, name="digits")
    assert table.n == robot.n
    from identify.app.commands import model

    class Args:
        robot = None
        base = False
        json = None

    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf), pytest.MonkeyPatch.context() as mp:
        mp.setattr(model, "load_robot", lambda args: robot)
        assert model.run(Args()) == 0
    cells = [line.split() for line in buf.getvalue().splitlines()[2:]]
    assert float(cells[1][3]) == 0.0825 and float(cells[5][5]) == 0.1234
    assert float(cells[1][2]) == -90.0


def test_messages_print_plain_numbers_not_numpy_reprs():
    from identify.estimation.consistency import consistent_least_squares
    from identify.estimation.least_squares import weighted_least_squares
    from rx90sym.messages import plain

    assert plain(np.float64(np.nan)) == "nan" and plain((np.float64(50.0), 25.5)) == "(50, 25.5)"
    assert plain(np.array([1.5, 2.0])) == "[1.5, 2]" and plain("x") == "'x'"
    rng = np.random.default_rng(0)
    W, Y = rng.normal(size=(20, 2)), rng.normal(size=20)
    joint = np.r_[np.zeros(10), np.full(10, 1.5)]
    with pytest.raises(ValueError) as info:
        weighted_least_squares(W, Y, joint, ("a", "b"))
    assert "holds 1.5" in str(info.value) and "np." not in str(info.value)
    with pytest.raises(ValueError) as info:
        consistent_least_squares(np.eye(1), np.ones(1), np.ones((1, 1)), ("FV1",), rss_outside=np.float64(-1.0))
    assert "got -1" in str(info.value) and "np." not in str(info.value)
