"""``oceanloc simulate drift-follow`` and ``drift-swap``: following drift plans in a true current (V.D)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.table import Table

from oceanloc.cli import simulate
from oceanloc.cli._common import (
    Scheduler,
    Workers,
    console,
    ensure_dir,
    err_console,
    progress_bar,
    write_json,
)
from oceanloc.config.drift import load_drift_scenario
from oceanloc.evaluation.montecarlo import open_executor
from oceanloc.evaluation.path_following import drift_follow_study, drift_swap_study
from oceanloc.planning.drift_rrt.planner import make_planner, parse_planner_name


def _planner(name: str | None, default: str):
    name = default if name is None else parse_planner_name(name, "--planner")
    return name, make_planner(name)


@simulate.app.command("drift-follow")
def drift_follow(
    scenario: str = typer.Option(
        "dillard-drift-fixed", "--scenario", help="Drift scenario file or built-in name."
    ),
    runs: int | None = typer.Option(
        None, "--runs", min=1, help="Monte Carlo runs (default: the scenario's)."
    ),
    seed: int | None = typer.Option(None, "--seed", min=0, help="Master seed (default: the scenario's)."),
    planner: str | None = typer.Option(None, "--planner", help="Planner for the plan and the replans."),
    json_path: Annotated[Path | None, typer.Option("--json", help="Write the summary as JSON.")] = None,
    figures: Annotated[
        Path | None, typer.Option("--figures", help="Write the Fig. 72-style PNG here.")
    ] = None,
    workers: Workers = None,
    scheduler: Scheduler = None,
) -> None:
    """Follow a plan with watch circles in a perturbed current; arrival rate, extra energy, replans."""
    from oceanloc.report.figures.drift import following_figure

    sc = load_drift_scenario(scenario)
    fs = sc.following
    n = runs or fs.runs
    with open_executor(scheduler, workers) as executor, progress_bar(n, "following runs") as advance:
        study = drift_follow_study(sc, n, seed, planner=planner, executor=executor, progress=advance)
    summary, problem, name, first, res = study.summary, study.problem, study.planner, study.plan, study.runs
    table = Table(title=f"Path following: {sc.name}, {name}, {n} runs (thesis V.D)", show_header=False)
    table.add_row(
        "true current",
        f"{fs.current_scale:g} x planning current rotated {np.degrees(fs.current_rotation_rad):g} deg "
        f"+ {fs.noise_mps:g} m/s noise (tau {fs.noise_correlation_s:g} s)",
    )
    table.add_row("watch circle / stray", f"{fs.watch_circle_m:g} m / {fs.stray_m:g} m")
    table.add_row("arrival rate", f"{100 * summary.arrival_rate:.1f}%")
    table.add_row("planned flight energy", f"{summary.planned_energy_wh:.2f} Wh")
    table.add_row(
        "flown (arrivals)",
        f"{summary.flight_energy_wh_mean:.2f} Wh; "
        f"extra {summary.extra_energy_wh_mean:+.2f} +- {summary.extra_energy_wh_std:.2f} Wh",
    )
    table.add_row("replans (arrivals)", f"{summary.replans_mean:.2f} per run")
    table.add_row("duration (arrivals)", f"{summary.duration_h_mean:.2f} h")
    table.add_row("units", problem.energy.convention)
    console.print(table)
    if json_path is not None:
        write_json(
            json_path,
            {"scenario": sc.name, "planner": name, **{k: getattr(summary, k) for k in summary.__slots__}},
        )
    if figures is not None:
        out = following_figure(
            ensure_dir(figures) / f"{sc.name}-following.png",
            problem,
            first.path,
            res.tracks(),
            res.flights(),
            fs.watch_circle_m,
            f"Path following, {sc.name} (thesis Fig. 72)",
        )
        err_console.print(f"wrote {out}")


@simulate.app.command("drift-swap")
def drift_swap(
    scenario: str = typer.Option(
        "dillard-drift-swap", "--scenario", help="Drift scenario file or built-in name."
    ),
    seed: int | None = typer.Option(None, "--seed", min=0, help="Planner seed (default: the scenario's)."),
    planner: str | None = typer.Option(None, "--planner", help="Planner of both drifters."),
    figures: Annotated[Path | None, typer.Option("--figures", help="Write PNG figures here.")] = None,
) -> None:
    """Two drifters swap positions (thesis Figs. 68-71): both plans, then both followed in a true current."""
    from oceanloc.report.figures.drift import following_figure, paths_figure

    sc = load_drift_scenario(scenario)
    study = drift_swap_study(sc, seed, planner=planner)
    swap, name, problem = study.swap, study.planner, study.swap.problems[0]
    table = Table(title=f"Position swap: {sc.name}, {name}")
    for col in (
        "drifter",
        "status",
        "flights",
        "flight energy Wh",
        "saving",
        "duration h",
        "followed: arrived",
        "flown Wh",
        "replans",
    ):
        table.add_column(col)
    followed = study.followed
    for k, (res, f) in enumerate(zip(swap.results, followed, strict=True)):
        if res.path is None or f is None:
            table.add_row(str(k + 1), res.status.value, "-", "-", "-", "-", "-", "-", "-")
            continue
        table.add_row(
            str(k + 1),
            res.status.value,
            str(res.path.hops_m().shape[0]),
            f"{res.flight_energy_wh:.2f}",
            f"{100 * res.saving:.1f}%",
            f"{res.path.duration_s / 3600:.2f}",
            "yes" if f.arrived[0] else "no",
            f"{f.flight_energy_wh[0]:.2f}",
            str(int(f.replans[0])),
        )
    console.print(table)
    console.print(
        f"closest approach of the planned schedules: {swap.min_separation_m:.0f} m; "
        f"units: {problem.energy.convention}"
    )
    if figures is not None:
        folder = ensure_dir(figures)
        plans = {f"drifter {k + 1}": r.path for k, r in enumerate(swap.results) if r.path is not None}
        out = paths_figure(
            folder / f"{sc.name}-plans.png",
            problem,
            plans,
            "Two drifters swap positions (thesis Figs. 70-71)",
        )
        err_console.print(f"wrote {out}")
        for k, (prob, res, f) in enumerate(zip(swap.problems, swap.results, followed, strict=True)):
            if res.path is None or f is None:
                continue
            out = following_figure(
                folder / f"{sc.name}-drifter{k + 1}-following.png",
                prob,
                res.path,
                f.tracks(),
                f.flights(),
                sc.following.watch_circle_m,
                f"Drifter {k + 1} following its plan (thesis Fig. 72)",
            )
            err_console.print(f"wrote {out}")
