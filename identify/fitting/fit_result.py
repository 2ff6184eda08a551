"""A fit and its file: :class:`Fit` predicts and validates with its own processing, bootstraps
its σ and saves itself; :func:`load_fit` reads the file back with its robot, gains and processing
(:func:`identify.fit` makes one)."""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Sequence

import numpy as np

import rx90sym
from rx90sym.files import write_json
from rx90sym.threads import one_blas_thread

from identify.estimation.bootstrap import BLOCK_S, DRAWS, segment_bootstrap_std
from identify.fitting.consistent_fit import ConsistentResult
from identify.fitting.plausibility import Flag
from identify.estimation.results import IdentificationResult, json_number
from identify.fitting.fit_file import FitModel, SCHEMA_VERSION, gains_of, read_fit_file, robot_of
from identify.io.gains import DriveGains
from identify.friction.columns import friction_base
from identify.observation.matrix import Observation
from identify.observation.rest import coulomb_terms
from identify.observation.processing import Processing
from identify.observation.rest import defaulted_travels
from identify.estimation.delay import DelayEstimate
from identify.fitting.validation import Validation, predict
from identify.io.blocks import DEFAULT_BLOCK
from identify.fitting.baseline import PlainBaseline
from identify.fitting.user_model import UserModel, not_computed
from identify.observation.offsets import offset_base


__all__ = ["BOOTSTRAP_BLOCK_S", "BOOTSTRAP_DRAWS", "Bootstrap", "Fit", "load_fit"]

#: Segment bootstrap: block length [s] and number of draws (the library's one bootstrap).
BOOTSTRAP_BLOCK_S = BLOCK_S
BOOTSTRAP_DRAWS = DRAWS


@dataclass(frozen=True, eq=False)
class Bootstrap:
    """Segment-bootstrap σ of each estimate: std (per parameter, its unit), block_s [s], draws, seed; names:
    the parameters they are the σ of (the least-squares estimates'; empty: the result's, in its order)."""

    std: np.ndarray
    block_s: float
    draws: int
    seed: int
    names: tuple[str, ...] = ()

    def of(self, names: Sequence[str]) -> np.ndarray:
        """σ of the parameters ``names`` (NaN for one the bootstrap did not draw: a column only the
        identified model has)."""
        if not self.names:
            return self.std
        by_name = dict(zip(self.names, self.std))
        return np.array([by_name.get(n, np.nan) for n in names])

    def to_json(self) -> dict[str, Any]:
        # A column the draws could not estimate (NaN) is null in the file, NaN again when read.
        return {"bootstrap_std": [json_number(v) for v in self.std],
                "bootstrap": {"block_s": self.block_s, "draws": self.draws, "seed": self.seed}}

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> "Bootstrap | None":
        if d.get("bootstrap_std") is None:
            return None
        b = d["bootstrap"]
        std = np.array([np.nan if v is None else v for v in d["bootstrap_std"]], dtype=float)
        return cls(std, float(b["block_s"]), int(b["draws"]),
                   int(b["seed"]))

    def table(self, res: IdentificationResult) -> str:
        """σ of eq. 13 (white residuals) beside the segment-bootstrap σ, per parameter."""
        width = max([len("Parameter")] + [len(n) for n in res.names])
        lines = [f"{'Parameter':<{width}}  {'σ eq. 13':>10}  {'σ bootstrap':>11}  ratio"]
        for n, s, b in zip(res.names, res.std, self.of(res.names)):
            ratio = b / s if s > 0 else float("nan")
            lines.append(f"{n:<{width}}  {s:10.3g}  {b:11.3g}  {ratio:5.2f}")
        return "\n".join(lines)


