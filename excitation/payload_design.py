"""Excitation for a payload's ten inertial parameters (paper section IV).

The payload (XXc ... Mc) adds to link n's inertial parameters, so its observation matrix Wc is
link n's ten columns of the standard regressor (eq. 21). A motion for the payload optimises the
predicted relative sigma of those ten (criterion "sigma" on Wc, reference magnitudes from a
typical payload, floored per kind: inertias, first moments, mass), with the torque limits of the
robot carrying that payload. The paper's conclusion: about ten via points suffice.

Predicted standard deviations, for noise S = diag(noise_std) per joint and samples counted at
``rate`` (objective.py):
- method 3 (eq. 28, same motion empty and loaded): cov = 2 (Wc^T S^-2 Wc)^-1 (the torque
  difference carries the noise of two runs);
- method 4 (eq. 29, global system of the empty and loaded runs): the payload block of
  [[2 Wb^T S^-2 Wb, Wb^T S^-2 Wc], [Wc^T S^-2 Wb, Wc^T S^-2 Wc]]^-1.
"""
from __future__ import annotations

import dataclasses
from typing import Any

import casadi as ca
import numpy as np

import rx90sym
from rx90sym.parameters import PAYLOAD_NAMES
from rx90sym.payloads import add_payload, as_payload, payload_regressor_columns

from .criterion import regressor_samples, symbols_like
from .model import ExcitationModel, model_from_robot
from .objective import Objective, reference_magnitudes
from .trajectory import sample_times

PAYLOAD_KINDS = tuple("inertia" if n[:2] in ("XX", "XY", "XZ", "YY", "YZ", "ZZ") else
                      "mass" if n == "Mc" else "first moment" for n in PAYLOAD_NAMES)


def payload_regressor(robot: rx90sym.Robot) -> ca.Function:
    """Wc rows: (q, qd, qdd) -> (n x 10), link n's columns of the standard regressor (eq. 21)."""
    cols = [int(c) for c in payload_regressor_columns(robot)]
    f = robot.regressor
    sym = symbols_like(f)
    return ca.Function("payload_regressor", list(sym), [f(*sym)[:, cols]], ["q", "qd", "qdd"], ["Phi"])


def payload_reference(payload: Any) -> np.ndarray:
    """Reference magnitudes (10,) of a typical payload (name, path or mapping of XXc..Mc)."""
    values = as_payload(payload)
    return reference_magnitudes([values[n] for n in PAYLOAD_NAMES], PAYLOAD_NAMES, groups=PAYLOAD_KINDS)


def payload_model(robot: rx90sym.Robot, base: Any, chi_nominal: Any, payload: Any,
                  z_min: float | None = None) -> ExcitationModel:
    """The robot as a payload excitation sees it: regressor Wc, names XXc..Mc, torque limits of
    the robot carrying ``payload`` (none without nominal parameters chi_nominal)."""
    chi = None if chi_nominal is None else add_payload(robot, chi_nominal, payload)
    model = model_from_robot(robot, chi, base, z_min)
    return dataclasses.replace(model, regressor=payload_regressor(robot), names=PAYLOAD_NAMES)


def payload_sigma(robot: rx90sym.Robot, base_regressor: Any, loaded: Any, noise_std: Any,
                  empty: Any = None, rate: float = 250.0) -> dict[str, dict[str, float]]:
    """Predicted sigma of XXc..Mc [SI] by methods 3 and 4 for the ``loaded`` trajectory.

    Method 3 runs ``loaded`` empty and loaded; method 4 combines an empty run of ``empty`` (None:
    the same motion, then methods 3 and 4 agree since Wc = Wb Kc lies in the range of Wb) with
    the loaded run. noise_std (n,) [N m] per joint; samples counted at ``rate`` [Hz]."""
    s = 1.0 / np.asarray(noise_std, dtype=float)

    def blocks(traj: Any) -> tuple[np.ndarray, np.ndarray]:
        t = sample_times(traj.duration, rate)
        q, qd, qdd = traj.form.evaluate(traj.coefficients, t)
        wb = regressor_samples(base_regressor, q, qd, qdd) * s[None, :, None]
        wc = regressor_samples(payload_regressor(robot), q, qd, qdd) * s[None, :, None]
        return wb, wc

    wb, wc = blocks(loaded)
    gcc = np.einsum("kji,kjl->il", wc, wc)
    gbc = np.einsum("kji,kjl->il", wb, wc)
    gbb = np.einsum("kji,kjl->il", wb, wb)
    sigma3 = np.sqrt(np.diag(2.0 * np.linalg.inv(gcc)))
    wb_empty = wb if empty is None else blocks(empty)[0]
    full = np.block([[gbb + np.einsum("kji,kjl->il", wb_empty, wb_empty), gbc], [gbc.T, gcc]])
    sigma4 = np.sqrt(np.diag(np.linalg.inv(full))[gbb.shape[0]:])
    return {"method_3": dict(zip(PAYLOAD_NAMES, sigma3.tolist())),
            "method_4": dict(zip(PAYLOAD_NAMES, sigma4.tolist()))}


def payload_objective(payload: Any, noise_std: np.ndarray, rate: float = 250.0) -> Objective:
    """Criterion "sigma" on the ten payload parameters (method 3's information)."""
    return Objective("sigma", np.asarray(noise_std, dtype=float), payload_reference(payload), rate=rate)
