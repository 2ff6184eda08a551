"""Drive gains: the roles of the runs checked, and the two methods compared joint by joint.

- **Swapped runs.** With the payload in the runs given as empty, both methods return the gains
  with their sign reversed (the known mass pulls the other way: the payload's identified mass is
  positive only with the runs the right way round). :func:`swapped_runs_error` confirms it by
  fitting the runs swapped: the loaded runs are those for which most gains come out positive
  (with the global method, unless the robot's viscous friction is positive as given: then every
  current is logged with its sign reversed, which also flips every gain).
- **Same-motion against global.** The two methods estimate the same gains from the same runs by
  different routes (the robot's own dynamics cancelled or identified). :func:`compare_methods`
  gives, per joint, ``z = |k_a − k_b| / sqrt(σ_a² + σ_b²)`` with each σ the method's own
  (the larger of eq. 13's and the segment bootstrap's) **without** the weighing error, which scales
  both methods' gains alike; the methods agree on a joint when ``z <= AGREE_SIGMAS``. The σ are
  taken as independent although both fits see the same currents: the test is, if anything, lenient.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Callable, Sequence

import numpy as np

from identify.fitting.plausibility import Flag, PlausibilityError

if TYPE_CHECKING:  # for annotations only
    from identify.gains.drive_gains import DriveGainsResult
    from identify.estimation.results import IdentificationResult

__all__ = ["AGREE_SIGMAS", "GainComparison", "compare_methods", "swapped_runs_error"]

#: Two methods' gains agree on a joint when they differ by at most this many combined σ.
AGREE_SIGMAS = 2.0


@dataclass(frozen=True)
class GainComparison:
    """Per joint: the gains of two methods, their σ without the weighing error, z and the verdict.

    methods: the two method names; gains, std: (2, n), N·m/A; z: (n,) (nan for a fixed gain);
    agree: (n,) bool (True for a fixed gain); sigmas: the threshold on z.
    """

    methods: tuple[str, str]
    gains: np.ndarray
    std: np.ndarray
    z: np.ndarray
    agree: np.ndarray
    sigmas: float = AGREE_SIGMAS

    def table(self) -> str:
        a, b = self.methods
        lines = [f"Methods compared (σ without the weighing error, common to both; agree: within {self.sigmas:g} σ)",
                 f"{'joint':>5s} {a:>18s} {b:>18s} {'z':>6s}  verdict"]
        for j in range(self.gains.shape[1]):
            cells = [f"{self.gains[m, j]:.5g} ± {self.std[m, j]:.2g}" for m in (0, 1)]
            verdict = ("fixed" if not np.isfinite(self.z[j]) else
                       "agree" if self.agree[j] else f"DISAGREE (> {self.sigmas:g} σ)")
            lines.append(f"{j + 1:5d} {cells[0]:>18s} {cells[1]:>18s} {self.z[j]:6.2f}  {verdict}")
        off = [j + 1 for j in range(self.gains.shape[1]) if not self.agree[j]]
        lines.append(f"the methods agree within {self.sigmas:g} σ on every joint" if not off else
                     f"the methods disagree on joint{'s' if len(off) > 1 else ''} {', '.join(map(str, off))}: "
                     f"their assumptions differ there (same-motion: friction and dynamics unchanged by the load; "
                     f"global: the robot's model complete)")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        return {"methods": list(self.methods), "gains": self.gains.tolist(),
                "std_without_mass": self.std.tolist(),
                "z": [None if not np.isfinite(z) else float(z) for z in self.z],
                "agree": [bool(x) for x in self.agree], "sigmas": self.sigmas}


def _std_without_mass(res: "DriveGainsResult") -> np.ndarray:
    """σ of each gain (N·m/A) without the weighing error: the larger of eq. 13's and the bootstrap's."""
    rel = res.rel_std_ls_pct if res.rel_std_boot_pct is None else np.fmax(res.rel_std_ls_pct, res.rel_std_boot_pct)
    return np.abs(res.gains.gains) * rel / 100.0


def compare_methods(a: "DriveGainsResult", b: "DriveGainsResult", sigmas: float = AGREE_SIGMAS) -> GainComparison:
    """The per-joint verdict of two results on the same runs (module docstring)."""
    if a.gains.side != b.gains.side or a.gains.gains.size != b.gains.gains.size:
        raise ValueError(f"compare_methods: {a.method} and {b.method} gains are not on the same side or robot")
    gains = np.vstack([a.gains.gains, b.gains.gains])
    std = np.vstack([_std_without_mass(a), _std_without_mass(b)])
    with np.errstate(invalid="ignore", divide="ignore"):
        z = np.abs(gains[0] - gains[1]) / np.hypot(std[0], std[1])
    z = np.where(np.isfinite(std).all(axis=0), z, np.nan)  # a fixed gain: nothing to compare
    agree = ~(z > sigmas)
    return GainComparison((a.method, b.method), gains, std, z, agree, float(sigmas))


def _viscous(robot_fit: "IdentificationResult | None") -> dict[str, float]:
    """The robot's viscous friction coefficients FVj identified by the global method (N·m·s/rad)."""
    if robot_fit is None:
        return {}
    return {n: float(v) for n, v in zip(robot_fit.names, robot_fit.values) if n.startswith("FV")}


