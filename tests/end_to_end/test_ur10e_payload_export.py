"""The shared UR10e pair's payload in UR's form, no circle: gains fitted on the first 25 s, the
payload by methods 3 and 4 on the rest, exported as a URScript line that is parsed back.

The logs have no licence: read in place from ../shared, skipped when absent.
"""
from __future__ import annotations

import json
import re

import numpy as np
import pytest

from identify.app.cli import main
from identify.io.gains import DriveGains, apply_gains
from identify.payloads.methods import payload
from rx90sym.flange_payload import flange_payload

from conftest import SHARED

DATA = SHARED / "data" / "ur10e"
needs_data = pytest.mark.skipif(not (DATA / "ur-20_02_19_14harm50sec.csv").exists(),
                                reason=f"UR10e logs not found in {DATA} (../shared is absent)")
NUMBER = r"([-+0-9.eE]+)"
LINE = re.compile(rf"^set_target_payload\({NUMBER}, \[{NUMBER}, {NUMBER}, {NUMBER}\], "
                  rf"\[{NUMBER}, {NUMBER}, {NUMBER}, {NUMBER}, {NUMBER}, {NUMBER}\]\)$")


def parse_set_target_payload(text: str) -> tuple[float, np.ndarray, np.ndarray]:
    """(mass, CoG, inertia 3x3) of a URScript set_target_payload line, written out independently."""
    m = LINE.match(text.strip())
    assert m is not None, text
    v = [float(x) for x in m.groups()]
    xx, yy, zz, xy, xz, yz = v[4:]
    return v[0], np.array(v[1:4]), np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


@pytest.fixture(scope="module")
def held_out(ur10e_gains_25s):
    """Gains fitted on the first 25 s of the pair (conftest); the remaining samples with them."""
    b, robot, pair, runs, gains, cut = ur10e_gains_25s
    g = DriveGains(gains.gains.gains, side="joint")
    return b, robot, [apply_gains(r.select(slice(cut, r.n_samples)), g, robot) for r in runs]


@needs_data
@pytest.mark.slow
@pytest.mark.parametrize("method", [3, 4])
def test_urscript_payload_from_held_out_data(tmp_path, held_out, method):
    b, robot, rest = held_out
    res = payload(robot, method, empty=[rest[0]], loaded=[rest[1]], min_velocity=b.MIN_VELOCITY, constrained=True)
    block = flange_payload(robot, res.as_dict()).to_dict()
    (tmp_path / "p.json").write_text(json.dumps({**res.to_dict(), "flange": block}))
    out = tmp_path / "payload.script"
    assert main(["export", str(tmp_path / "p.json"), "--ur", str(out)]) == 0
    mass, cog, inertia = parse_set_target_payload(out.read_text())
    assert abs(mass / b.MASS - 1) < 0.03, mass
    np.testing.assert_allclose(cog, block["cog_m"], rtol=0, atol=0)
    xx, yy, zz, xy, xz, yz = block["inertia_at_cog_kg_m2"]
    np.testing.assert_array_equal(inertia, [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    moments = np.linalg.eigvalsh(inertia)
    assert moments[0] > 0, moments
    a, c, d = moments
    assert a + c >= d and a + d >= c and c + d >= a


def test_the_parser_reads_what_ur_script_writes():
    from rx90sym import load_robot, load_payload
    from rx90sym.flange_payload import ur_script

    p = flange_payload(load_robot("ur10e"), load_payload("tables_4"))
    mass, cog, inertia = parse_set_target_payload(ur_script(p))
    assert mass == p.mass
    np.testing.assert_array_equal(cog, p.cog)
    np.testing.assert_array_equal(inertia, p.inertia)
