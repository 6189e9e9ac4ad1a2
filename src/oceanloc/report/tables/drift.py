"""Terminal tables (rich) for the drift-planning commands: a plan, path following, a position swap and the
DR-RRT* Monte Carlo (thesis Table 4). Every numeric column or row names its unit; text from a scenario
file (names, descriptions, file paths) is escaped so rich prints it as written. Tables fit 100 columns.
"""

from __future__ import annotations

import math

import numpy as np
from rich.markup import escape
from rich.table import Table

from oceanloc.evaluation.drift import ScenarioPlan
from oceanloc.evaluation.path_following import FollowingStudy, SwapStudy
from oceanloc.reproduce.dillard_drrt import (
    THESIS_DIRECT_FLIGHT_WH,
    THESIS_TABLE4,
    DillardReport,
    reference_options_note,
)

__all__ = [
    "dillard_fields_table",
    "dillard_notes",
    "dillard_table",
    "ensemble_table",
    "following_table",
    "plan_table",
    "swap_notes",
    "swap_table",
]


def _key_value(title: str) -> Table:
    table = Table(title=title)
    table.add_column("quantity")
    table.add_column("value", overflow="fold")
    return table


def _pct(x: float) -> str:
    return "-" if not math.isfinite(x) else f"{100 * x:.1f}"


def _ratio(x: float) -> str:
    return f"{x:.3f}" if math.isfinite(x) else "-"


def _pm(mean: float, std: float) -> str:
    """``mean +- std`` with two decimals; ``-`` for a missing value (a std of fewer than two runs)."""
    if not math.isfinite(mean):
        return "-"
    return f"{mean:.2f} +- {std:.2f}" if math.isfinite(std) else f"{mean:.2f}"


def plan_table(plan: ScenarioPlan) -> Table:
    """A drift plan: status, route, flights, energies (IV.14), duration, compute time, unit convention."""
    res, problem = plan.result, plan.problem
    table = _key_value(f"{escape(plan.scenario.name)}: {plan.planner}")
    table.add_row("status", escape(f"{res.status.value} - {res.message}"))
    table.add_row("currents", escape(plan.scenario.currents_description))
    table.add_row(
        "start -> goal (m)",
        f"{problem.start_m.tolist()} -> {problem.goal_m.tolist()} (within {problem.goal_tolerance_m:g})",
    )
    if res.path is not None and plan.energy is not None:
        path, account = res.path, plan.energy
        table.add_row(
            "flights, distance flown (m)", f"{path.hops_m().shape[0]}, {path.flight_distance_m:.0f}"
        )
        table.add_row("flight energy (Wh)", f"{res.flight_energy_wh:.2f}")
        table.add_row("direct flight (Wh), saving (%)", f"{res.direct_flight_wh:.2f}, {_pct(res.saving)}")
        table.add_row(
            "duration, drift (h)", f"{account.duration_s / 3600:.2f}, {path.drift_time_s / 3600:.2f}"
        )
        table.add_row(
            "energy balance IV.14 (Wh)",
            f"solar +{account.solar_wh:.1f}, loads -{account.loads_wh:.1f}, "
            f"flight -{account.flight_wh:.1f}: net {account.net_wh:+.1f}",
        )
    if res.path is not None:
        objective = (
            "time to goal (s)" if problem.objective == "time" else "objective: flight + time price (Wh)"
        )
        deadline = "" if problem.max_duration_s is None else f", deadline {problem.max_duration_s / 3600:g} h"
        table.add_row(objective + deadline, f"{res.cost:.2f}" if math.isfinite(res.cost) else "-")
        if plan.scenario.time_origin is not None:
            table.add_row("start", f"{plan.scenario.time_origin} + {problem.t0_s / 3600:.2f} h")
    table.add_row("compute (ms)", f"{1e3 * res.compute_s:.1f}")
    table.add_row("units", problem.energy.convention)
    return table


def ensemble_table(plan: ScenarioPlan) -> Table | None:
    """Each candidate plan of an ensemble (made in the mean or in one member) flown in every member: its
    expected objective and the spread of its flight energy; the chosen plan is marked."""
    ens = plan.ensemble
    if ens is None:
        return None
    table = Table(title=f"Ensemble of {ens.n_members} members: every candidate flown in every member")
    table.add_column("plan made in")
    table.add_column(f"expected objective ({ens.unit})", justify="right")
    table.add_column("flight energy mean +- std (Wh)", justify="right")
    table.add_column("min - max (Wh)", justify="right")
    for row in ens.spread():
        mark = " (chosen)" if row["chosen"] else ""
        table.add_row(
            row["candidate"] + mark,
            f"{row['objective_mean']:.2f}" if math.isfinite(row["objective_mean"]) else "-",
            _pm(row["energy_wh_mean"], row["energy_wh_std"]),
            f"{row['energy_wh_min']:.2f} - {row['energy_wh_max']:.2f}"
            if math.isfinite(row["energy_wh_max"])
            else "-",
        )
    return table


def following_table(study: FollowingStudy) -> Table:
    """Path following: the true current, watch circle, arrival rate, energies and replans (thesis V.D)."""
    fs, s = study.settings, study.summary
    table = _key_value(
        f"Path following: {escape(study.scenario)}, {study.planner}, {s.runs} runs (thesis V.D)"
    )
    table.add_row(
        "true current",
        f"{fs.current_scale:g} x planning current rotated {np.degrees(fs.current_rotation_rad):g} deg "
        f"+ {fs.noise_mps:g} m/s noise (tau {fs.noise_correlation_s:g} s)",
    )
    table.add_row("watch circle, stray (m)", f"{fs.watch_circle_m:g}, {fs.stray_m:g}")
    table.add_row("arrival rate (%)", _pct(s.arrival_rate))
    table.add_row("planned flight energy (Wh)", f"{s.planned_energy_wh:.2f}")
    table.add_row("flown, arrivals (Wh)", f"{s.flight_energy_wh_mean:.2f}")
    table.add_row(
        "extra over plan, arrivals (Wh)", f"{s.extra_energy_wh_mean:+.2f} +- {s.extra_energy_wh_std:.2f}"
    )
    table.add_row("replans per run, arrivals", f"{s.replans_mean:.2f}")
    table.add_row("duration, arrivals (h)", f"{s.duration_h_mean:.2f}")
    table.add_row("units", study.problem.energy.convention)
    return table