def swapped_runs_error(error: PlausibilityError, swapped: Callable[[], "DriveGainsResult"],
                       empty: Sequence[str], loaded: Sequence[str],
                       robot_fit: "IdentificationResult | None" = None) -> PlausibilityError:
    """The refusal of gains that came out mostly negative: "runs swapped" when the fit of the runs
    swapped (``swapped()``) gives mostly positive gains, else ``error`` with what the swap gave.

    Swapped runs and currents all logged with their sign reversed both flip every gain; the global
    method tells them apart by the robot's own parameters (``robot_fit``), whose sign follows the
    gains' only for swapped runs: with the viscous friction FVj mostly positive as given, the runs
    are not swapped (the currents are reversed). Same-motion cannot tell (the robot cancels out).

    empty, loaded: the sources of the runs as given, named by the message.
    """
    original = next(f for f in error.flags if f.code == "gains_negative")
    fv = _viscous(robot_fit)
    if fv and sum(v > 0 for v in fv.values()) > len(fv) / 2:
        shown = ", ".join(f"{n} {v:.3g}" for n, v in fv.items())
        return PlausibilityError([replace(original, action=(
            f"the runs are not swapped: with them as given the robot's viscous friction is positive ({shown}); "
            f"the currents are logged with the sign opposite to the torques: negate them"))])
    try:
        k = swapped().gains.gains
        shown = f" ({', '.join(f'{v:.4g}' for v in k)} N m/A)"
    except PlausibilityError as exc:
        if any(f.code == "gains_negative" for f in exc.flags):
            k = -np.ones(1)
        else:  # mostly positive, another gain refused (e.g. one not identified): the swap is confirmed
            k, shown = np.ones(1), f" (but {exc.flags[0].message})"
    except (ValueError, np.linalg.LinAlgError) as exc:  # the swapped fit fails: no confirmation
        return PlausibilityError([replace(original, action=original.action + f" (the runs swapped could not be fitted: "
                                                                        f"{str(exc).splitlines()[0]})")])
    if np.sum(k > 0) > k.size / 2:
        flag = Flag("runs_swapped", "error",
                    f"empty and loaded runs swapped: the payload is in {', '.join(empty)} (given as --empty), not in "
                    f"{', '.join(loaded)} (given as --loaded): as given, {original.message}; with the runs swapped "
                    f"the gains come out positive{shown}, the payload's known mass adding torque",
                    "swap --empty and --loaded")
        return PlausibilityError([flag])
    return PlausibilityError([replace(original, action="check the sign of the currents: with --empty and --loaded "
                                                       "swapped the gains are mostly negative too")])
