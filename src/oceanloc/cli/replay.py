"""``oceanloc replay``: planners choosing among recorded measurements (journal Section VI, PLANS eq. 31)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.table import Table

from oceanloc.cli._common import (
    FiguresOut,
    JsonOut,
    Scheduler,
    Seed,
    Workers,
    console,
    ensure_dir,
    err_console,
    progress_bar,
    write_json,
)
from oceanloc.errors import ConfigError
from oceanloc.estimation.gnssa import GnssaOptions
from oceanloc.evaluation.montecarlo import open_executor
from oceanloc.field.replay import DEFAULT_PLANNERS, RecordSet, ReplaySettings, planner_label, planner_settings
from oceanloc.geo.enu import EnuOrigin
from oceanloc.io.gnssa import lajolla_paths, read_gnssa, survey_sound_speeds_mps
from oceanloc.reproduce import garcia2019_replay as rep
from oceanloc.sim.logs import PIER_ORIGIN

app = typer.Typer(
    help="Replay planning on recorded data: each planner chooses which recorded ping to use next "
    "(nearest recorded location to its planned point, PLANS eq. 31), over a Monte Carlo of prior draws.",
    no_args_is_help=True,
)

_READINGS = (
    "Readings: eq. (31) picks the unused record nearest (horizontally) to the planned point among those "
    "within d_max of the vehicle, else the nearest unused record; each ping is used once; the vehicle moves "
    "to the chosen record; 'recorded' is the log's own order from the start record. Each run draws its "
    "prior mean from N(reference, P_0), P_0 = diag(100, 100, 2)^2 m^2; all planners share the prior draws."
)

Runs = Annotated[int, typer.Option("--runs", min=2, help="Monte Carlo runs per planner (paper: 100).")]
Epochs = Annotated[int, typer.Option("--epochs", min=1, help="Measurement epochs N (paper: 50).")]
Planners = Annotated[
    str,
    typer.Option(
        "--planners",
        help="Comma-separated: recorded (the log's order), k0 (random yaw), k1..k10 (look-ahead), greedy "
        "(D-optimal point within d_max), random-disk.",
    ),
]
PriorSigma = Annotated[
    str, typer.Option("--prior-sigma", help="Prior 1-sigma E,N,U of each draw, m (journal: 100,100,2).")
]
_ALL_PLANNERS = ",".join(DEFAULT_PLANNERS)
YawRate = Annotated[float, typer.Option("--yaw-rate", min=0.0, help="w_max of the k planners, deg/s.")]


@app.command(
    "gnssa",
    help="Replay GNSS-A surveys: the reference is the robust solution over all pings (oceanloc localize "
    "gnssa); the replayed estimate's error is measured against it.\n\n" + _READINGS + "\n\nGNSS-A: one epoch "
    "advances the recording's median ping spacing (--step) and d_max is twice that (--reach); the "
    "measurement is c(t) TWTT with the reference's sound speed and per-ping sigma.",
)
def gnssa_command(
    files: Annotated[
        list[Path] | None,
        typer.Argument(
            help="GNSS-A ping files; none: the five packaged La Jolla surveys.", show_default=False
        ),
    ] = None,
    runs: Runs = 100,
    epochs: Epochs = 50,
    planners: Planners = _ALL_PLANNERS,
    seed: Seed = None,
    json_path: JsonOut = None,
    figures: FiguresOut = None,
    workers: Workers = None,
    scheduler: Scheduler = None,
    sound_speed: Annotated[
        list[float] | None,
        typer.Option(
            "--sound-speed",
            help="Prior sound speed, m/s: one value or one per file (default: "
            "the published value for known files).",
        ),
    ] = None,
    step: Annotated[
        float | None, typer.Option("--step", min=0.0, help="Metres per epoch (default: median ping spacing).")
    ] = None,
    reach: Annotated[
        float | None, typer.Option("--reach", min=0.0, help="d_max, m (default: 2 x step).")
    ] = None,
    yaw_rate: YawRate = 30.0,
    prior_sigma: PriorSigma = "100,100,2",
) -> None:
    """Table VII-style replay of GNSS-A surveys under every planner."""
    seed = 2019 if seed is None else seed
    names = _parse_planners(planners)
    paths = list(files) if files else lajolla_paths()
    if not files:
        err_console.print(f"no file given: using the {len(paths)} packaged La Jolla surveys")
    speeds = survey_sound_speeds_mps(paths, sound_speed or [])
    sigma = _vector(prior_sigma, "--prior-sigma")
    surveys = [read_gnssa(p) for p in paths]

    def settings(records: RecordSet) -> ReplaySettings:
        return rep.gnssa_replay_settings(
            records, epochs=epochs, step_m=step or None, reach_m=reach or None,
            max_yaw_rate_deg_s=yaw_rate, prior_sigma_enu_m=sigma,
        )  # fmt: skip

    results = []
    total = len(paths) * len(names) * runs
    with open_executor(scheduler, workers) as executor, progress_bar(total, "replay runs") as advance:
        for survey, speed in zip(surveys, speeds, strict=True):
            results.append(
                rep.replay_gnssa(
                    survey,
                    GnssaOptions(sound_speed_mps=speed),
                    runs=runs,
                    seed=seed,
                    planners=names,
                    settings=settings,
                    executor=executor,
                    progress=advance,
                )
            )
    for res in results:
        exp = res.experiment
        ref = res.reference
        e, n, u = ref.position_enu_m
        console.print(
            f"[bold]{res.survey}[/bold]: {exp.records.n_records} pings; reference (all pings) E {e:+.3f} "
            f"N {n:+.3f} U {u:+.3f} m; {_settings_line(exp)}",
            highlight=False,
        )
        console.print(_rows_table(exp, f"{res.survey}: {runs} runs, seed {seed}", unit_m=0.01))
        if exp.convergence:
            console.print(_convergence_table(exp, unit_m=0.01))
    if figures:
        out = ensure_dir(figures)
        for res in results:
            _figures(res.experiment, out, res.survey, unit_m=0.01)
        console.print(f"wrote figures to {out}")
    if json_path:
        write_json(
            json_path,
            {
                "seed": seed,
                "runs": runs,
                "epochs": epochs,
                "planners": names,
                "surveys": [
                    {
                        "file": r.survey,
                        "reference": {
                            "enu_m": r.reference.position_enu_m,
                            "sigma_enu_m": r.reference.sigma_enu_m,
                            "pings_used": r.reference.pings_used,
                        },
                        **rep.experiment_json(r.experiment),
                    }
                    for r in results
                ],
            },
        )


@app.command(
    "logs",
    help="Reproduce journal Tables VII (M = 1, beacon 1) and IX (M = 2) on a GPS + USBL log pair, with the "
    "paper's values (and the thesis' Tables 6.2 and 6.6 for greedy and random disk) beside ours.\n\n"
    + _READINGS
    + "\n\nLogs: p_V(1) = [8.62, -6.77, 0] m, phi(1) = 13 deg, 3 m/s, T = 1 s, w_max = 30 deg/s, "
    "d_max = 10 m, sigma_eps = 1.006 m; a record of Table IX is one range to each beacon within 3 s; "
    "ranges the robust estimator rejects as outliers are left out.",
)
def logs_command(
    gps: Annotated[Path, typer.Argument(help="NMEA 0183 GPS log (GGA with RMC or ZDA dates).")],
    ranges: Annotated[Path, typer.Argument(help="USBL range CSV (utc,beacon,range_m|owtt_s|twtt_s).")],
    truth: Annotated[
        list[str] | None,
        typer.Option(
            "--truth",
            help="Beacon position E,N,U in m, once per beacon in id order (default: the journal's "
            "9.21,1.68,-1.15 and 2.79,0.44,-1.15), or 'estimate' for the robust estimate over every range.",
        ),
    ] = None,
    origin: Annotated[
        str,
        typer.Option("--origin", help="ENU origin LAT,LON,H (default: the journal's) or 'first-fix'."),
    ] = f"{PIER_ORIGIN.lat_deg},{PIER_ORIGIN.lon_deg},{PIER_ORIGIN.h_m}",
    tables: Annotated[str, typer.Option("--tables", help="Which tables: VII, IX or VII,IX.")] = "VII,IX",
    runs: Runs = 100,
    epochs: Epochs = 50,
    planners: Planners = _ALL_PLANNERS,
    seed: Seed = None,
    json_path: JsonOut = None,
    figures: FiguresOut = None,
    workers: Workers = None,
    scheduler: Scheduler = None,
    sound_speed: Annotated[float, typer.Option(help="Sound speed for travel-time columns, m/s.")] = 1500.0,
    sigma_range: Annotated[float, typer.Option(min=0.0, help="sigma_eps of every range, m.")] = 1.006,
    max_gap: Annotated[float, typer.Option(help="Largest GPS gap to interpolate across, s.")] = 2.0,
    speed: Annotated[float, typer.Option("--speed", min=0.0, help="Speed of the k planners, m/s.")] = 3.0,
    reach: Annotated[float, typer.Option("--reach", min=0.0, help="d_max, m.")] = 10.0,
    yaw_rate: YawRate = 30.0,
    prior_sigma: PriorSigma = "100,100,2",
) -> None:
    """Tables VII and IX on recorded logs."""
    from oceanloc.io.nmea import read_nmea
    from oceanloc.io.usbl import align_ranges, read_usbl

    seed = 2019 if seed is None else seed
    names = _parse_planners(planners)
    table_names = [t.strip().upper() for t in tables.split(",") if t.strip()]
    truth_map = _parse_truth(truth)
    if sigma_range <= 0 or speed <= 0 or reach <= 0:
        raise ConfigError("--sigma-range, --speed and --reach must be positive")
    settings = rep.log_replay_settings(
        epochs=epochs, speed_mps=speed, reach_m=reach, max_yaw_rate_deg_s=yaw_rate,
        prior_sigma_enu_m=_vector(prior_sigma, "--prior-sigma"),
    )  # fmt: skip
    gps_log = read_nmea(gps)
    range_log = read_usbl(ranges, sound_speed_mps=sound_speed)
    qc = gps_log.qc.merge(range_log.qc)
    err_console.print("QC: " + qc.summary(max_lines=5), highlight=False)
    aligned = align_ranges(gps_log, range_log, origin=_parse_origin(origin), max_gap_s=max_gap)
    if aligned.range_m.size == 0:
        raise ConfigError(f"{ranges}: no range has a GPS fix within {max_gap} s in {gps}")
    total = len(table_names) * len(names) * runs
    with open_executor(scheduler, workers) as executor, progress_bar(total, "replay runs") as advance:
        result = rep.replay_logs(
            aligned, truth_enu_m=truth_map, tables=table_names, runs=runs, seed=seed, planners=names,
            settings=settings, sigma_range_m=sigma_range, executor=executor, progress=advance,
        )  # fmt: skip
    console.print(
        f"reference ({result.truth_source}): "
        + "; ".join(f"beacon {b} {_triple(v)}" for b, v in result.truth_enu_m.items())
        + " m; robust estimate over every range: "
        + "; ".join(f"beacon {b} {_triple(v)}" for b, v in result.estimate_enu_m.items())
        + " m",
        highlight=False,
    )
    titles = {"VII": "Table VII: one beacon (M = 1)", "IX": "Table IX: two beacons (M = 2), RMSEE of m = 1"}
    for name, exp in result.experiments.items():
        head = f"[bold]{exp.records.name}[/bold]: {exp.records.n_records} records"
        console.print(f"{head}; {_settings_line(exp)}")
        title = f"{titles[name]}, {runs} runs (paper 100), seed {seed}; z = (ours - paper) / SE"
        console.print(_rows_table(exp, title, paper=True))
        if exp.convergence:
            console.print(_convergence_table(exp))
    if figures:
        out = ensure_dir(figures)
        for name, exp in result.experiments.items():
            _figures(exp, out, f"table_{name.lower()}", unit_m=1.0)
        console.print(f"wrote figures to {out}")
    if json_path:
        write_json(
            json_path,
            {
                "seed": seed,
                "runs": runs,
                "epochs": epochs,
                "planners": names,
                "truth_source": result.truth_source,
                "truth_enu_m": {str(b): v for b, v in result.truth_enu_m.items()},
                "estimate_enu_m": {str(b): v for b, v in result.estimate_enu_m.items()},
                "tables": {name: rep.experiment_json(exp) for name, exp in result.experiments.items()},
            },
        )


def _parse_planners(text: str) -> list[str]:
    names = [p.strip().lower() for p in text.split(",") if p.strip()]
    if not names:
        raise ConfigError("--planners lists no planner")
    for name in names:
        planner_settings(name, 1.0)  # raises a ConfigError naming the valid choices
    return list(dict.fromkeys(names))


def _vector(text: str, option: str, size: int = 3) -> list[float]:
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise ConfigError(f"{option} must be {size} comma-separated numbers, got '{text}'") from None
    if len(values) != size or not all(np.isfinite(values)):
        raise ConfigError(f"{option} must be {size} comma-separated numbers, got '{text}'")
    return values


def _parse_truth(values: list[str] | None) -> dict[int, list[float]] | None:
    if not values:
        return {b + 1: list(v) for b, v in enumerate(rep.LOG_BEACONS_ENU_M)}
    if [v.strip().lower() for v in values] == ["estimate"]:
        return None
    return {b + 1: _vector(v, "--truth") for b, v in enumerate(values)}


def _parse_origin(text: str) -> EnuOrigin | None:
    if text.strip().lower() == "first-fix":
        return None
    lat, lon, h = _vector(text, "--origin")
    return EnuOrigin(lat_deg=lat, lon_deg=lon, h_m=h)


def _settings_line(exp: rep.ReplayExperiment) -> str:
    s = exp.settings
    return (
        f"step {s.speed_mps * s.period_s:.2f} m per epoch, "
        f"w_max {np.degrees(s.max_yaw_rate_rad_s):.0f} deg/s, "
        f"d_max {s.reach_m:.2f} m, planners' sigma {exp.records.sigma_planning_m:.4g} m"
    )


def _rows_table(exp: rep.ReplayExperiment, title: str, *, paper: bool = False, unit_m: float = 1.0) -> Table:
    unit = "cm" if unit_m == 0.01 else "m"
    table = Table(title=title)
    ours = ["epoch", "planner", f"RMSEE m=1 ({unit})", "log det mean", "log det std"]
    cols = [*ours[:3], "paper", ours[3], "paper", ours[4], "paper", "z", "source"] if paper else ours
    for col in cols:
        table.add_column(col, justify="left" if col in ("planner", "source") else "right")
    rows = exp.rows
    for i, r in enumerate(rows):
        cells = [f"n = {r.epoch}" if i == 0 or rows[i - 1].epoch != r.epoch else "", planner_label(r.planner)]
        cells.append(f"{r.rmse_m / unit_m:.2f}")
        if paper:
            cells.append(_opt(r.paper_rmse_m))
        cells.append(f"{r.logdet_mean:.2f}")
        if paper:
            cells.append(_opt(r.paper_logdet_mean))
        cells.append(f"{r.logdet_std:.2f}")
        if paper:
            cells += [_opt(r.paper_logdet_std), _opt(r.logdet_z, "+.1f"), r.paper_source]
        last = i == len(rows) - 1 or rows[i + 1].epoch != r.epoch
        table.add_row(*cells, end_section=last and i != len(rows) - 1)
    return table


def _convergence_table(exp: rep.ReplayExperiment, *, unit_m: float = 1.0) -> Table:
    unit = "cm" if unit_m == 0.01 else "m"
    n = exp.settings.epochs
    table = Table(
        title=f"Convergence against the recorded order, n = {n}",
        caption="n RMSEE / n log det: the epoch from which a planner stays at least as good as the recorded "
        f"order at n = {n}; NEES: mean at n = {n} ({3 * exp.records.n_transponders} if consistent); snap: "
        "mean distance from the planned point to the record used (eq. 31); conv: MAP solves that met the "
        "step test within J_max",
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


def _figures(exp: rep.ReplayExperiment, out: Path, stem: str, *, unit_m: float) -> None:
    from oceanloc.report.figures.replay import replay_curves_figure, replay_tracks_figure

    replay_curves_figure(
        exp.studies, 0, out / f"{stem}_replay_curves.png", f"{exp.records.name}: replay on recorded data",
        unit_m=unit_m,
    )  # fmt: skip
    title = f"{exp.records.name}: chosen records, run 0"
    replay_tracks_figure(exp.records, exp.studies, out / f"{stem}_replay_tracks.png", title)


def _opt(value: float | None, fmt: str = ".2f") -> str:
    return "-" if value is None else format(value, fmt)


def _epoch(value: int | None, n: int) -> str:
    return f"> {n}" if value is None else str(value)


def _triple(v: np.ndarray) -> str:
    return "(" + ", ".join(f"{x:+.2f}" for x in v) + ")"
