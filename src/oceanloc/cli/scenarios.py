"""``oceanloc scenarios``: list and show the built-in scenarios."""

from __future__ import annotations

import typer
from rich.table import Table

from oceanloc.cli._common import console
from oceanloc.config.survey import builtin_survey_scenarios, load_survey_scenario
from oceanloc.planning.site_planners import site_planner_label
from oceanloc.units import DEG

app = typer.Typer(help="List and show built-in scenarios.", no_args_is_help=True)


@app.command("list")
def list_scenarios() -> None:
    """List the built-in survey scenarios."""
    table = Table(title="Built-in survey scenarios")
    for col in ("name", "M", "N", "planner", "description"):
        table.add_column(col)
    for name in builtin_survey_scenarios():
        s = load_survey_scenario(name)
        table.add_row(
            name, str(s.n_transponders), str(s.epochs), site_planner_label(s.planner), s.description
        )
    console.print(table)


@app.command("show")
def show(name: str = typer.Argument(..., help="Built-in scenario name or TOML file.")) -> None:
    """Show a scenario's settings after validation."""
    s = load_survey_scenario(name)
    table = Table(title=s.name, show_header=False)
    table.add_row("transponders (E, N, U) m", "\n".join(str(list(p)) for p in s.transponders_enu_m))
    table.add_row("start (E, N, U) m", str(list(s.start_enu_m)))
    table.add_row("start yaw deg", f"{s.start_yaw_rad / DEG:.1f}")
    table.add_row("speed m/s, period s", f"{s.speed_mps}, {s.period_s}")
    table.add_row("max yaw rate deg/s", f"{s.max_yaw_rate_rad_s / DEG:.1f}")
    table.add_row("sigma range m", f"{s.sigma_range_m}")
    table.add_row("prior sigma (E, N, U) m", str(list(map(float, s.prior_cov_m2.diagonal() ** 0.5))))
    table.add_row("epochs N", str(s.epochs))
    table.add_row("planner", f"{s.planner.kind} (k={s.planner.horizon}, d_max={s.planner.max_distance_m} m)")
    table.add_row("Monte Carlo", f"{s.runs} runs, seed {s.seed}")
    console.print(table)