def swap_table(study: SwapStudy) -> Table:
    """Both drifters of a position swap, one column each: the plan, then one run following it in the
    true current."""
    table = Table(title=f"Position swap: {escape(study.scenario)}, {study.planner}")
    table.add_column("quantity")
    for k in range(len(study.swap.results)):
        table.add_column(f"drifter {k + 1}", justify="right")
    rows: dict[str, list[str]] = {
        label: []
        for label in (
            "plan status",
            "flights",
            "flight energy (Wh)",
            "saving (%)",
            "duration (h)",
            "followed: arrived",
            "followed: flown (Wh)",
            "followed: replans",
        )
    }
    for res, f in zip(study.swap.results, study.followed, strict=True):
        path = res.path
        rows["plan status"].append(res.status.value)
        rows["flights"].append("-" if path is None else str(path.hops_m().shape[0]))
        rows["flight energy (Wh)"].append("-" if path is None else f"{res.flight_energy_wh:.2f}")
        rows["saving (%)"].append(_pct(res.saving))
        rows["duration (h)"].append("-" if path is None else f"{path.duration_s / 3600:.2f}")
        rows["followed: arrived"].append("-" if f is None else ("yes" if f.arrived[0] else "no"))
        rows["followed: flown (Wh)"].append("-" if f is None else f"{f.flight_energy_wh[0]:.2f}")
        rows["followed: replans"].append("-" if f is None else str(int(f.replans[0])))
    for label, cells in rows.items():
        table.add_row(label, *cells)
    return table


def swap_notes(study: SwapStudy) -> list[str]:
    """Lines printed under :func:`swap_table`."""
    return [
        f"closest approach of the planned schedules: {study.swap.min_separation_m:.0f} m",
        f"units: {study.swap.problems[0].energy.convention}",
    ]


def dillard_table(report: DillardReport) -> Table:
    """Ours beside thesis Table 4, one row per planner and under it the thesis' row: success, flight
    energy (mean +- std over successful runs), saving, compute time and the ratio to the best achievable."""
    table = Table(
        title=f"DR-RRT* Monte Carlo on the fixed field ({report.runs} runs per planner) - thesis Table 4"
    )
    table.add_column("planner", no_wrap=True, min_width=25)
    for col in ("success (%)", "energy (Wh)", "saving (%)", "compute (ms)", "/ best"):
        table.add_column(col, justify="right")
    names = list(report.planners)
    for name, s in report.planners.items():
        t = THESIS_TABLE4.get(name)
        table.add_row(
            name,
            _pct(s.success_rate),
            _pm(s.energy_wh_mean, s.energy_wh_std),
            _pct(s.saving_mean),
            f"{1e3 * s.compute_s_median:.1f}",
            _ratio(s.ratio_to_best),
            end_section=t is None and name != names[-1],
        )
        if t is not None:
            table.add_row(
                "  thesis Table 4",
                "-",
                f"{t['energy_wh_mean']:.2f} +- {t['energy_wh_std']:.2f}",
                f"{100 * t['saving_mean']:.0f}",
                f"{1e3 * t['compute_s_mean']:.0f} +- {1e3 * t['compute_s_std']:.0f}",
                "-",
                style="dim",
                end_section=True,
            )
    return table


def dillard_notes(report: DillardReport) -> list[str]:
    """Lines printed under :func:`dillard_table`: baselines, iterations, units, reference lattice."""
    saving = 1 - report.best_achievable_wh / report.direct_flight_wh
    return [
        f"direct flight {report.direct_flight_wh:.2f} Wh (thesis {THESIS_DIRECT_FLIGHT_WH} Wh); "
        f"best achievable {report.best_achievable_wh:.2f} Wh (saving {100 * saving:.1f} %)",
        f"thesis-optimality-seeking: {report.iterations} iterations",
        "compute: ours the median per run; the thesis' mean +- std (MATLAB, Core i7-2600)",
        f"units: {report.convention}",
        reference_options_note(report.reference_options),
    ]


def dillard_fields_table(report: DillardReport) -> Table | None:
    """Every planner across the random fields (``None`` when there were none): pooled success, the mean
    over fields of each field's mean saving, the worst field's saving, the mean ratio to each field's best
    achievable, and the median compute time."""
    if not report.fields or report.random_fields is None:
        return None
    n_fields = report.field_best_wh.size
    table = Table(
        title=f"Across {n_fields} random field{'s' if n_fields != 1 else ''} (the thesis' generator), "
        f"{report.random_fields.n_runs} runs per planner"
    )
    table.add_column("planner", no_wrap=True, min_width=25)
    for col in (
        "success (%)",
        "saving (%)",
        "worst field saving (%)",
        "/ best (field mean)",
        "compute (ms)",
    ):
        table.add_column(col, justify="right")
    for name, s in report.fields.items():
        table.add_row(
            name,
            _pct(s.success_rate),
            _pct(s.saving_mean),
            _pct(s.saving_min_field),
            _ratio(s.ratio_to_best_mean),
            f"{1e3 * s.compute_s_median:.1f}",
        )
    return table
