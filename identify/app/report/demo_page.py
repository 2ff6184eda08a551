"""The report of ``rx90 demo``: the twin's identification against its truth, payloads, the real TX40."""
from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np

import rx90sym

from .figures import figure, parameter_figure, residual_figure, torque_figure, trajectory_figure
from .page import Cell, Column, Page, Section, Summary, Table, Text
from .summary import heldout_flags, heldout_table, next_steps
from .tables import bodies_table, parameter_table, validation_table


def _truth_table(result: Any, truth: Mapping[str, float]) -> Table:
    """Estimate beside the twin's truth: error in σ (marked beyond 3σ)."""
    rows = []
    for n, v, s in zip(result.names, result.values, result.std):
        z = abs(v - truth[n]) / s if s > 0 else np.inf
        rows.append((n, truth[n], v, s, Cell(z, "ok" if z <= 3 else "poor")))
    return Table("truth", "Estimates against the twin's truth", (
        Column("parameter", text=True), Column("truth"), Column("estimate"), Column("σ", digits=3),
        Column("|error| / σ", digits=2)), tuple(rows), "✗: the truth lies beyond 3σ.")


def _payload_table(name: str, results: Sequence[Any]) -> Table:
    ap = rx90sym.load_payload(name)
    rows = tuple((r.method, ap["Mc"], r["Mc"], r.std[r.names.index("Mc")], ap["MZc"], r["MZc"]) for r in results)
    return Table(f"payload-{name}", f"Payload {name}: the four methods of section IV", (
        Column("method", decimals=0), Column("Mc a priori", "kg"), Column("Mc", "kg"), Column("σ Mc", "kg", digits=3),
        Column("MZc a priori", "kg·m"), Column("MZc", "kg·m")), rows)


def demo_page(robot: rx90sym.Robot, res: Any, truth: Mapping[str, float], ess: Any, con: Any, val: Any,
              fit_prediction: Any, empty: Any, payloads: Mapping[str, Sequence[Any]], tx40: tuple[Any, Any],
              excitation_text: str) -> Page:
    """The demo's page: summary on the twin's held-out motion, then every step's tables and figures."""
    vrec = val.to_dict()
    flags = heldout_flags(vrec)
    within = sum(abs(v - truth[n]) <= 3 * s for n, v, s in zip(res.names, res.values, res.std))
    summary = Summary(f"Twin identification: {within}/{len(res.names)} base parameters within 3σ of the truth.",
                      (("Robot", robot.name), ("Method", f"WLS, {len(res.names)} base parameters"),
                       ("Conditioning", f"cond(W) = {res.cond:.4g}"), ("Essential parameters", str(len(ess.names))),
                       ("Consistent fit", f"cost +{con.cost_increase_pct:.3f} % over WLS")),
                      heldout_table(vrec), tuple(flags), next_steps(flags))
    tx_res, tx_val = tx40
    sections = (
        Section("excitation", "Excitation trajectory", (Text((excitation_text,)),)),
        Section("validation", "Held-out validation", (validation_table(vrec), figure(
            "fig-validation", "Torque prediction on the validation motion", torque_figure(val, val.source)))),
        Section("parameters", "Parameters", (parameter_table(res.to_dict()["parameters"]), _truth_table(res, truth),
                                             figure("fig-parameters", "Base parameters with 2σ bars (×: truth)",
                                                    parameter_figure(res, truth)))),
        Section("essential", "Essential parameters", (parameter_table(ess.to_dict()["parameters"], table_id="essential",
                                                                      caption="Essential parameters"),)),
        Section("fit", "Fit: measured and predicted torques", (
            figure("fig-torques", "Measured and predicted joint torques", torque_figure(fit_prediction, fit_prediction.source)),
            figure("fig-residuals", "Residuals per joint [N·m]", residual_figure(fit_prediction, "Residuals")),
            figure("fig-trajectory", "Joint positions of the excitation", trajectory_figure(np.asarray(empty.t),
                                                                                            np.asarray(empty.q))))),
        Section("consistent", "Physically consistent identification", (
            Text((f"The identified model: {con.split}. Cost increase over WLS: {con.cost_increase_pct:.3f} %.",)),
            bodies_table(con.standard, robot.n, rx90sym.twin.default_parameters(robot)),
            figure("fig-consistent", "Consistent estimate with WLS 2σ bars", parameter_figure(con, truth, "Consistent estimate")))),
        Section("payloads", "Payloads", tuple(_payload_table(n, r) for n, r in payloads.items())),
        Section("tx40", "Real data: Stäubli TX40 (FIGAROH record, Apache-2.0)", (
            parameter_table(tx_res.to_dict()["parameters"], table_id="tx40-parameters", caption="TX40 base parameters"),
            validation_table(tx_val.to_dict(), "tx40-validation"))),
    )
    return Page("rx90sym demo: RX90 and its payload", "rx90 demo · twin with realistic noise, then the real TX40",
                summary, sections)
