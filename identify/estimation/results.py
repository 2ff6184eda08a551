"""Identification results: estimates, their statistics (eqs. 12–15) and the paper's Table 3 layout."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rx90sym.files import read_json
from rx90sym.recording import frozen_array

from identify.estimation.compression import CompressedSystem

__all__ = ["METHODS", "EliminationStep", "IdentificationResult"]

#: The estimators a fit can use: ordinary, weighted (eqs. 9-15) and physically consistent least squares.
METHODS = ("ols", "wls", "consistent")


def _frozen_array(a: Any, name: str, shape: tuple[int, ...] | None = None) -> np.ndarray:
    out = frozen_array(a)
    if shape is not None and out.shape != shape:
        raise ValueError(f"IdentificationResult.{name} must have shape {shape}, got {out.shape}")
    return out


def json_number(v: float) -> float | None:
    """JSON has no inf/NaN: they become null."""
    v = float(v)
    return v if math.isfinite(v) else None


def _number(v: float | None, missing: float) -> float:
    return missing if v is None else float(v)


@dataclass(frozen=True)
class EliminationStep:
    """One trial of the essential-parameter procedure (§II-B, end).

    Attributes:
        removed: parameter removed in this trial.
        sigma_pe: residual standard deviation of the reduced model (eq. 12 with r − c_k),
            units of the solved (weighted) system.
        ratio: sigma_pe / σρ0 of the full base-parameter model.
        parameters_left: number of parameters after the removal.
        accepted: False for the trial that reached the threshold (the procedure stops there and
            keeps the previous set).
    """

    removed: str
    sigma_pe: float
    ratio: float
    parameters_left: int
    accepted: bool

    def to_dict(self) -> dict[str, Any]:
        return {
            "removed": self.removed,
            "sigma_pe": json_number(self.sigma_pe),
            "ratio": json_number(self.ratio),
            "parameters_left": self.parameters_left,
            "accepted": self.accepted,
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "EliminationStep":
        return cls(
            removed=str(d["removed"]),
            sigma_pe=_number(d["sigma_pe"], math.nan),
            ratio=_number(d["ratio"], math.nan),
            parameters_left=int(d["parameters_left"]),
            accepted=bool(d["accepted"]),
        )


@dataclass(frozen=True, eq=False)
class IdentificationResult:
    """Estimated parameters and their statistics.

    Attributes:
        names: (c,) parameter names.
        values: (c,) estimates χ̂ (SI units of each parameter).
        std: (c,) standard deviations σ (eq. 14), same units.
        rel_std_pct: (c,) relative standard deviations 100·σ/|χ̂| (eq. 15), inf when χ̂ = 0.
        sigma_rho: residual standard deviation σρ of the solved system (eq. 12); for WLS the
            system is weighted, so σρ is dimensionless and close to 1.
        cond: 2-norm condition number of the W that was solved (weighted for WLS).
        cond_unweighted: condition number of the unweighted W (NaN if unknown).
        residual_rms: (n,) RMS of the unweighted residual per joint, N·m.
        weights: (n,) weight of each joint's equations, 1/(N·m) (ones for OLS).
        rows: number of equations r.
        method: "ols", "wls", "essential", ...
        covariance: (c, c) covariance of the estimates (eq. 13) or None; not in JSON.
        system: the compressed (weighted) system solved, for re-solves without the raw data
            (essential parameters, constrained LS); None when loaded from JSON.
        joint_systems: unweighted compressed system of each joint's rows; () when unknown.
        history: essential-parameter elimination trials, in order.
        holds: (name, what its estimate holds) of the columns that hold others the fitted rows
            cannot separate from them, e.g. ("FS5", "FS5 + OFF5")
            (identify.estimation.dependent_columns); () when none.
    """

    names: tuple[str, ...]
    values: np.ndarray
    std: np.ndarray
    rel_std_pct: np.ndarray
    sigma_rho: float
    cond: float
    cond_unweighted: float
    residual_rms: np.ndarray
    weights: np.ndarray
    rows: int
    method: str
    covariance: np.ndarray | None = field(default=None, repr=False)
    system: CompressedSystem | None = field(default=None, repr=False)
    joint_systems: tuple[CompressedSystem, ...] = field(default=(), repr=False)
    history: tuple[EliminationStep, ...] = ()
    holds: tuple[tuple[str, str], ...] = ()

    def __post_init__(self) -> None:
        names = tuple(str(n) for n in self.names)
        c = len(names)
        if len(set(names)) != c:
            raise ValueError(f"IdentificationResult.names has duplicates: {names}")
        set_ = lambda k, v: object.__setattr__(self, k, v)  # noqa: E731 (frozen dataclass)
        set_("names", names)
        for key in ("values", "std", "rel_std_pct"):
            set_(key, _frozen_array(getattr(self, key), key, (c,)))
        residual_rms = _frozen_array(self.residual_rms, "residual_rms")
        set_("residual_rms", residual_rms)
        set_("weights", _frozen_array(self.weights, "weights", residual_rms.shape))
        if self.covariance is not None:
            set_("covariance", _frozen_array(self.covariance, "covariance", (c, c)))
        for key in ("sigma_rho", "cond", "cond_unweighted"):
            set_(key, float(getattr(self, key)))
        set_("rows", int(self.rows))
        set_("method", str(self.method))
        set_("joint_systems", tuple(self.joint_systems))
        set_("history", tuple(self.history))
        held = dict(self.holds)
        unknown = [k for k in held if k not in names]
        if unknown:
            raise ValueError(f"IdentificationResult.holds names {unknown[0]!r}, not a parameter of the result")
        set_("holds", tuple((str(k), str(v)) for k, v in held.items()))

    # ------------------------------------------------------------------ access

    def __getitem__(self, name: str) -> float:
        """Estimate of a parameter by name."""
        try:
            return float(self.values[self.names.index(name)])
        except ValueError:
            raise KeyError(f"no parameter {name!r} in this result (has {', '.join(self.names)})") from None

    def __contains__(self, name: object) -> bool:
        return name in self.names

    def __len__(self) -> int:
        return len(self.names)

    def as_dict(self) -> dict[str, float]:
        """{name: estimate}."""
        return {n: float(v) for n, v in zip(self.names, self.values)}

    # ------------------------------------------------------------------ JSON

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe dictionary (inf and NaN become None); the compressed systems are omitted. A
        parameter whose column holds others has ``"holds"`` (what its estimate is)."""
        held = dict(self.holds)
        return {
            "method": self.method,
            "parameters": [
                {"name": n, "value": json_number(v), "std": json_number(s), "rel_std_pct": json_number(p),
                 **({"holds": held[n]} if n in held else {})}
                for n, v, s, p in zip(self.names, self.values, self.std, self.rel_std_pct)
            ],
            "sigma_rho": json_number(self.sigma_rho),
            "cond": json_number(self.cond),
            "cond_unweighted": json_number(self.cond_unweighted),
            "residual_rms": [json_number(v) for v in self.residual_rms],
            "weights": [json_number(v) for v in self.weights],
            "rows": self.rows,
            "history": [step.to_dict() for step in self.history],
        }

    def to_json(self, path: str | Path) -> Path:
        """Write :meth:`to_dict` as JSON (strict: no NaN/Infinity tokens). Returns the path."""
        path = Path(path)
        path.write_text(json.dumps(self.to_dict(), indent=2, allow_nan=False) + "\n", encoding="utf-8")
        return path

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "IdentificationResult":
        """Inverse of :meth:`to_dict`. null becomes inf for rel_std_pct and cond, NaN elsewhere.

        The result has no compressed system (it cannot be re-solved).
        """
        try:
            params = d["parameters"]
            return cls(
                names=tuple(p["name"] for p in params),
                values=[_number(p["value"], math.nan) for p in params],
                std=[_number(p["std"], math.nan) for p in params],
                rel_std_pct=[_number(p["rel_std_pct"], math.inf) for p in params],
                sigma_rho=_number(d["sigma_rho"], math.nan),
                cond=_number(d["cond"], math.inf),
                cond_unweighted=_number(d.get("cond_unweighted"), math.nan),
                residual_rms=[_number(v, math.nan) for v in d["residual_rms"]],
                weights=[_number(v, math.nan) for v in d["weights"]],
                rows=int(d["rows"]),
                method=str(d["method"]),
                history=tuple(EliminationStep.from_dict(s) for s in d.get("history", [])),
                holds=tuple((p["name"], str(p["holds"])) for p in params if p.get("holds")),
            )
        except KeyError as err:
            raise ValueError(f"identification result dictionary is missing field {err}") from None

    @classmethod
    def from_json(cls, path: str | Path) -> "IdentificationResult":
        """Read a file written by :meth:`to_json`."""
        path = Path(path)
        data = read_json(path)   # ValueError naming the file (and line, column)
        try:
            return cls.from_dict(data)
        except ValueError as err:
            raise ValueError(f"{path}: {err}") from None

    # ------------------------------------------------------------------ display

    def table(self) -> str:
        """Text table in the layout of the paper's Table 3 (plus 2σ), with a summary footer."""
        width = max([len("Parameter")] + [len(n) for n in self.names])
        lines = [f"{'Parameter':<{width}}  {'Estimate':>12}  {'2σ':>10}  {'σr %':>9}"]
        held = dict(self.holds)
        for n, v, s, p in zip(self.names, self.values, self.std, self.rel_std_pct):
            rel = f"{p:9.3f}" if math.isfinite(p) else f"{'inf':>9}"
            lines.append(f"{n:<{width}}  {v:12.6g}  {2.0 * s:10.3g}  {rel}" + (f"  holds {held[n]}" if n in held else ""))
        lines.append(
            f"method {self.method}, {len(self.names)} parameters, {self.rows} equations, "
            f"σρ = {self.sigma_rho:.4g}, cond(W) = {self.cond:.4g} (unweighted {self.cond_unweighted:.4g})"
        )
        if self.residual_rms.size:
            rms = "  ".join(f"{v:.4g}" for v in self.residual_rms)
            lines.append(f"residual RMS per joint (N·m): {rms}")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.table()
