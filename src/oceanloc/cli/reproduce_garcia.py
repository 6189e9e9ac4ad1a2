"""``oceanloc reproduce garcia2019`` and ``oceanloc reproduce garcia2018-greedy``."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.table import Table

from oceanloc.cli import reproduce
from oceanloc.cli._common import (
    FiguresOut,
    JsonOut,
    Scheduler,
    Seed,
    Workers,
    console,
    ensure_dir,
    progress_bar,
    write_json,
)
from oceanloc.errors import ConfigError
from oceanloc.evaluation.montecarlo import open_executor
from oceanloc.planning.site_planners import site_planner_label
from oceanloc.report.tables.survey import checks_table, reproduction_table
from oceanloc.reproduce import garcia2018, garcia2019
from oceanloc.reproduce.survey_tables import MajorAxisSweep

_READINGS = """
Readings where the paper is ambiguous: measurement n is taken at p_V(n) (p_V(1), phi(1) as given);
statistics at epoch n use the prior and ranges 1..n (estimation starts at n = 1, warm-started from the
previous epoch); the planner at epoch n uses the epoch-n estimates and only its first yaw rate is applied
(eq. 1: new heading, then position); no planning after the last epoch. The random baseline (k = 0) draws
each yaw rate uniformly in [-w_max, w_max]. Each run draws its prior mean from N(p_T, P_0). Y_n includes the
prior information (inverse of eq. 22); for M = 4 log det is over the block-diagonal Y_n. The planners'
objective keeps the sigma^-2 that eq. (37) drops and is solved to its global optimum (not a local solve
from straight ahead), so the planned rows need not equal the paper's.
"""


@reproduce.app.command(
    "garcia2019", help=f"Reproduce Garcia et al. (IEEE TAES 2019), Section V.\n\n{_READINGS}"
)
def garcia2019_command(
    runs: int = typer.Option(1000, "--runs", min=2, help="Monte Carlo runs per table row (paper: 1000)."),
    seed: Seed = None,
    json_path: JsonOut = None,
    figures: FiguresOut = None,
    workers: Workers = None,
    scheduler: Scheduler = None,
    horizons: str = typer.Option("0,1,2,3", "--horizons", help="Comma-separated k to run (0 = random)."),
) -> None:
    """Section V: estimator study (Figs. 1-2), Tables III and V for k = 0..3 (Figs. 3-8)."""
    seed = 2019 if seed is None else seed
    ks = _parse_horizons(horizons)
    total = min(runs, garcia2019.ESTIMATOR_RUNS) + 2 * len(ks) * runs
    with open_executor(scheduler, workers) as executor, progress_bar(total, "Monte Carlo runs") as advance:
        result = garcia2019.reproduce_garcia2019(runs, seed, executor=executor, progress=advance, horizons=ks)

    est = result.estimator
    band = est.check.mean_band
    actual, fitted = est.actual_ellipse, est.sample_ellipse
    console.print(
        f"[bold]V-A estimator[/bold] ({est.nees.size} runs, N = 4): mean NEES {est.check.mean:.2f} "
        f"(chi2(3): 3, band {band[0]:.2f}-{band[1]:.2f}), KS p = {est.check.p_value:.2f}; 95% ellipse "
        f"semi-axes: eq. (22) {actual.semi_major_m:.3f} x {actual.semi_minor_m:.3f} m, "
        f"fitted {fitted.semi_major_m:.3f} x {fitted.semi_minor_m:.3f} m"
    )
    titles = {
        "III": "Table III: one transponder (M = 1)",
        "V": "Table V: four transponders (M = 4), RMSEE of m = 2",
    }
    for name, rows in result.tables.items():
        console.print(
            reproduction_table(rows, f"{titles[name]}, {runs} runs (paper 1000); z = (ours - paper) / SE")
        )
    console.print(_nees_plan_table(result))
    console.print(_sweep_line(result.fig5, "Fig. 5 (k = 1, w_max = 180 deg/s, speed 1-80 m/s)"))
    console.print(checks_table(result.checks))
    if json_path:
        write_json(json_path, garcia2019.to_json(result))
    if figures:
        _garcia2019_figures(result, ensure_dir(figures))


@reproduce.app.command(
    "garcia2018-greedy",
    help="Reproduce the greedy distance-constrained planner of Garcia's MS thesis (2018), Sections 5.2 "
    "and 5.4.\n\nRandom point in the 5 m disk (k = 0) against the greedy D-optimal point (k = 1), M = 1 and "
    "M = 4, 50 epochs, and Fig. 5.3. The epoch readings are those of 'reproduce garcia2019'. The thesis' "
    "Table 5.3 does not reproduce at n = 3 and 7 under any reading tried; Table 5.7 does.",
)
def garcia2018_command(
    runs: int = typer.Option(500, "--runs", min=2, help="Monte Carlo runs per table row (thesis: 500)."),
    seed: Seed = None,
    json_path: JsonOut = None,
    figures: FiguresOut = None,
    workers: Workers = None,
    scheduler: Scheduler = None,
) -> None:
    """Tables 5.3 and 5.7 and Fig. 5.3."""
    from oceanloc.report.figures import survey as survey_figures

    seed = 2018 if seed is None else seed
    with open_executor(scheduler, workers) as executor, progress_bar(4 * runs, "Monte Carlo runs") as advance:
        result = garcia2018.reproduce_garcia2018_greedy(runs, seed, executor=executor, progress=advance)
    titles = {
        "5.3": "Table 5.3: one transponder, d_max = 5 m",
        "5.7": "Table 5.7: four transponders, RMSEE of m = 2",
    }
    for name, rows in result.tables.items():
        table = reproduction_table(rows, f"{titles[name]}, {runs} runs (thesis 500); k = 1 is greedy")
        console.print(table)
    console.print(_sweep_line(result.fig53, "Fig. 5.3 (greedy, reach 1-80 m)"))
    console.print(checks_table(result.checks))
    if json_path:
        write_json(json_path, garcia2018.to_json(result))
    if figures:
        out = ensure_dir(figures)
        for label, by_k in result.studies.items():
            survey_figures.logdet_rmse_figure(
                by_k, 0 if label == "M1" else 1, out / f"greedy_{label.lower()}_logdet_rmse.png",
                f"Greedy vs random, {label}",
            )  # fmt: skip
        _sweep_figure(result.fig53, out / "fig5_3_major_axis.png", "Thesis Fig. 5.3: greedy point vs reach")
        console.print(f"wrote figures to {out}")


def _parse_horizons(text: str) -> tuple[int, ...]:
    try:
        ks = tuple(sorted({int(p) for p in text.split(",") if p.strip()}))
    except ValueError:
        raise ConfigError(f"--horizons must be comma-separated integers, got '{text}'") from None
    if not ks or min(ks) < 0 or max(ks) > 10:
        raise ConfigError(f"--horizons must list values between 0 and 10, got '{text}'")
    return ks


def _nees_plan_table(result: garcia2019.Garcia2019Result) -> Table:
    table = Table(title="NEES at n = 50 (chi-square 3M) and planning time per epoch")
    for col in (
        "M",
        "k",
        "mean NEES",
        "3M band",
        "KS p",
        "plan time ours (batched, per run)",
        "paper (MATLAB)",
    ):
        table.add_column(col, justify="right")
    for label, by_k in result.studies.items():
        for k, s in sorted(by_k.items()):
            c = s.nees_final
            paper = garcia2019.PAPER_PLAN_TIME_S[label].get(k)
            lo, hi = c.mean_band
            table.add_row(
                label[1:], str(k), f"{c.mean:.2f}", f"{lo:.2f}-{hi:.2f}", f"{c.p_value:.2f}",
                f"{s.plan_time_s * 1e3:.2f} ms" if k else "-", f"{paper:.2f} s" if paper else "-",
            )  # fmt: skip
    return table


def _sweep_line(sweep: MajorAxisSweep, title: str) -> str:
    picks = [
        (r, a) for r, a in zip(sweep.reaches_m, sweep.angle_deg, strict=True) if int(r) in (5, 10, 20, 40, 80)
    ]
    angles = ", ".join(f"{int(r)} m: {a:.2f} deg" for r, a in picks)
    return f"[bold]{title}[/bold]: angle between the planned direction and the ellipse's major axis: {angles}"


def _sweep_figure(sweep: MajorAxisSweep, path: Path, title: str) -> Path:
    from oceanloc.report.figures import survey as survey_figures

    return survey_figures.major_axis_figure(
        sweep.planned_enu_m[:, :2], sweep.reaches_m, sweep.start_enu_m[:2], sweep.estimate_m[:2],
        sweep.covariance_m2[:2, :2], path, title,
    )  # fmt: skip


def _garcia2019_figures(result: garcia2019.Garcia2019Result, out: Path) -> None:
    from oceanloc.report.figures import survey as survey_figures

    est = result.estimator
    survey_figures.estimates_figure(
        est.estimates_m[:, :2], garcia2019.ESTIMATOR_TRUTH_M[:2], est.actual_ellipse, est.sample_ellipse,
        out / "fig1_estimates_en.png",
    )  # fmt: skip
    survey_figures.nees_figure(est.nees, 3, out / "fig2_nees_n4.png", "Fig. 2: NEES at n = N = 4")
    k_fig = garcia2019.NEES_FIGURE_HORIZON
    for label, fig_curves, fig_nees in (("M1", "fig3", "fig4"), ("M4", "fig6", "fig7")):
        by_k = result.studies[label]
        m = 0 if label == "M1" else 1
        survey_figures.logdet_rmse_figure(
            by_k,
            m,
            out / f"{fig_curves}_{label.lower()}_logdet_rmse.png",
            f"{label}: D-optimal value and RMSEE",
        )
        if k_fig in by_k:
            s = by_k[k_fig]
            name = f"{fig_nees}_nees_{label.lower()}_k{k_fig}.png"
            survey_figures.nees_figure(
                s.nees[:, -1], 3 * s.scenario.n_transponders, out / name,
                f"NEES at n = 50, {label}, k = {k_fig}",
            )  # fmt: skip
    _sweep_figure(
        result.fig5, out / "fig5_major_axis.png", "Fig. 5: k = 1 plan vs speed, after the first range"
    )
    runs = {
        site_planner_label(s.scenario.planner): s.sample_run(0)
        for _, s in sorted(result.studies["M4"].items())
    }
    survey_figures.trajectories_figure(
        runs, out / "fig8_trajectories_m4.png", "Fig. 8: measurement paths, run 0"
    )
    console.print(f"wrote figures to {out}")
