"""Terminal tables (rich) for the transponder-survey commands: one survey, a Monte Carlo, the reproductions.

Every numeric column header states its unit (``(m)``, ``(nats)``, ``(ms)``; ``(1)`` for dimensionless).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from rich.markup import escape
from rich.table import Table

from oceanloc.evaluation.survey import SingleSurvey, SurveyMonteCarlo
from oceanloc.planning.site_planners import site_planner_label
from oceanloc.reproduce.garcia2019 import EstimatorStudy
from oceanloc.reproduce.survey_tables import Check, MajorAxisSweep, TableRow, Verdict

REPORT_EPOCHS: tuple[int, ...] = (3, 7, 30)
"""The epochs the papers tabulate; the last epoch is always added."""


def report_epochs(epochs: int) -> list[int]:
    """The tabulated epochs within ``1..epochs``, plus the last."""
    return sorted({n for n in (*REPORT_EPOCHS, epochs) if n <= epochs})


def _triple(v: np.ndarray) -> str:
    return ", ".join(f"{float(x):.2f}" for x in v)


def single_survey_table(survey: SingleSurvey) -> Table:
    """Each transponder's truth, final estimate, error, 95 % horizontal ellipse (semi-axes and the major
    axis' azimuth, degrees clockwise from north in [0, 180), the convention of every printed bearing) and
    vertical standard deviation after one survey."""
    scen, ell = survey.scenario, survey.ellipses
    label = escape(site_planner_label(scen.planner))
    title = f"{escape(scen.name)}: after {scen.epochs} epochs (planner {label}, seed {survey.seed})"
    table = Table(title=title, caption="az: the 95 % ellipse's major axis, degrees clockwise from north")
    for col in (
        "m",
        "truth E,N,U (m)",
        "estimate E,N,U (m)",
        "error (m)",
        "95% a x b (m) @ az",
        "sd U (m)",
    ):
        table.add_column(col, justify="right", no_wrap=True)
    errors = survey.error_norm_m[-1]
    azimuth = (90.0 - np.degrees(ell.angle_rad)) % 180.0
    for m in range(scen.n_transponders):
        table.add_row(
            str(m + 1),
            _triple(scen.transponders_enu_m[m]),
            _triple(survey.final_estimates_m[m]),
            f"{errors[m]:.3f}",
            f"{ell.semi_major_m[m]:.3f} x {ell.semi_minor_m[m]:.3f} @ {azimuth[m]:.0f}",
            f"{survey.sigma_up_m[m]:.3f}",
        )
    return table


def single_survey_epoch_table(survey: SingleSurvey) -> Table:
    """Error per transponder, RMSEE over transponders and ``log det Y_n`` at the tabulated epochs."""
    scen = survey.scenario
    table = Table(title="Error and D-optimal value by epoch")
    table.add_column("epoch n", justify="right")
    for m in range(scen.n_transponders):
        table.add_column(f"error m={m + 1} (m)", justify="right")
    table.add_column("RMS over m (m)", justify="right")
    table.add_column("log det Y_n (nats)", justify="right")
    norms = survey.error_norm_m
    for n in report_epochs(scen.epochs):
        row = norms[n - 1]
        table.add_row(
            str(n),
            *(f"{v:.3f}" for v in row),
            f"{np.sqrt(np.mean(row**2)):.3f}",
            f"{survey.run.log_det[0, n - 1]:.2f}",
        )
    return table


def single_survey_summary(survey: SingleSurvey) -> str:
    """One line: final NEES and planning time."""
    n_dof = 3 * survey.scenario.n_transponders
    plan_ms = 1e3 * float(survey.run.plan_time_s.mean()) if survey.run.plan_time_s.size else 0.0
    return (
        f"NEES at n = {survey.scenario.epochs}: {survey.run.nees[0, -1]:.2f} (chi-square, {n_dof} dof); "
        f"mean planning time {plan_ms:.2f} ms per epoch"
    )


def monte_carlo_table(result: SurveyMonteCarlo) -> Table:
    """RMSEE per transponder, log det mean and std, and NEES consistency at the tabulated epochs."""
    scen, cons = result.scenario, result.consistency
    label = escape(site_planner_label(scen.planner))
    title = f"{escape(scen.name)}: {result.runs} runs, planner {label}, seed {result.seed}"
    title += f"; NEES vs chi2({cons.dof})"
    table = Table(title=title)
    table.add_column("epoch n", justify="right")
    for m in range(scen.n_transponders):
        table.add_column(f"RMSEE m={m + 1} (m)", justify="right")
    for col in (
        "log det mean (nats)",
        "log det std (nats)",
        "mean NEES (1)",
        "> chi2 q95 (%)",
    ):
        table.add_column(col, justify="right")
    for n in report_epochs(scen.epochs):
        table.add_row(
            str(n),
            *(f"{v:.3f}" for v in result.rmsee_m[n - 1]),
            f"{result.log_det.mean[n - 1]:.2f}",
            f"{result.log_det.std[n - 1]:.2f}",
            f"{cons.mean_nees[n - 1]:.2f}",
            f"{100 * cons.fraction_above[n - 1]:.1f}",
        )
    return table


def monte_carlo_summary(result: SurveyMonteCarlo) -> str:
    """One line: the NEES check at the last epoch, planning time and convergence."""
    c = result.nees_final
    verdict = "inside" if c.mean_within_band else "OUTSIDE"
    lo, hi = c.mean_band
    above, q95 = 100 * result.consistency.fraction_above[-1], result.consistency.quantile
    return (
        f"NEES at n = {result.scenario.epochs}: mean {c.mean:.2f} (chi-square {c.dof}: "
        f"band {lo:.2f}-{hi:.2f}, {verdict}), KS p = {c.p_value:.3f}; "
        f"{above:.1f} % of runs above the 95 % quantile {q95:.2f} "
        f"(5 % expected); planning {result.plan_time_s * 1e3:.2f} ms per run and epoch (batched); "
        f"{100 * result.converged_fraction:.2f} % of MAP solves converged"
    )


def reproduction_table(rows: Sequence[TableRow], title: str, rmse_label: str = "RMSEE (m)") -> Table:
    """Our Monte Carlo beside the paper's values, one row per (epoch, planner)."""
    table = Table(title=title)
    for col in (
        "epoch",
        "planner",
        f"{rmse_label} ours",
        "paper",
        "log det (nats) ours",
        "paper",
        "std (nats) ours",
        "paper",
        "z (1)",
    ):
        table.add_column(col, justify="right", overflow="fold")
    last_epoch = None
    for i, r in enumerate(rows):
        table.add_row(
            f"n = {r.epoch}" if r.epoch != last_epoch else "",
            escape(r.planner),
            f"{r.rmse_m:.2f}",
            f"{r.paper_rmse_m:.2f}",
            f"{r.logdet_mean:.2f}",
            f"{r.paper_logdet_mean:.2f}",
            f"{r.logdet_std:.2f}",
            f"{r.paper_logdet_std:.2f}",
            f"{r.logdet_z:+.1f}",
            end_section=i + 1 < len(rows) and rows[i + 1].epoch != r.epoch,
        )
        last_epoch = r.epoch
    return table


