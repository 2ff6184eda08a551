"""Issue 7: identification from the optimised trajectory beats a random feasible one (twin)."""
from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "compare_excitation.py"


@pytest.mark.slow
def test_optimised_trajectory_gives_smaller_relative_sigma_than_a_random_one():
    spec = importlib.util.spec_from_file_location("compare_excitation", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    out = module.compare(seed=0)
    assert out["optimised"]["cond"] <= 30 < out["random"]["cond"]
    for group, value in out["optimised"]["median_rel_std"].items():
        assert value < out["random"]["median_rel_std"][group], group
