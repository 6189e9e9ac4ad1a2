"""Terminal tables (rich) for flock tracking, dilution of precision and time delays.

Every numeric column states its unit in the header (or, where rows mix units, in a ``unit`` column); text
that came from a user (file and scenario names) is escaped; every table fits 100 columns.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from rich.markup import escape
from rich.table import Table

from oceanloc.estimation.time_delay import RecordingDelay
from oceanloc.evaluation.flock import FilterMonteCarlo
from oceanloc.planning.dop import DopMap, PlacementResult, hdop_unit
from oceanloc.reproduce.dillard_filters import THESIS_RUN_TIME_S, DillardFiltersResult
from oceanloc.reproduce.dillard_lab_tdoa import LabTdoaResult

__all__ = [
    "delay_table",
    "filter_stats_table",
    "hdop_map_table",
    "lab_table",
    "placement_summary",
    "placement_table",
    "table_2",
]

_KIND_LABEL = {"bearing": "bearing-only", "range": "range-only", "tdoa": "TDOA"}


def _sig(value: float, digits: int) -> str:
    """``value`` with ``digits`` significant digits in fixed point (``628.2``, ``14820``, ``0.06606``);
    exponent notation only outside ``1e-3 <= |value| < 1e6``."""
    if not np.isfinite(value):
        return "-"
    if value == 0:
        return "0"
    magnitude = int(np.floor(np.log10(abs(value))))
    if not -3 <= magnitude < 6:
        return f"{value:.{digits - 1}e}"
    decimals = max(0, digits - 1 - magnitude)
    return f"{round(value, decimals):.{decimals}f}"


def _pm(mean: float, spread: float) -> str:
    return f"{_sig(mean, 4)} ± {_sig(spread, 2)}"


def table_2(result: DillardFiltersResult) -> Table:
    """Mean square error per state: the thesis' single run beside our mean ± sd (thesis scenario), and the
    paired EKF - UKF difference ± its standard error. Units per row (the states mix m² and (m/s)²)."""
    mc = result.monte_carlo
    kind = _KIND_LABEL.get(mc.scenario.kind, mc.scenario.kind)
    thesis = result.is_thesis
    if thesis:
        title = f"Table 2: {kind} tracking MSE, thesis (1 run) vs oceanloc ({mc.runs} runs)"
    else:
        name = escape(mc.scenario.name)
        title = f"{name}: {kind} tracking MSE over {mc.runs} runs ({mc.scenario.duration_s:g} s)"
    table = Table(title=title)
    table.add_column("state")
    table.add_column("unit")
    columns = (
        ("thesis\nEKF", thesis),
        ("EKF\nmean ± sd", True),
        ("thesis\nUKF", thesis),
        ("UKF\nmean ± sd", True),
        ("thesis\nΔ", thesis),
        ("Δ = EKF - UKF\n± SE (paired)", True),
    )
    for col, shown in columns:
        if shown:
            table.add_column(col, justify="right")
    for r in result.rows:
        cells = [
            f"{r.thesis_ekf:.4f}" if r.thesis_ekf is not None else None,
            _pm(r.ekf_mean, r.ekf_sd),
            f"{r.thesis_ukf:.4f}" if r.thesis_ukf is not None else None,
            _pm(r.ukf_mean, r.ukf_sd),
            f"{r.thesis_delta:.4f}" if r.thesis_delta is not None else None,
            _pm(r.delta, r.delta_se),
        ]
        table.add_row(r.state, r.unit, *(c for c in cells if c is not None))
    return table


def filter_stats_table(result: DillardFiltersResult) -> Table:
    """Per filter variant: position MSE, NEES, RMSE over the bound and the wall time of one run."""
    mc: FilterMonteCarlo = result.monte_carlo
    n_state = mc.truth.shape[-1]
    table = Table(title=f"Per filter: consistency and cost (NEES is {n_state} for a consistent filter)")
    table.add_column("filter")
    table.add_column("motion model")
    for col in ("pos. MSE (m²)", "NEES (1)", "RMSE/√PCRLB", "run (s)"):
        table.add_column(col, justify="right")
    if result.is_thesis:
        table.add_column("thesis (s)", justify="right")
    for key, v in mc.variants.items():
        row = [
            v.variant.filter.upper() + (" ctrl" if v.variant.is_control else ""),
            v.variant.motion,
            _sig(v.position_mse_m2, 4),
            _sig(v.nees_mean, 3),
            _sig(v.rmse_over_sqrt_pcrlb, 3),
            _sig(v.step_time_s * mc.times_s.size, 3),
        ]
        if result.is_thesis:
            row.append(f"{THESIS_RUN_TIME_S[key]:.2f}" if key in THESIS_RUN_TIME_S else "")
        table.add_row(*row)
    table.caption = gate_caption(mc)
    return table


def gate_caption(mc: FilterMonteCarlo) -> str:
    """One line per run set: the NIS gate, the share of epochs it rejected and the runs that diverged."""
    gate = mc.scenario.filters.gate_probability
    head = f"NIS gate {gate:g}" if gate else "NIS gate off"
    parts = [
        f"{key} {100 * float(np.mean(v.gated_per_run)) / mc.times_s.size:.2f} {v.diverged_runs}/{mc.runs}"
        for key, v in mc.variants.items()
    ]
    return f"{head}; gated epochs (%), diverged runs: " + ", ".join(parts)


def lab_table(result: LabTdoaResult) -> Table:
    """The lab test's statistics over runs, the thesis' single-run values beside (thesis scenario)."""
    mc = result.monte_carlo
    if result.is_thesis:
        title = f"Lab TDOA UKF test (Chapter V.C): thesis (1 run) vs oceanloc ({mc.runs} runs)"
    else:
        title = f"{escape(mc.scenario.name)}: UKF tracking over {mc.runs} runs"
    table = Table(title=title)
    table.add_column("quantity")
    table.add_column("unit")
    if result.is_thesis:
        table.add_column("thesis", justify="right")
    table.add_column("mean ± sd", justify="right")
    table.add_column("median", justify="right")
    for r in result.rows:
        cells = [r.quantity, r.unit]
        if result.is_thesis:
            cells.append(r.thesis or "-")
        table.add_row(*cells, _pm(r.mean, r.sd), _sig(r.median, 4))
    gate = mc.scenario.filters.gate_probability
    table.caption = (
        f"{f'NIS gate {gate:g}' if gate else 'NIS gate off'}: {float(np.mean(mc.gated)):.1f} epochs gated per"
        f" run; {int(np.sum(mc.diverged_epoch >= 0))}/{mc.runs} runs diverged"
    )
    return table


def hdop_map_table(dop: DopMap) -> Table:
    """Minimum, where it is, median and the singular share of an HDOP map."""
    unit = dop.hdop_unit
    table = Table(title=f"{dop.kind} HDOP map: {dop.x_m.size} x {dop.y_m.size} cells")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    best = dop.minimum()
    if best is not None:
        finite = np.isfinite(dop.hdop)
        table.add_row(f"minimum HDOP ({unit})", f"{best[0]:.4g}")
        table.add_row("moving node at the minimum, east, north (m)", f"({best[1]:.1f}, {best[2]:.1f})")
        table.add_row(f"median HDOP ({unit})", f"{np.median(dop.hdop[finite]):.4g}")
    table.add_row("singular cells (%)", f"{100 * (1 - np.isfinite(dop.hdop).mean()):.2f}")
    return table


def placement_table(result: PlacementResult) -> Table:
    """The placed nodes: position, range and true bearing from the target (clockwise from north)."""
    n = result.nodes_m.shape[0]
    table = Table(title=f"{result.kind} HDOP-optimal placement of {n} node(s)")
    for col in ("node", "east (m)", "north (m)", "range (m)", "bearing (° cw from N)"):
        table.add_column(col, justify="right")
    ranges, bearings = result.ranges_bearings()
    for i, p in enumerate(result.nodes_m):
        table.add_row(
            str(i + 1), f"{p[0]:.2f}", f"{p[1]:.2f}", f"{ranges[i]:.2f}", f"{np.degrees(bearings[i]):.1f}"
        )
    for j, p in enumerate(result.fixed_nodes_m):
        d = p - result.target_m
        bearing = np.degrees(np.mod(np.arctan2(d[0], d[1]), 2 * np.pi))
        table.add_row(f"fixed {j + 1}", f"{p[0]:.2f}", f"{p[1]:.2f}", f"{np.hypot(*d):.2f}", f"{bearing:.1f}")
    return table


def placement_summary(result: PlacementResult) -> str:
    """One line: the HDOP found, the even ring's and the spread of the local solutions."""
    unit = hdop_unit(result.kind, result.sigma)
    return (
        f"HDOP {result.hdop:.5g} {unit}; even ring {result.ring_hdop:.5g} ({100 * result.gap:.2f} % worse); "
        f"{result.start_hdop.size} starts reach "
        f"{result.start_hdop.min():.5g} .. {result.start_hdop.max():.5g}"
    )


def delay_table(result: RecordingDelay) -> Table:
    """The delay of A relative to B, which file heard the signal first and how clear the peak is."""
    est = result.estimate
    names = [escape(Path(s).name) for s in result.sources]
    table = Table(title=f"TDOA {names[0]} (A) - {names[1]} (B), {est.method}")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_row("delay, arrival at A minus at B (s)", f"{est.delay_s:.9f}")
    table.add_row("delay (samples)", f"{est.delay_samples:.4f}")
    sd = f"{est.delay_sd_s:.3g} ({est.delay_sd_samples:.3g} samples)" if np.isfinite(est.delay_sd_s) else "-"
    table.add_row("delay sd, Cramer-Rao bound (s)", sd)
    table.add_row("band used (Hz)", f"{est.band_hz[0]:.0f} .. {est.band_hz[1]:.0f}")
    table.add_row("heard first", f"{est.first} ({escape(Path(result.first_source).name)})")
    table.add_row("peak ratio (1)", f"{est.peak_ratio:.3g}")
    table.add_row("sample rate (Hz)", f"{est.sample_rate_hz:g}")
    table.add_row("formats, channel", f"{result.formats[0]}, {result.formats[1]}; channel {result.channel}")
    return table
