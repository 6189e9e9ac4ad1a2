"""Terminal tables (rich) of the built-in scenarios of every kind (survey, flock, drift).

Every value is turned into plain text here (numpy scalars and arrays included, which rich would otherwise
read as markup or print blank) and escaped, since scenario files are user input.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np
from rich.markup import escape
from rich.table import Table

from oceanloc.config.drift import DriftScenario
from oceanloc.config.flock import FlockScenario
from oceanloc.config.survey import SurveyScenario
from oceanloc.planning.site_planners import site_planner_label
from oceanloc.units import DEG

Scenario = SurveyScenario | FlockScenario | DriftScenario


def scenario_kind(scenario: Scenario) -> str:
    """``survey``, ``flock`` or ``drift``."""
    if isinstance(scenario, SurveyScenario):
        return "survey"
    return "flock" if isinstance(scenario, FlockScenario) else "drift"


def scenario_summary(scenario: Scenario) -> str:
    """One line: the numbers that tell scenarios of a kind apart."""
    if isinstance(scenario, SurveyScenario):
        planner = site_planner_label(scenario.planner)
        return f"M = {scenario.n_transponders}, N = {scenario.epochs}, planner {planner}"
    if isinstance(scenario, FlockScenario):
        nodes = scenario.nodes
        return f"{nodes.count} nodes ({nodes.layout}), {scenario.kind}, {scenario.duration_s:g} s"
    return f"planner {scenario.planner}, {type(scenario.current).__name__}"


def scenario_list_table(scenarios: Sequence[Scenario]) -> Table:
    """Every built-in scenario: kind, name, summary and description."""
    table = Table(title="Built-in scenarios")
    for col in ("kind", "name", "summary", "description"):
        table.add_column(col, overflow="fold")
    for s in scenarios:
        table.add_row(scenario_kind(s), escape(s.name), escape(scenario_summary(s)), escape(s.description))
    return table


def scenario_show_table(scenario: Scenario) -> Table:
    """A scenario's validated settings, one row per setting, units in the row names."""
    table = Table(title=f"{escape(scenario.name)} ({scenario_kind(scenario)} scenario)", show_header=False)
    table.add_column("setting", style="bold")
    table.add_column("value", overflow="fold")
    rows = _survey_rows(scenario) if isinstance(scenario, SurveyScenario) else _field_rows(scenario)
    for name, value in rows:
        table.add_row(escape(name), escape(value))
    return table


def _survey_rows(s: SurveyScenario) -> list[tuple[str, str]]:
    planner = s.planner
    return [
        ("description", s.description),
        ("transponders (E, N, U) m", "\n".join(format_value(p) for p in s.transponders_enu_m)),
        ("start (E, N, U) m", format_value(s.start_enu_m)),
        ("start yaw deg (ccw from east)", f"{s.start_yaw_rad / DEG:.1f}"),
        ("speed m/s", f"{s.speed_mps:g}"),
        ("period s", f"{s.period_s:g}"),
        ("max yaw rate deg/s", f"{s.max_yaw_rate_rad_s / DEG:.1f}"),
        ("sigma range m", f"{s.sigma_range_m:g}"),
        ("prior sigma (E, N, U) m", format_value(np.sqrt(np.diag(s.prior_cov_m2)))),
        ("epochs N", str(s.epochs)),
        ("planner", site_planner_label(planner)),
        ("planner horizon k, reach d_max m", f"{planner.horizon}, {planner.max_distance_m:g}"),
        (
            "estimator delta_min m, max iterations",
            f"{s.estimator.delta_min_m:g}, {s.estimator.max_iterations}",
        ),
        ("Monte Carlo runs, seed", f"{s.runs}, {s.seed}"),
    ]


def _field_rows(obj: Any, prefix: str = "") -> list[tuple[str, str]]:
    """One row per dataclass field (nested settings flattened as ``table.field``); names keep their unit
    suffixes (``_m``, ``_s``, ``_rad``)."""
    rows = []
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        name = f"{prefix}{f.name}"
        if dataclasses.is_dataclass(value) and not isinstance(value, type) and _is_settings(value):
            rows.extend(_field_rows(value, prefix=f"{name}."))
        else:
            rows.append((name, format_value(value)))
    return rows


def _is_settings(value: Any) -> bool:
    """Settings tables (flattened) rather than models such as a current field (summarized)."""
    return type(value).__name__.endswith(("Settings", "Budget"))


def format_value(value: Any) -> str:
    """Plain text for a setting: floats with up to 6 significant digits, arrays row by row (large ones by
    shape), other objects by their type name."""
    if value is None or isinstance(value, bool | int | str):
        return str(value)
    if isinstance(value, float | np.floating):
        return f"{float(value):.6g}"
    if isinstance(value, np.integer):
        return str(int(value))
    if isinstance(value, np.ndarray | list | tuple):
        arr = np.asarray(value)
        if arr.dtype.kind not in "fiub":
            return ", ".join(format_value(v) for v in value)
        if arr.size > 24:
            return f"array of shape {arr.shape}"
        if arr.ndim <= 1:
            return "[" + ", ".join(format_value(v) for v in arr.ravel()) + "]"
        return "\n".join(format_value(row) for row in arr)
    return type(value).__name__
