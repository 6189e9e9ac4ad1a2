"""``oceanloc reproduce dillard-drrt``: Table 4 of the AquaQuad thesis, with oceanloc's planner beside it."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from oceanloc._random import run_generators
from oceanloc.cli import reproduce
from oceanloc.cli._common import (
    Scheduler,
    Workers,
    console,
    ensure_dir,
    err_console,
    progress_bar,
    write_json,
)
from oceanloc.evaluation.montecarlo import open_executor
from oceanloc.planning.drift_rrt.oceanloc_planner import plan_oceanloc
from oceanloc.planning.drift_rrt.planner import PLANNER_NAMES
from oceanloc.planning.drift_rrt.problem import PlanBudget
from oceanloc.planning.drift_rrt.thesis import ThesisOptions, plan_thesis
from oceanloc.reproduce.dillard_drrt import (
    THESIS_DIRECT_FLIGHT_WH,
    THESIS_TABLE4,
    DillardReport,
    planned_runs,
    reference_options_note,
    reproduce_dillard_drrt,
    thesis_problem,
)


@reproduce.app.command("dillard-drrt")
def dillard_drrt(
    runs: int = typer.Option(1000, "--runs", min=1, help="Monte Carlo runs per planner on the fixed field."),
    seed: int = typer.Option(2014, "--seed", min=0, help="Master seed."),
    json_path: Annotated[Path | None, typer.Option("--json", help="Write the summary as JSON.")] = None,
    figures: Annotated[
        Path | None, typer.Option("--figures", help="Write PNG figures to this folder.")
    ] = None,
    fields: int = typer.Option(
        20, "--fields", min=0, help="Random obstacle fields (the thesis' generator); 0 skips."
    ),
    iterations: int = typer.Option(
        25_000, "--iterations", min=1, help="Iterations of the optimality-seeking mode."
    ),
    reference_spacing: float = typer.Option(
        50.0, "--reference-spacing", min=10.0, help="Lattice spacing (m) of the best-achievable reference."
    ),
    workers: Workers = None,
    scheduler: Scheduler = None,
) -> None:
    """DR-RRT* Monte Carlo (thesis Table 4): single-solution, optimality-seeking and oceanloc's planner.

    Compute times are wall-clock per run inside its worker; with several workers sharing the cores they
    run longer than alone (use --workers 1, or make bench, for timings).
    """
    total = planned_runs(runs, fields)
    with open_executor(scheduler, workers) as executor, progress_bar(total, "planner runs") as advance:
        report = reproduce_dillard_drrt(
            runs,
            seed,
            fields=fields,
            iterations=iterations,
            reference_spacing_m=reference_spacing,
            executor=executor,
            progress=advance,
            note=lambda text: err_console.print(text, highlight=False),
        )
    _print_report(report, runs, iterations)
    if json_path is not None:
        write_json(json_path, report.to_record())
    if figures is not None:
        _figures(ensure_dir(figures), report, seed, iterations)


def _print_report(report: DillardReport, runs: int, iterations: int) -> None:
    table = Table(title=f"DR-RRT* Monte Carlo on the fixed field ({runs} runs per planner) - thesis Table 4")
    for col in (
        "planner",
        "success",
        "energy Wh",
        "saving",
        "compute ms (median)",
        "/ best",
        "thesis energy Wh",
        "thesis saving",
        "thesis compute ms",
    ):
        table.add_column(col, justify="right" if col != "planner" else "left")
    for name in PLANNER_NAMES:
        s = report.planners[name]
        t = THESIS_TABLE4.get(name)
        label = f"{name} ({iterations} it.)" if name == "thesis-optimality-seeking" else name
        table.add_row(
            label,
            f"{100 * s.success_rate:.1f}%",
            f"{s.energy_wh_mean:.2f} +- {s.energy_wh_std:.2f}",
            f"{100 * s.saving_mean:.1f}%",
            f"{1e3 * s.compute_s_median:.1f}",
            f"{s.ratio_to_best:.3f}",
            f"{t['energy_wh_mean']:.2f} +- {t['energy_wh_std']:.2f}" if t else "-",
            f"{100 * t['saving_mean']:.0f}%" if t else "-",
            f"{1e3 * t['compute_s_mean']:.0f} +- {1e3 * t['compute_s_std']:.0f}" if t else "-",
        )
    console.print(table)
    console.print(
        f"direct flight {report.direct_flight_wh:.2f} Wh (thesis {THESIS_DIRECT_FLIGHT_WH} Wh); "
        f"best achievable {report.best_achievable_wh:.2f} Wh "
        f"(saving {100 * (1 - report.best_achievable_wh / report.direct_flight_wh):.1f}%)"
    )
    console.print(f"units: {report.convention}")
    console.print(
        f"{reference_options_note(report.reference_options)}; "
        "thesis compute times: MATLAB, Core i7-2600 (mean +- std)"
    )
    if report.fields:
        ft = Table(title=f"Across {report.field_best_wh.size} random fields (the thesis' generator)")
        for col in (
            "planner",
            "success",
            "mean saving",
            "worst field saving",
            "/ best (mean over fields)",
            "compute ms (median)",
        ):
            ft.add_column(col, justify="right" if col != "planner" else "left")
        for name, s in report.fields.items():
            ft.add_row(
                name,
                f"{100 * s.success_rate:.1f}%",
                f"{100 * s.saving_mean:.1f}%",
                f"{100 * s.saving_min_field:.1f}%",
                f"{s.ratio_to_best_mean:.3f}",
                f"{1e3 * s.compute_s_median:.1f}",
            )
        console.print(ft)


def _figures(folder: Path, report: DillardReport, seed: int, iterations: int) -> None:
    from oceanloc.report.figures.drift import energy_figure, paths_figure, tree_figure

    problem = thesis_problem()
    rng = run_generators(seed, [0])[0]
    single = plan_thesis(problem, rng, options=ThesisOptions(mode="single", keep_tree=True))
    rng = run_generators(seed, [0])[0]
    optimal = plan_thesis(
        problem,
        rng,
        PlanBudget(max_iterations=iterations),
        ThesisOptions(mode="optimality-seeking", keep_tree=True),
    )
    ours = plan_oceanloc(problem, run_generators(seed, [0])[0])
    written = [
        tree_figure(
            folder / "drrt_tree_single.png",
            problem,
            single.tree,
            single.path,
            "DR-RRT* single solution (thesis Figs. 46, 50)",
        ),  # type: ignore[arg-type]
        tree_figure(
            folder / "drrt_tree_optimality.png",
            problem,
            optimal.tree,
            optimal.path,
            f"DR-RRT* optimality-seeking, {iterations} iterations",
        ),  # type: ignore[arg-type]
    ]
    plans = {
        "thesis-single": single.path,
        "thesis-optimality-seeking": optimal.path,
        "oceanloc": ours.path,
        "best achievable": report.reference.path,
    }
    written.append(
        paths_figure(
            folder / "drrt_paths.png",
            problem,
            {k: v for k, v in plans.items() if v is not None},
            "Final paths",
        )
    )
    energies = {name: report.fixed.runs[name].energy_wh for name in PLANNER_NAMES}
    written.append(
        energy_figure(
            folder / "drrt_energy.png",
            energies,
            report.direct_flight_wh,
            report.best_achievable_wh,
            "Flight energy per run (thesis Figs. 51, 53)",
        )
    )
    for p in written:
        err_console.print(f"wrote {p}")