@dataclass(frozen=True, eq=False)
class Fit:
    """One identification with what it was run with.

    robot: the description fitted; result: the estimates; processing: as asked (cut-off None:
    automatic); model: the robot record and the achieved processing (cut-off used, rate, delay);
    base: the base parameters (columns) used; observation: W, Y and notes (None when loaded);
    delay_estimate: the lag search (None when not run or loaded); delay_estimate_s [s];
    spring: how the spring entered (JSON entry); bootstrap, essential, validation: None until
    asked (:meth:`bootstrapped`, :meth:`with_essential`, :meth:`validated`); flags: the
    plausibility warnings of the fit (identify.fitting.plausibility, :meth:`with_flags`); recordings: per
    recording its samples, segments, samples bridged over lost packets and stale rows dropped
    (:func:`identify.io.recordings.layout_summary`); choice: the cross-validated processing's
    candidate table (:meth:`ProcessingChoice.to_dict`), None when the processing was given;
    identified: the identified model — physically consistent bodies weighed between the description and
    the data (:func:`identify.fitting.consistent_fit.consistent_fit`) — which predicts, exports and
    monitors (``result`` keeps the paper's (W)LS estimates and σ unless the method was "consistent").
    """

    robot: rx90sym.Robot
    result: IdentificationResult
    processing: Processing
    model: FitModel
    base: Any
    observation: Observation | None = None
    delay_estimate: DelayEstimate | None = None
    delay_estimate_s: float | None = None
    spring: dict | None = None
    bootstrap: Bootstrap | None = None
    essential: IdentificationResult | None = None
    validation: Validation | None = None
    flags: tuple[Flag, ...] = ()
    recordings: tuple[dict, ...] = ()
    choice: dict | None = None
    block: int | None = None        # logs read block by block with this many samples (None: whole)
    passes: Any = None              # what the passes over the logs read, chose and fitted (identify.fitting.passes.Passes)
    baseline: Any = None            # the plain OLS baseline (identify.fitting.baseline.PlainBaseline) or None
    user_model: Any = None          # the model the user had (identify.fitting.user_model.UserModel) or None
    user_model_note: str = ""       # why there is no model the user had ("" when there is)
    contact_thresholds: np.ndarray | None = None  # contact monitor's per joint [N·m] (identify.monitor)
    identified: ConsistentResult | None = None  # the identified model (identify.fitting.consistent_fit)
    result_validation: Validation | None = None  # the (W)LS estimates' own validation, beside the model's
    ls_result: IdentificationResult | None = None  # the (W)LS estimates when the result is the model (consistent)

    # ------------------------------------------------------------ what the fit used
    @property
    def delay(self) -> float:
        return self.model.delay_s

    @property
    def cutoff(self) -> float:
        return self.model.cutoff_hz

    @property
    def decimate_to(self) -> float | None:
        return self.model.decimate_to_hz

    @property
    def min_velocity(self) -> float | None:
        return self.model.min_velocity

    @property
    def rest(self) -> str | tuple[str, ...]:
        return self.model.rest

    @property
    def gains(self) -> DriveGains | None:
        return gains_of(self.model)

    @property
    def least_squares(self) -> IdentificationResult:
        """The paper's (weighted) least-squares estimates with eq. 13's σ (the result, unless the method
        was "consistent")."""
        return self.ls_result if self.ls_result is not None else self.result

    @property
    def model_result(self) -> IdentificationResult:
        """What predicts, exports and monitors: the identified model (the (W)LS result without one)."""
        return self.identified if self.identified is not None else self.result

    def columns_of(self, result: IdentificationResult) -> Any:
        """The columns of ``result``: the fit's, with the torque offsets its identified model adds."""
        names = set(self.base.names)
        added = [int(n[3:]) - 1 for n in result.names if n.startswith("OFF") and n[3:].isdigit() and n not in names]
        return offset_base(self.base, added)

    def filtering(self, spring: bool | None = None) -> dict[str, Any]:
        """Keyword arguments of :func:`identify.predict` that reuse this fit's processing."""
        return {"cutoff": self.cutoff, "decimate_to": self.decimate_to, "min_velocity": self.min_velocity,
                "delay": self.delay, "spring": self.processing.spring if spring is None else spring,
                "rest": self.rest}

    # ------------------------------------------------------------ using it
    def predict(self, recording: Any, result: IdentificationResult | None = None, *, block: int | None = None,
                convention: str | None = None, rollout: Any = None) -> Validation:
        """Torques of ``recording`` (a recording, or a recording file read block by block: ``block`` raw
        samples at a time, default the fit's, its angles ``convention``, default the fit's) predicted with
        this fit's identified model (:attr:`model_result`; or ``result``) and processing. Where a joint rests the Coulomb term is 0,
        or the presliding state with that rest policy (every sample is predicted, whatever the rest
        policy). rollout: window lengths [s] ("0.25,0.5" or numbers): the fit's own model, as ``rx90
        export --mjcf`` writes it, also rolled out in MuJoCo (identify.rollout.run.roll_out_fit; the
        validation's ``rollout``). A joint whose torque the fit left out is not predicted (NaN, said)."""
        # At 20 x the cut-off (identify.fitting.validation.prediction_rate), not at the fit's decimated rate.
        options = dict(self.filtering(), decimate_to="prediction", filtered_at=self.decimate_to)
        block = block if block is not None else (self.block or DEFAULT_BLOCK)
        convention = convention or self.model.convention
        simulated = None
        if rollout is not None:  # first: a window the recording cannot hold is refused before the prediction
            from identify.rollout.run import roll_out_fit

            simulated = roll_out_fit(self, recording, rollout, block=block, convention=convention)
        result = result or self.model_result
        val = predict(self.robot, result, recording, base=self.columns_of(result), baseline=self.baseline,
                      user_model=self.user_model, user_model_note=self.user_model_note,
                      block=block, convention=convention, gains=self.gains, **options)
        # A joint whose torque the fit left out (constant: not logged) is not predicted (Validation.without_joints).
        val = val.without_joints(self.model.torque_left_out) if self.model.torque_left_out else val
        return val if simulated is None else replace(val, rollout=simulated)

    def validate(self, recording: Any, rollout: Any = None) -> Validation:
        """Cross-validation on a recording not used in the fit (with the essential parameters when
        they were computed); rollout: as :meth:`predict`."""
        return self.predict(recording, self.essential, rollout=rollout)

    def validated(self, recording: Any, rollout: Any = None) -> "Fit":
        """This fit with its validation on ``recording`` recorded (saved in the file): the identified
        model's (what predicts), and beside it the (W)LS estimates' when they are not the model;
        rollout: as :meth:`predict`."""
        ls = self.predict(recording, self.result) if self.result is not self.model_result else None
        return replace(self, validation=self.validate(recording, rollout), result_validation=ls)

    def with_flags(self, flags: Sequence[Flag]) -> "Fit":
        """This fit with its plausibility flags recorded (saved in the file's ``flags``)."""
        return replace(self, flags=tuple(flags))

    @one_blas_thread()
    def with_essential(self) -> "Fit":
        """This fit with its essential parameters (eqs. 16-17) computed."""
        from identify.estimation.essential import essential_parameters

        return replace(self, essential=essential_parameters(self.least_squares))

    @one_blas_thread()
    def bootstrapped(self, seed: int = 0, draws: int = BOOTSTRAP_DRAWS, block_s: float = BOOTSTRAP_BLOCK_S) -> "Fit":
        """This fit with the segment-bootstrap σ of each estimate (blocks of ``block_s`` s)."""
        obs = self.observation
        done = self.bootstrap
        same = done is not None and (done.seed, done.draws) == (seed, draws)
        if same and (self.passes is not None or (obs is not None and
                                                   done.block_s == max(1, int(round(block_s * obs.rate))) / obs.rate)):
            return self  # computed already: by fit(), or while the blocks went by (fit(..., block=...))
        if obs is None:
            raise ValueError("bootstrap needs the fit's observation matrix (not a fit loaded from a file; "
                             "a fit in blocks computes it while it reads them: fit(..., bootstrap_seed=...))")
        block = max(1, int(round(block_s * obs.rate)))
        ls = self.least_squares
        std = segment_bootstrap_std(obs.W, obs.Y, obs.joint, obs.samples, ls.weights, block, draws, seed)
        return replace(self, bootstrap=Bootstrap(std, block / obs.rate, draws, seed, tuple(ls.names)))

    # ------------------------------------------------------------ the file
    def to_json(self) -> dict[str, Any]:
        """The fit file's content (every schema's keys: identify.fitting.fit_file)."""
        out = {"robot": self.model.robot, "method": self.result.method, **self.result.to_dict(),
               "spring": self.spring}
        if self.bootstrap is not None:  # in the result's order
            out.update(replace(self.bootstrap, std=self.bootstrap.of(self.result.names), names=()).to_json())
        out.update({"cutoff_hz": self.model.cutoff_hz, "decimate_to_hz": self.model.decimate_to_hz,
                    "delay_estimate_s": self.delay_estimate_s, "model": self.model.to_json(),
                    "essential": self.essential.to_dict() if self.essential is not None else {},
                    "validation": self.validation.to_dict() if self.validation is not None else {},
                    "validation_result": (self.result_validation.to_dict() if self.result_validation is not None
                                          else None),
                    "schema_version": SCHEMA_VERSION, "processing": self.processing.to_json(),
                    "flags": [f.to_json() for f in self.flags], "recordings": list(self.recordings),
                    "processing_choice": self.choice,
                    "baseline": self.baseline.to_json() if self.baseline is not None else None,
                    "user_model": (self.user_model.to_json() if self.user_model is not None
                                   else not_computed(self.user_model_note) if self.user_model_note else None),
                    "contact_thresholds_nm": (None if self.contact_thresholds is None
                                              else [float(v) for v in self.contact_thresholds]),
                    "identified": self.identified.to_dict() if self.identified is not None else None})
        return out

    def save(self, path: str | Path) -> Path:
        """Write the fit file atomically (nothing written on error). Returns the path."""
        return write_json(path, self.to_json())

    @classmethod
    def load(cls, path: str | Path, robot: rx90sym.Robot | str | None = None) -> "Fit":
        """The fit saved in ``path``, with its robot (rebuilt from its file, or ``robot``: a
        description, name or file), gains and processing. It predicts; it cannot be refitted."""
        data = read_fit_file(path)
        try:
            model = FitModel.from_json(data["model"], str(path))
            processing = Processing.from_json(data.get("processing", {}), f"{path}: processing")
            consistent = data.get("method") == "consistent" and isinstance(data.get("standard"), dict)
            result = (ConsistentResult if consistent else IdentificationResult).from_dict(data)
            essential = IdentificationResult.from_dict(data["essential"]) if data.get("essential") else None
            bootstrap = Bootstrap.from_json(data)
            flags = tuple(Flag.from_json(f) for f in data.get("flags", []))
            baseline = PlainBaseline.from_json(data.get("baseline"))  # None in older files
            identified = (ConsistentResult.from_dict(data["identified"]) if isinstance(data.get("identified"), dict)
                          else result if isinstance(result, ConsistentResult) else None)
            user, note = UserModel.from_json(data.get("user_model"))  # None in files of schema 4 and older
        except (KeyError, TypeError, ValueError) as exc:
            raise ValueError(f"{path}: {exc}".replace(f"{path}: {path}: ", f"{path}: ")) from None
        rob = robot if isinstance(robot, rx90sym.Robot) else robot_of(model, robot)
        # FS+ / FS- columns in the result: the fit used asymmetric Coulomb friction on those joints.
        asymmetric = tuple(j for j in range(rob.n) if f"FSP{j + 1}" in result.names)
        if asymmetric != tuple(rob.asymmetric_coulomb):
            rob = rob.with_options(asymmetric_coulomb=asymmetric)
        base = offset_base(rx90sym.base_parameters(rob), [j - 1 for j in model.offset_joints or ()])
        if model.friction is not None:  # the friction columns found: smooth form's scales, presliding travels
            fr = model.friction
            scales = [np.nan if v is None else v for v in fr["velocity_scale"]] if "velocity_scale" in fr else None
            travels = defaulted_travels(fr["presliding_travel"]) if "presliding_travel" in fr else None
            base = friction_base(base, coulomb_terms(rob, base.names), fr["form"], scales,
                                 presliding=travels is not None, travels=travels)
        return cls(rob, result, processing, model, base,
                   delay_estimate_s=data.get("delay_estimate_s"), spring=data.get("spring"),
                   bootstrap=bootstrap, essential=essential, flags=flags,
                   recordings=tuple(data.get("recordings", [])), choice=data.get("processing_choice"),
                   baseline=baseline, user_model=user, user_model_note=note,
                   contact_thresholds=(None if data.get("contact_thresholds_nm") is None
                                       else np.asarray(data["contact_thresholds_nm"], dtype=float)),
                   identified=identified)


def load_fit(path: str | Path, robot: rx90sym.Robot | str | None = None) -> Fit:
    """Read a fit file (:meth:`Fit.save`, ``rx90 identify --json``): see :meth:`Fit.load`."""
    return Fit.load(path, robot)
