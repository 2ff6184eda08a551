"""Tables of the reports, built from the JSON records (plain dicts): parameters, bodies, gains, validation."""
from __future__ import annotations

import re
from typing import Any, Mapping, Sequence

import numpy as np

from rx90sym.rigid_body import RigidBody

from .cells import fmt, number
from .page import Cell, Column, Table
from .summary import WEAK_REL_STD_PCT, mark

# Units of a parameter by its name's stem (revolute joints; eq. 4's order, then actuation terms).
_UNITS = (("XX", "kg·m²"), ("XY", "kg·m²"), ("XZ", "kg·m²"), ("YY", "kg·m²"), ("YZ", "kg·m²"),
          ("ZZ", "kg·m²"), ("MX", "kg·m"), ("MY", "kg·m"), ("MZ", "kg·m"), ("IA", "kg·m²"),
          ("FV", "N·m·s/rad"), ("FS", "N·m"), ("OFF", "N·m"), ("K", "N·m/rad"), ("M", "kg"))


def unit(name: str) -> str:
    """The SI unit of a standard, base or payload parameter (revolute joints), '' when unknown."""
    stem = re.sub(r"(R|c|\d+|[PN])*$", "", name) if not name.startswith(("FSP", "FSN")) else "FS"
    for prefix, u in _UNITS:
        if stem == prefix or (prefix in ("FV", "FS") and stem.startswith(prefix)):
            return u
    return ""


def parameter_table(parameters: Sequence[Mapping[str, Any]], bootstrap_std: Sequence[Any] | None = None,
                    a_priori: Mapping[str, Any] | None = None, table_id: str = "parameters",
                    caption: str = "Base parameters") -> Table:
    """Name, unit, estimate, σ (eq. 14 from eq. 13), σr % (eq. 15) marked, bootstrap σ and σr %."""
    cols = [Column("parameter", text=True), Column("unit", text=True)]
    if a_priori is not None:
        cols.append(Column("a priori"))
    cols += [Column("estimate"), Column("σ eq. 13", digits=3), Column("σr eq. 15", "%", decimals=2)]
    if bootstrap_std is not None:
        cols += [Column("σ bootstrap", digits=3), Column("σr bootstrap", "%", decimals=2),
                 Column("bootstrap / eq. 13", digits=3)]
    rows = []
    for k, p in enumerate(parameters):
        value, std, rel = number(p.get("value")), number(p.get("std")), p.get("rel_std_pct")
        rel_cell = Cell(float("inf") if rel is None and value == 0 else rel,
                        mark(rel, WEAK_REL_STD_PCT, 10 * WEAK_REL_STD_PCT))
        row: list[Any] = [p["name"], unit(p["name"])]
        if a_priori is not None:
            row.append(a_priori.get(p["name"]))
        row += [value, std, rel_cell]
        if bootstrap_std is not None:
            b = number(bootstrap_std[k])
            row += [b, None if b is None or not value else 100 * b / abs(value),
                    None if b is None or not std else b / std]
        rows.append(tuple(row))
    note = (f"σr marked ! above {WEAK_REL_STD_PCT:g} % (weakly identified), ✗ above {10 * WEAK_REL_STD_PCT:g} %. "
            "σ in the unit of the estimate. Click a header to sort.")
    return Table(table_id, caption, tuple(cols), tuple(rows), note)


def body(standard: Mapping[str, float], j: int) -> tuple[float, np.ndarray, np.ndarray] | None:
    """Mass [kg], centre of mass in frame j [m] and principal inertias about it [kg·m²] of link j
    (None when a parameter is missing; centre NaN for a non-positive mass)."""
    try:
        rigid = RigidBody.from_vector(np.array([float(standard[f"{s}{j}"]) for s in
                                                ("XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M")]))
    except KeyError:
        return None
    if rigid.m <= 0:
        return rigid.m, np.full(3, np.nan), np.sort(np.linalg.eigvalsh(rigid.J))
    c, inertia = rigid.com_inertia()
    return rigid.m, c, np.sort(np.linalg.eigvalsh(inertia))


