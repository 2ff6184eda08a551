"""The twin's torque ripple on a robot file without gear ratios (issue 13)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import identify
import rx90sym
from rx90sym.robot_file import ROBOTS_DIR

from motions import multisine


@pytest.fixture(scope="module")
def gearless(tmp_path_factory) -> rx90sym.Robot:
    """The RX90 without its [transmission] section: every gear ratio 1."""
    text = (ROBOTS_DIR / "rx90.toml").read_text()
    text = text[:text.index("[transmission]")] + text[text.index("[coupling]"):]
    path = tmp_path_factory.mktemp("gearless") / "gearless.toml"
    path.write_text(text.replace('name = "rx90"', 'name = "gearless"'))
    return rx90sym.load_robot(path)


def z_scores(robot: rx90sym.Robot, noise: rx90sym.twin.NoiseProfile, seeds: range) -> np.ndarray:
    chi = robot.parameter_vector(rx90sym.default_parameters(rx90sym.load_robot("rx90")))
    base = rx90sym.base_parameters(robot)
    recs = [rx90sym.twin.simulate(robot, multisine(robot, s), params=chi, duration=20.0, noise=noise, seed=s)
            for s in seeds]
    res = identify.fit(robot, recs, identify.Processing(min_velocity=0.1, rest="drop", estimate_delay=False, cross_validate=False), base=base).result
    return (res.values - base.beta(chi)) / res.std


@pytest.mark.slow
def test_a_robot_without_gears_is_identified_as_well_as_a_geared_one(gearless):
    realistic = rx90sym.twin.profiles()["realistic"]
    with pytest.warns(UserWarning, match="no gear ratios; the motor torque ripple assumes motors geared 50:1"):
        z = z_scores(gearless, realistic, range(4))
    # 54 base parameters: measured 52-54 within 3 sigma over seeds 0-3, 10-13, 20-23.
    assert np.sum(np.abs(z) <= 3) >= 51 and np.max(np.abs(z)) < 5, np.round(z, 1)
    # The cause, shown: the ripple at 6 and 12 cycles per joint turn (motor = joint) biases the
    # fit (measured: 40/54 within 3 sigma, |z| up to 11).
    with pytest.warns(UserWarning):
        z_in_band = z_scores(gearless, replace(realistic, ripple_gear=1.0), range(4))
    assert np.sum(np.abs(z_in_band) <= 3) <= 46 and np.max(np.abs(z_in_band)) > 6
