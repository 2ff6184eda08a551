"""``rx90 excite`` as a user runs it: reproducible files, refusals, torque feasibility claims."""
from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest

from excitation.constraints import TORQUE_UNCHECKED, check_limits
from conftest import robot_file_without
from command_line import RX90, run
from test_excitation import toy_model

SMALL = ("excite", "--duration", "6", "--harmonics", "2", "--starts", "2")


def _without_timing(data: dict) -> dict:
    data = json.loads(json.dumps(data))
    data["optimiser"].pop("time_s")
    return data


@pytest.mark.slow
def test_two_runs_with_the_same_seed_in_separate_processes_write_identical_files(tmp_path):
    procs = [subprocess.Popen([RX90, *SMALL, "--seed", "3", "--out", str(tmp_path / f"{k}.csv"),
                               "--json", str(tmp_path / f"{k}.json")],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for k in (1, 2)]
    for proc in procs:
        _, err = proc.communicate(timeout=600)
        assert proc.returncode == 0, err
    assert (tmp_path / "1.csv").read_bytes() == (tmp_path / "2.csv").read_bytes()
    first, second = (json.loads((tmp_path / f"{k}.json").read_text()) for k in (1, 2))
    assert _without_timing(first) == _without_timing(second)
    assert first["optimiser"]["starts"] == 2 and first["optimiser"]["skipped_starts"] == []


@pytest.mark.slow
def test_robot_without_nominal_parameters_does_not_claim_torque_feasibility(tmp_path):
    # --no-self-collision: this test is about torques (collisions: test_excitation_collision.py)
    bare = robot_file_without(tmp_path / "tx40.toml", "tx40", "nominal")
    proc = run(*SMALL[:-1], "1", "--robot", str(bare), "--no-self-collision", "--out", str(tmp_path / "t.csv"),
               "--json", str(tmp_path / "t.json"))
    assert proc.returncode == 0, proc.stderr
    assert "NOT checked against the torque limits" in proc.stderr and "--params" in proc.stderr
    usage = json.loads((tmp_path / "t.json").read_text())["limits_usage"]
    assert usage["torque"] == TORQUE_UNCHECKED


def test_unchecked_torques_say_why_in_the_report():
    q = np.zeros((5, 2))
    report = check_limits(toy_model(torque=False), q, q, q, 100.0)
    assert report.to_dict()["torque"] == TORQUE_UNCHECKED
    assert isinstance(check_limits(toy_model(), q, q, q, 100.0).to_dict()["torque"], list)


@pytest.mark.parametrize("extra, message", [
    (("--workers", "2", "--scheduler", "tcp://127.0.0.1:1"), "not both"),
    (("--seed", "-1"), "--seed must be >= 0"),
    (("--workers", "0"), "--workers must be >= 1"),
    (("--criterion", "logdet", "--select", "ZZ1R"), "--select is for --criterion sigma"),
    (("--noise-std", "1,2"), "expected 6 numbers"),
])
def test_conflicting_or_bad_options_exit_2(tmp_path, extra, message):
    proc = run(*SMALL, *extra, "--out", str(tmp_path / "t.csv"))
    assert proc.returncode == 2 and message in proc.stderr, proc.stderr
    assert not (tmp_path / "t.csv").exists()
