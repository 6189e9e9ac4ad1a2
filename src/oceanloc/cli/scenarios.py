"""``oceanloc scenarios``: list and show the built-in scenarios of every kind (survey, flock, drift)."""

from __future__ import annotations

import typer

from oceanloc.cli import root
from oceanloc.cli._common import console
from oceanloc.config.catalog import builtin_scenarios, load_scenario
from oceanloc.report.tables.scenarios import scenario_list_table, scenario_show_table

app = typer.Typer(help="List and show built-in scenarios (survey, flock, drift).", no_args_is_help=True)
root.app.add_typer(app, name="scenarios")


@app.command("list")
def list_scenarios() -> None:
    """List the built-in scenarios of every kind."""
    console.print(scenario_list_table(builtin_scenarios()))


@app.command("show")
def show(name: str = typer.Argument(..., help="Built-in scenario name or TOML file (any kind).")) -> None:
    """Show a scenario's settings after validation."""
    console.print(scenario_show_table(load_scenario(name)))