def bodies_table(standard: Mapping[str, float], n: int, prior: Mapping[str, float] | None = None) -> Table:
    """Per link: mass, centre of mass, principal inertias; the prior's on the next row when given."""
    cols = (Column("link", decimals=0), Column("values", text=True), Column("mass", "kg"),
            Column("CoG x", "m", digits=3), Column("CoG y", "m", digits=3), Column("CoG z", "m", digits=3),
            Column("I₁", "kg·m²", digits=3), Column("I₂", "kg·m²", digits=3), Column("I₃", "kg·m²", digits=3))
    rows = []
    for j in range(1, n + 1):
        for label, params in (("identified", standard), ("prior", prior)):
            b = body(params, j) if params is not None else None
            if b is not None:
                rows.append((j, label, b[0], *b[1], *b[2]))
    return Table("bodies", "Bodies of the consistent fit" + (" beside the prior" if prior is not None else ""),
                 cols, tuple(rows), "Centre of mass in the link's frame (Khalil); principal inertias about the "
                 "centre of mass, ascending. A link the data do not see keeps what the constraints allow.")


def validation_table(validation: Mapping[str, Any], table_id: str = "validation") -> Table:
    """The whole held-out record per joint, against the raw measured torques: RMS and relative error,
    all samples and while moving; beside them the two yardsticks' RMS on the same samples (the plain OLS
    baseline, the model the user had: those the fit file has), the ratio to the better one and whether
    the toolkit beats both."""
    keys = ("rms_error", "relative_error_pct", "rms_error_moving", "relative_error_pct_moving")
    cols = (Column("joint", decimals=0), Column("RMS all", "N·m", digits=3), Column("relative all", "%", decimals=2),
            Column("RMS moving", "N·m", digits=3), Column("relative moving", "%", decimals=2),
            Column("moving", "%", decimals=1))
    n = len(validation.get("rms_error") or [])
    lists = [validation.get(k) or [None] * n for k in keys]
    share = validation.get("moving_fraction") or [None] * n
    rows = tuple((j + 1, lists[0][j], Cell(lists[1][j], mark(lists[1][j])), lists[2][j],
                  Cell(lists[3][j], mark(lists[3][j])), None if share[j] is None else 100 * share[j])
                 for j in range(n))
    sticks = [(label, validation.get(f"{key}_rms_error"), validation.get(f"{key}_rms_error_moving"))
              for label, key in (("plain OLS", "baseline"), ("user model", "user_model"))
              if validation.get(f"{key}_rms_error")]
    for label, every, moving in sticks:
        cols += (Column(f"{label} RMS all", "N·m", digits=3), Column(f"{label} RMS moving", "N·m", digits=3))
        rows = tuple(row + (every[j], (moving or [None] * n)[j]) for j, row in enumerate(rows))
    ratio, better = validation.get("yardstick_ratio"), validation.get("better_yardstick")
    ratio_m = validation.get("yardstick_ratio_moving") or [None] * n
    if sticks and ratio and better:
        cols += (Column("ratio to the better yardstick, all", digits=3),
                 Column("ratio to the better yardstick, moving", digits=3), Column("beats both", text=True))
        rows = tuple(row + (Cell(ratio[j], "" if ratio[j] is None or ratio[j] <= 1 else "check", better[j]),
                            ratio_m[j], Cell("yes" if _beats(ratio[j]) else "no", "" if _beats(ratio[j]) else "check"))
                     for j, row in enumerate(rows))
    thr = validation.get("moving_threshold")
    note = (f"Against the raw measured torques (the prediction interpolated onto the recording's time stamps). "
            f"Filtering of the fit: cut-off {number(validation.get('cutoff_hz')):.4g} Hz, rate "
            f"{number(validation.get('rate_hz')):.4g} Hz; moving: |q̇j| ≥ {thr:g} rad/s." if thr is not None
            and number(validation.get("cutoff_hz")) is not None else "")
    if sticks:
        note += (" Yardsticks, fitted on the same recordings (q by a zero-phase 10 Hz Butterworth, numpy.gradient, "
                 "viscous, Coulomb and offset per joint by least squares) and scored on the same samples: the plain "
                 "OLS (the rigid bodies fitted too) and the model the user had (the description's rigid bodies as "
                 "written). " + " ".join(_verdicts(validation, n, len(sticks))))
    if validation.get("user_model_note") and sticks:
        note += f" The model the user had: not computed ({validation['user_model_note']})."
    return Table(table_id, f"Held-out validation on {validation.get('source', '')}", cols, rows, note.strip())


