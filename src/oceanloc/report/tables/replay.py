"""Terminal tables (rich) for replays on recorded data (journal Tables VII and IX, GNSS-A replays).

Every numeric column header states its unit; record-set names (file names) are escaped; the tables fit
100 columns.
"""

from __future__ import annotations

from rich import box
from rich.markup import escape
from rich.table import Table

from oceanloc.field.replay import planner_label
from oceanloc.reproduce.garcia2019_replay import GnssaReplay, LogsReplay, ReplayExperiment
from oceanloc.units import DEG


def _unit(unit_m: float) -> str:
    return "cm" if unit_m == 0.01 else "m"


def settings_line(exp: ReplayExperiment) -> str:
    """One line: the record set, its size and the replay's vehicle and reach settings (escaped)."""
    s = exp.settings
    return (
        f"[bold]{escape(exp.records.name)}[/bold]: {exp.records.n_records} records; "
        f"step {s.speed_mps * s.period_s:.2f} m per epoch, w_max {s.max_yaw_rate_rad_s / DEG:.0f} deg/s, "
        f"d_max {s.reach_m:.2f} m, planners' sigma {exp.records.sigma_planning_m:.4g} m"
    )


def rows_table(exp: ReplayExperiment, title: str, *, paper: bool = False, unit_m: float = 1.0) -> Table:
    """Table VII / IX: RMSEE of the first transponder and log det Y_n per epoch and planner, with the
    paper's values and the z-score of the log det means beside ours when ``paper``."""
    unit = _unit(unit_m)
    table = Table(
        title=escape(title),
        caption="log det: ln det Y_n of the information matrix (eq. 32; Y in m^-2), mean and std over runs; "
        "z: difference of the means over their standard error (dimensionless)",
        box=box.SIMPLE_HEAD,
        pad_edge=False,
        collapse_padding=True,
    )
    ours = ["epoch", "planner", f"RMSEE {unit}", "log det", "σ log det"]
    cols = [*ours[:3], f"paper {unit}", ours[3], "paper", ours[4], "paper", "z", "source"] if paper else ours
    for col in cols:
        table.add_column(col, justify="left" if col in ("planner", "source") else "right")
    rows = exp.rows
    for i, r in enumerate(rows):
        cells = [f"n = {r.epoch}" if i == 0 or rows[i - 1].epoch != r.epoch else "", planner_label(r.planner)]
        cells.append(f"{r.rmse_m / unit_m:.2f}")
        if paper:
            cells.append(_opt(r.paper_rmse_m, scale=unit_m))
        cells.append(f"{r.logdet_mean:.2f}")
        if paper:
            cells.append(_opt(r.paper_logdet_mean))
        cells.append(f"{r.logdet_std:.2f}")
        if paper:
            cells += [_opt(r.paper_logdet_std), _opt(r.logdet_z, "+.1f"), _short_source(r.paper_source)]
        last = i == len(rows) - 1 or rows[i + 1].epoch != r.epoch
        table.add_row(*cells, end_section=last and i != len(rows) - 1)
    return table


def convergence_table(exp: ReplayExperiment, *, unit_m: float = 1.0) -> Table:
    """Per planner against the recorded order at the last epoch: final metrics, epochs to match it,
    NEES, snap distance, planning time, share of converged MAP solves."""
    unit = _unit(unit_m)
    n = exp.settings.epochs
    table = Table(
        title=f"Convergence against the recorded order, n = {n}",
        caption="n RMSEE / n log det: the epoch from which a planner stays at least as good as the recorded "
        f"order at n = {n}; NEES: mean at n = {n} ({3 * exp.records.n_transponders} if consistent); snap: "
        "mean distance from the planned point to the record used (eq. 31); conv: MAP solves that met the "
        "step test within J_max",
        box=box.SIMPLE_HEAD,
        pad_edge=False,
        collapse_padding=True,
    )
    for col in (
        "planner", f"RMSEE {unit}", "log det", "n RMSEE", "n log det", "NEES", "snap m", "plan ms", "conv %",
    ):  # fmt: skip
        table.add_column(col, justify="left" if col == "planner" else "right")
    for c in exp.convergence:
        table.add_row(
            planner_label(c.planner), f"{c.rmse_final_m / unit_m:.2f}", f"{c.logdet_final:.2f}",
            _epoch(c.epochs_to_recorded_rmse, n), _epoch(c.epochs_to_recorded_logdet, n),
            f"{c.nees_final:.1f}", f"{c.snap_distance_m:.2f}", f"{1e3 * c.plan_time_s:.2f}",
            f"{100 * c.converged_fraction:.1f}",
        )  # fmt: skip
    return table


def gnssa_reference_line(res: GnssaReplay) -> str:
    """The reference solution a GNSS-A replay is measured against (all pings)."""
    e, n, u = res.reference.position_enu_m
    return (
        f"[bold]{escape(res.survey)}[/bold]: reference (solution over all pings, "
        f"{res.reference.pings_used} used) "
        f"E {e:+.3f} N {n:+.3f} U {u:+.3f} m (file frame)"
    )


def logs_reference_line(res: LogsReplay) -> str:
    """The reference of a log replay and the robust estimate over every range, ENU from its origin."""
    origin = ""
    if res.logs is not None:
        o = res.logs.origin
        origin = f" (ENU from {o.lat_deg:.7f}, {o.lon_deg:.7f}, {o.h_m:.3f} m, {res.logs.origin_source})"
    truth = "; ".join(f"beacon {b} {_triple(v)}" for b, v in res.truth_enu_m.items())
    est = "; ".join(f"beacon {b} {_triple(v)}" for b, v in res.estimate_enu_m.items())
    return escape(
        f"reference ({res.truth_source}): {truth} m; robust estimate over every range: {est} m{origin}"
    )


def _short_source(source: str) -> str:
    """``journal Table VII`` -> ``journal VII``, ``thesis Table 6.2`` -> ``thesis 6.2``."""
    return source.replace(" Table ", " ")


def _opt(value: float | None, fmt: str = ".2f", scale: float = 1.0) -> str:
    return "-" if value is None else format(value / scale, fmt)


def _epoch(value: int | None, n: int) -> str:
    return f"> {n}" if value is None else str(value)


def _triple(v) -> str:
    return "(" + ", ".join(f"{float(x):+.2f}" for x in v) + ")"
