"""Issues 14 and 15: what the optimised excitation buys, asserted where it holds on any machine.

The former test compared one optimised and one random trajectory on the wrist's median relative
sigma from one twin run: a knife edge (cond 25.25 vs 24.46, wrist 62 % vs 51 % on another
machine), since the raw cond criterion does not aim at the wrist and one noise draw decides.
Now: the raw-cond optimiser is judged on cond, which it controls; the default criterion
("sigma", the predicted relative sigma of every base parameter) on the twin over three seeds,
median of the per-seed group medians, with the margins measured by benchmarks/compare_criteria.py.
"""
from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

import excitation

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "compare_criteria.py"


def _module():
    spec = importlib.util.spec_from_file_location("compare_criteria", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.slow
def test_default_criterion_halves_the_wrist_sigma_of_random_motions_on_the_twin():
    assert excitation.DEFAULT_CRITERION == "sigma"
    rows = _module().compare(seeds=3, criteria=("sigma",), stream=None)
    ratio = {g: np.median([r["groups"][g] for r in rows["sigma"]])
             / np.median([r["groups"][g] for r in rows["random"]]) for g in excitation.objective.GROUPS}
    # measured over seeds 0-4 (docs/excitation.md): wrist 0.21x (per seed 0.18-0.28), links 1-3
    # 0.15x, friction 0.69x, coupling 0.63x; targets: wrist <= 0.5x, no group worse than 1.1x
    assert ratio["inertial, wrist 4-6"] <= 0.5, ratio
    assert max(ratio.values()) <= 1.1, ratio