def estimates_table(validation: Mapping[str, Any], estimates: Mapping[str, Any]) -> Table:
    """The held-out RMS per joint of the fit's (W)LS estimates (``estimates``: the fit file's
    ``validation_result``) beside the identified model's (``validation``), all samples and while moving,
    and their ratio (model / estimates)."""
    n = len(validation.get("rms_error") or [])
    cols = (Column("joint", decimals=0), Column("estimates, all", "N·m", digits=3), Column("model, all", "N·m", digits=3),
            Column("model / estimates, all", digits=3), Column("estimates, moving", "N·m", digits=3),
            Column("model, moving", "N·m", digits=3), Column("model / estimates, moving", digits=3))

    def ratio(a: Any, b: Any) -> Any:
        return None if number(a) is None or not number(b) else number(a) / number(b)

    rows = []
    for j in range(n):
        pairs = [((estimates.get(k) or [None] * n)[j], (validation.get(k) or [None] * n)[j])
                 for k in ("rms_error", "rms_error_moving")]
        rows.append((j + 1, *(v for ls, model in pairs for v in (ls, model, ratio(model, ls)))))
    return Table("estimates-model", "Held out: the paper's estimates beside the identified model", cols, tuple(rows),
                 "The fit's (weighted) least-squares estimates (base parameters, eq. 13's σ) and the identified model "
                 "(physically consistent, the description weighed by the data: what predict, export and the payload "
                 "methods use), scored on the same raw samples.")


def _beats(ratio: Any) -> bool:
    return ratio is not None and ratio <= 1.0


def _verdicts(validation: Mapping[str, Any], n: int, count: int) -> list[str]:
    """"Beats both on joints …" on all samples and while moving, with the better yardstick and the ratio
    where it does not (from the JSON's yardstick_ratio[_moving] and better_yardstick[_moving])."""
    out = []
    for suffix, label in (("", "on all samples"), ("_moving", "while moving")):
        ratio, better = validation.get(f"yardstick_ratio{suffix}"), validation.get(f"better_yardstick{suffix}")
        if not ratio or not better:
            continue
        won = [str(j + 1) for j in range(n) if _beats(ratio[j])]
        lost = [f"{j + 1} ({better[j]} {ratio[j]:.3f}×)" for j in range(n) if ratio[j] is not None and ratio[j] > 1]
        out.append(f"Beats {'both' if count == 2 else 'the plain OLS'} {label} on joints {', '.join(won) or 'none'}"
                   + (f"; not on joints {', '.join(lost)}." if lost else "."))
    return out


def gains_table(gains: Mapping[str, Any], table_id: str = "gains") -> Table:
    """Drive gains per motor: value, σ, σr (total and least-squares part) marked, fixed/flagged."""
    k = gains.get("gains") or []
    std = gains.get("std") or [None] * len(k)
    rel = gains.get("rel_std_pct") or [None if s is None or not g else 100 * s / abs(g) for g, s in zip(k, std)]
    rel_ls = gains.get("rel_std_ls_pct") or [None] * len(k)
    flagged, fixed = set(gains.get("flagged") or ()), set(gains.get("fixed") or ())
    offsets = gains.get("current_offsets") or [None] * len(k)
    rows = tuple((j, g, s, Cell(r, "poor" if j in flagged else ""), rl, o,
                  "fixed" if j in fixed else "flagged" if j in flagged else "")
                 for j, (g, s, r, rl, o) in enumerate(zip(k, std, rel, rel_ls, offsets), start=1))
    side = gains.get("side", "joint")
    cols = (Column("motor" if side == "motor" else "joint", decimals=0), Column("gain", "N·m/A", digits=5),
            Column("σ", "N·m/A", digits=3), Column("σr", "%", decimals=2), Column("σr LS", "%", decimals=2),
            Column("current offset", "A", digits=3), Column("note", text=True))
    return Table(table_id, f"Drive gains ({side} side, τ = Rt·diag(k)·(i − i₀))", cols, rows)


def key_values(table_id: str, caption: str, items: Sequence[tuple[str, str, Any]]) -> Table:
    """A two-column table of settings: (name, unit, value); numbers formatted, text as it is."""
    rows = tuple((name if not u else f"{name} [{u}]", value) for name, u, value in items)
    return Table(table_id, caption, (Column("setting", text=True), Column("value", text=True)),
                 tuple((r[0], _text(r[1])) for r in rows))


def _text(value: Any) -> str:
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, (int, float)) or value is None:
        return fmt(value, 4)
    if isinstance(value, (list, tuple)):
        return ", ".join(_text(v) for v in value)
    return str(value)
