"""The result of a payload identification (paper section IV): the ten parameters with their
sigma, the a priori values, the robot's estimates, and its table and JSON."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from identify.estimation.results import IdentificationResult, json_number

if TYPE_CHECKING:
    from identify.signal.pairing import PairedRuns

__all__ = ["PayloadResult"]


@dataclass(frozen=True, eq=False)
class PayloadResult:
    """Payload estimate: names XXc..Mc with values, std (eq. 14), rel_std_pct (eq. 15).

    robot: the identified robot base parameters (methods 2 and 4), else None;
    a_priori: reference values (CAD) when given; constrained: whether the PSD/mass constraints
    were imposed; fit: the underlying least-squares result; pairs: method 3's paired runs, one per
    segment (lag, position gap); bootstrap_std: the segment-bootstrap sigma (coloured residuals) beside eq. 13's
    ``std``, or None (method 2).
    """

    method: int
    names: tuple[str, ...]
    values: np.ndarray
    std: np.ndarray
    rel_std_pct: np.ndarray
    fit: IdentificationResult | None = field(default=None, repr=False)
    robot: IdentificationResult | None = field(default=None, repr=False)
    a_priori: dict | None = None
    constrained: bool = False
    pairs: tuple[PairedRuns, ...] = field(default=(), repr=False)
    bootstrap_std: np.ndarray | None = None

    @property
    def std_headline(self) -> np.ndarray:
        """The σ to quote: the larger of eq. 13's and the segment bootstrap's, per parameter (eq.
        13 alone assumes white residuals; the bootstrap sees their colour)."""
        return self.std if self.bootstrap_std is None else np.fmax(self.std, self.bootstrap_std)

    def headline(self) -> str:
        """The mass with ±1σ of :attr:`std_headline`, labelled (which σ it is)."""
        i = self.names.index("Mc")
        if self.constrained:
            return f"Mc = {self.values[i]:.4g} kg (constrained: no σ of its own)"
        which = ("eq. 13" if self.bootstrap_std is None or not self.bootstrap_std[i] > self.std[i]
                 else "segment bootstrap")
        return (f"Mc = {self.values[i]:.4g} ± {self.std_headline[i]:.2g} kg (±1σ, the larger of eq. 13's and the "
                f"bootstrap's: {which}; the noise of these runs only: a drive gain or robot model off by x % moves the "
                f"payload by about as much, which no σ here holds)")

    def __getitem__(self, name: str) -> float:
        return float(self.values[self.names.index(name)])

    def as_dict(self) -> dict[str, float]:
        return {k: float(v) for k, v in zip(self.names, self.values)}

    def to_dict(self) -> dict[str, Any]:
        return {"method": self.method, "constrained": self.constrained,
                "payload": [{"name": n, "value": json_number(v), "std": json_number(s), "rel_std_pct": json_number(p),
                             "bootstrap_std": None if self.bootstrap_std is None else json_number(b),
                             "std_headline": json_number(h)}
                            for n, v, s, p, b, h in zip(self.names, self.values, self.std, self.rel_std_pct,
                                                        self._boot(), self.std_headline)],
                "a_priori": self.a_priori,
                # The robot's base parameters identified with the payload (methods 2 and 4).
                "robot": None if self.robot is None else self.robot.to_dict(),
                "pairing": [p.to_dict() for p in self.pairs]}

    def _boot(self) -> np.ndarray:
        return np.full(len(self.names), np.nan) if self.bootstrap_std is None else self.bootstrap_std

    def table(self) -> str:
        """Like Tables 4-7: Parameter, A priori, Identified, 2 sigma (eq. 13), sigma_r %, and the
        segment bootstrap's 2 sigma."""
        lines = [f"Payload, method {self.method}{' (constrained)' if self.constrained else ''}",
                 f"{'Parameter':10s} {'A priori':>10s} {'Identified':>11s} {'2σ eq.13':>9s} {'σr %':>9s} "
                 f"{'2σ boot':>9s}"]
        if self.robot is not None:
            for n, v, s, p in zip(self.robot.names, self.robot.values, self.robot.std, self.robot.rel_std_pct):
                if n not in self.names:
                    lines.append(f"{n:10s} {'':>10s} {v:11.4g} {2 * s:9.3g} {p:9.3f}")
        for n, v, s, p, b in zip(self.names, self.values, self.std, self.rel_std_pct, self._boot()):
            ap = "" if not self.a_priori or n not in self.a_priori else f"{self.a_priori[n]:.4g}"
            # A constrained estimate has no σ of its own here: eq. 13's and the bootstrap's are the
            # unconstrained fit's.
            spread = (f"{'—':>9s} {'—':>9s} {'—':>9s}" if self.constrained else
                      f"{2 * s:9.3g} {p:9.3f} {2 * b:9.3g}")
            lines.append(f"{n:10s} {ap:>10s} {v:11.4g} {spread}")
        if self.constrained:
            lines.append("no σ is printed for the constrained payload (eq. 13's and the bootstrap's are the "
                         "unconstrained fit's)")
        lines += [p.summary() for p in self.pairs]
        return "\n".join(lines)
