"""``oceanloc reproduce garcia2019`` and ``oceanloc reproduce garcia2018-greedy``."""

from __future__ import annotations

from collections.abc import Iterable

import typer

from oceanloc.cli import reproduce
from oceanloc.cli._common import (
    FiguresOut,
    JsonOut,
    NetcdfOut,
    Scheduler,
    Seed,
    Workers,
    cli_provenance,
    console,
    ensure_dir,
    escape,
    progress_bar,
    write_json,
    write_netcdf,
)
from oceanloc.cli._options import parse_ints
from oceanloc.evaluation.montecarlo import open_executor
from oceanloc.evaluation.survey import planners_dataset
from oceanloc.io.records import Provenance
from oceanloc.report.tables import survey as tables
from oceanloc.reproduce import garcia2018, garcia2019

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
    netcdf: NetcdfOut = None,
    figures: FiguresOut = None,
    workers: Workers = None,
    scheduler: Scheduler = None,
    horizons: str = typer.Option("0,1,2,3", "--horizons", help="Comma-separated k to run (0 = random)."),
) -> None:
    """Section V: estimator study (Figs. 1-2), Tables III and V for k = 0..3 (Figs. 3-8)."""
    from oceanloc.report.figures import survey as survey_figures

    seed = 2019 if seed is None else seed
    ks = parse_ints(horizons, "--horizons", low=0, high=10)
    total = min(runs, garcia2019.ESTIMATOR_RUNS) + 2 * len(ks) * runs
    with open_executor(scheduler, workers) as executor, progress_bar(total, "Monte Carlo runs") as advance:
        result = garcia2019.reproduce_garcia2019(runs, seed, executor=executor, progress=advance, horizons=ks)
    console.print(tables.estimator_line(result.estimator))
    for name, rows in result.tables.items():
        title = f"{garcia2019.TABLE_TITLES[name]}, {runs} runs (paper 1000); z = (ours - paper) / SE"
        console.print(tables.reproduction_table(rows, title))
    console.print(tables.nees_plan_table(result.studies, garcia2019.PAPER_PLAN_TIME_S))
    console.print(tables.sweep_line(result.fig5, "Fig. 5 (k = 1, w_max = 180 deg/s, speed 1-80 m/s)"))
    console.print(tables.checks_table(result.checks))
    console.print(
        tables.verdicts_table(result.verdicts, "Which tables reproduce (log det within 3 SE or 2 %)")
    )
    console.print(tables.verdict_line(result.verdicts))
    prov = _provenance(seed, garcia2019.TABLE_SCENARIOS.values())
    if json_path:
        write_json(json_path, result.to_record(), prov)
    if netcdf:
        studies = {label: [s for _, s in sorted(by_k.items())] for label, by_k in result.studies.items()}
        write_netcdf(netcdf, planners_dataset(studies), prov)
    if figures:
        paths = survey_figures.garcia2019_figures(result, ensure_dir(figures))
        console.print(f"wrote {len(paths)} figures to {escape(str(figures))}")


@reproduce.app.command(
    "garcia2018-greedy",
    help="Reproduce the greedy distance-constrained planner of Garcia's MS thesis (2018), Sections 5.2 "
    "and 5.4.\n\nRandom point in the 5 m disk about the vehicle against the greedy D-optimal point, M = 1 "
    "and M = 4, 50 epochs, and Fig. 5.3. The epoch readings are those of 'reproduce garcia2019'. Prints "
    "which of the thesis' tables and figures reproduce and, for those that do not, ours against the "
    "thesis' values with z: the random rows of Tables 5.3 and 5.7 and the greedy rows of Table 5.3 at "
    "n = 3 and 7 do not.",
)
def garcia2018_command(
    runs: int = typer.Option(500, "--runs", min=2, help="Monte Carlo runs per table row (thesis: 500)."),
    seed: Seed = None,
    json_path: JsonOut = None,
    figures: FiguresOut = None,
    workers: Workers = None,
    scheduler: Scheduler = None,
) -> None:
    """Tables 5.3 and 5.7 and Fig. 5.3, with the verdict of each."""
    from oceanloc.report.figures import survey as survey_figures

    seed = 2018 if seed is None else seed
    with open_executor(scheduler, workers) as executor, progress_bar(4 * runs, "Monte Carlo runs") as advance:
        result = garcia2018.reproduce_garcia2018_greedy(runs, seed, executor=executor, progress=advance)
    for name, rows in result.tables.items():
        title = f"{garcia2018.TABLE_TITLES[name]}, {runs} runs (thesis 500); z = (ours - thesis) / SE"
        console.print(tables.reproduction_table(rows, title))
    console.print(tables.nees_plan_table(result.studies))
    console.print(tables.sweep_line(result.fig53, "Fig. 5.3 (greedy, reach 1-80 m)"))
    console.print(tables.checks_table(result.checks))
    console.print(tables.verdicts_table(result.verdicts, "Which thesis tables and figures reproduce"))
    console.print(tables.verdict_line(result.verdicts))
    if json_path:
        write_json(json_path, result.to_record(), _provenance(seed, garcia2018.TABLE_SCENARIOS.values()))
    if figures:
        paths = survey_figures.garcia2018_figures(result, ensure_dir(figures))
        console.print(f"wrote {len(paths)} figures to {escape(str(figures))}")


def _provenance(seed: int, scenarios: Iterable[str]) -> Provenance:
    """Provenance naming both scenarios; the TOML hash is over their texts joined in that order."""
    from oceanloc.config.survey import load_survey_scenario

    loaded = [load_survey_scenario(name) for name in scenarios]
    return cli_provenance(
        seed=seed,
        scenario=" + ".join(s.name for s in loaded),
        scenario_toml="".join(s.toml_text for s in loaded),
    )
