"""The payload's quoted σ is honest: estimates on the two halves of one empty/loaded pair agree
within 3x their combined headline σ (the larger of eq. 13's and the segment bootstrap's).

The twin with realistic noise (coloured torque residuals: ripple, Stribeck friction, servo error),
two motions of conftest's twin runs and both payloads of Tables 4-5; benchmarks/payload_halves.py
runs 20 seeds (at least 19 must agree)."""
from __future__ import annotations

import numpy as np

import identify


def _halves_z(rx90, empty, loaded, method):
    """|Mc(first half) - Mc(second half)| / sqrt(σ1² + σ2²), σ the headline σ of each half."""
    first = [identify.split(r, 0.5) for r in (empty, loaded)]
    a = identify.payload(rx90, method, empty=[first[0][0]], loaded=[first[1][0]])
    b = identify.payload(rx90, method, empty=[first[0][1]], loaded=[first[1][1]])
    i = a.names.index("Mc")
    assert a.std_headline[i] >= a.std[i] and b.std_headline[i] >= b.std[i]
    return abs(a["Mc"] - b["Mc"]) / np.hypot(a.std_headline[i], b.std_headline[i])


def test_payload_halves_agree_within_three_headline_sigma(rx90, twin_empty, twin_loaded):
    z = [_halves_z(rx90, twin_empty[k], twin_loaded[name][k], 3)
         for name in ("tables_4", "tables_5") for k in range(2)]
    assert max(z) <= 3.0, z


def test_the_headline_is_the_larger_sigma_and_says_which(rx90, twin_empty, twin_loaded):
    res = identify.payload(rx90, 3, empty=[twin_empty[0]], loaded=[twin_loaded["tables_4"][0]])
    i = res.names.index("Mc")
    entry = {p["name"]: p for p in res.to_dict()["payload"]}["Mc"]
    assert entry["std_headline"] == max(entry["std"], entry["bootstrap_std"])
    assert f"± {res.std_headline[i]:.2g} kg (±1σ" in res.headline()