def checks_table(checks: Sequence[Check], title: str = "Acceptance checks") -> Table:
    """Pass/fail lines of a reproduction."""
    table = Table(title=title)
    table.add_column("check", overflow="fold")
    table.add_column("result")
    table.add_column("values", overflow="fold")
    for c in checks:
        result = "[green]pass[/green]" if c.passed else "[red]FAIL[/red]"
        table.add_row(escape(c.name), result, escape(c.detail))
    return table


def verdicts_table(verdicts: Sequence[Verdict], title: str) -> Table:
    """Which published tables and figures reproduce, with the evidence (ours vs paper, z)."""
    colours = {"reproduces": "green", "close": "yellow", "does not reproduce": "red"}
    table = Table(title=title)
    table.add_column("table / figure", overflow="fold")
    table.add_column("verdict")
    table.add_column("evidence: ours vs paper (z)", overflow="fold")
    for v in verdicts:
        colour = colours[v.status]
        table.add_row(escape(v.item), f"[{colour}]{v.status}[/{colour}]", escape(v.evidence))
    return table


def verdict_line(verdicts: Sequence[Verdict]) -> str:
    """The one-line conclusion: never a success beside failing rows."""
    missing = [v.item for v in verdicts if not v.reproduces]
    if not missing:
        return "[green]Every table and figure above reproduces (within 3 SE or 2 %).[/green]"
    return f"[red]Does not reproduce:[/red] {escape('; '.join(missing))} (evidence in the table above)."


def nees_plan_table(
    studies: Mapping[str, Mapping[int, SurveyMonteCarlo]],
    paper_plan_time_s: Mapping[str, Mapping[int, float]] | None = None,
    title: str = "NEES at the last epoch (chi-square 3M) and planning time per epoch",
) -> Table:
    """Mean NEES with its 3-SE band and KS p-value, and the planning time, per study."""
    table = Table(title=title)
    columns = ["M", "planner", "mean NEES (1)", "3 SE band (1)", "KS p (1)", "plan time (ms, per run)"]
    if paper_plan_time_s is not None:
        columns.append("paper (s, MATLAB)")
    for col in columns:
        table.add_column(col, justify="right", overflow="fold")
    for label, by_k in studies.items():
        for k, s in sorted(by_k.items()):
            c = s.nees_final
            lo, hi = c.mean_band
            planned = s.scenario.planner.kind in ("greedy", "lookahead")
            cells = [
                label[1:],
                escape(site_planner_label(s.scenario.planner)),
                f"{c.mean:.2f}",
                f"{lo:.2f}-{hi:.2f}",
                f"{c.p_value:.2f}",
                f"{s.plan_time_s * 1e3:.2f}" if planned else "-",
            ]
            if paper_plan_time_s is not None:
                paper = paper_plan_time_s.get(label, {}).get(k)
                cells.append(f"{paper:.2f}" if paper else "-")
            table.add_row(*cells)
    return table


def estimator_line(est: EstimatorStudy) -> str:
    """Journal Section V-A in one line: NEES of the estimator alone and the two 95 % ellipses."""
    lo, hi = est.check.mean_band
    actual, fitted = est.actual_ellipse, est.sample_ellipse
    return (
        f"[bold]V-A estimator[/bold] ({est.nees.size} runs, N = 4): mean NEES {est.check.mean:.2f} "
        f"(chi2(3): 3, band {lo:.2f}-{hi:.2f}), KS p = {est.check.p_value:.2f}; 95% ellipse semi-axes: "
        f"eq. (22) {float(actual.semi_major_m):.3f} x {float(actual.semi_minor_m):.3f} m, "
        f"fitted {float(fitted.semi_major_m):.3f} x {float(fitted.semi_minor_m):.3f} m"
    )


def sweep_line(sweep: MajorAxisSweep, title: str) -> str:
    """The angle between the planned direction and the ellipse's major axis at the tabulated reaches."""
    angles = ", ".join(f"{r:g} m: {a:.2f} deg" for r, a in sweep.angle_at().items())
    return f"[bold]{title}[/bold]: angle between the planned direction and the ellipse's major axis: {angles}"
