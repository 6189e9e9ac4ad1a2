"""``oceanloc replay``: planners choosing among recorded measurements (journal Section VI, PLANS eq. 31)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from oceanloc.cli import root
from oceanloc.cli._common import (
    FiguresOut,
    JsonOut,
    Scheduler,
    Seed,
    Workers,
    cli_provenance,
    console,
    ensure_dir,
    err_console,
    escape,
    progress_bar,
    write_json,
)
from oceanloc.cli._options import parse_floats, parse_origin
from oceanloc.errors import ConfigError
from oceanloc.evaluation.montecarlo import open_executor
from oceanloc.field.replay import DEFAULT_PLANNERS, planner_name
from oceanloc.io.gnssa import lajolla_paths
from oceanloc.io.records import write_netcdf
from oceanloc.report.tables import replay as tables
from oceanloc.reproduce import garcia2019_replay as rep

app = typer.Typer(
    help="Replay planning on recorded data: each planner chooses which recorded ping to use next "
    "(nearest recorded location to its planned point, PLANS eq. 31), over a Monte Carlo of prior draws.",
    no_args_is_help=True,
)
root.app.add_typer(app, name="replay")

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
        "(D-optimal point within d_max), random-disk (or random).",
    ),
]
PriorSigma = Annotated[
    str, typer.Option("--prior-sigma", help="Prior 1-sigma E,N,U of each draw, m (journal: 100,100,2).")
]
NetcdfOut = Annotated[
    Path | None,
    typer.Option("--netcdf", help="Write every run (dims experiment, planner, run, epoch, transponder)."),
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
    netcdf: NetcdfOut = None,
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
    total = len(paths) * len(names) * runs
    with open_executor(scheduler, workers) as executor, progress_bar(total, "replay runs") as advance:
        res = rep.replay_gnssa_files(
            paths, sound_speeds_mps=sound_speed or [], runs=runs, seed=seed, planners=names, epochs=epochs,
            step_m=step or None, reach_m=reach or None, max_yaw_rate_deg_s=yaw_rate,
            prior_sigma_enu_m=parse_floats(prior_sigma, "--prior-sigma", 3), executor=executor,
            progress=advance,
        )  # fmt: skip
    for r in res.replays:
        console.print(tables.gnssa_reference_line(r), highlight=False)
        console.print(tables.settings_line(r.experiment), highlight=False)
        console.print(tables.rows_table(r.experiment, f"{r.survey}: {runs} runs, seed {seed}", unit_m=0.01))
        if r.experiment.convergence:
            console.print(tables.convergence_table(r.experiment, unit_m=0.01))
    experiments = {r.survey: r.experiment for r in res.replays}
    _write(res, experiments, json_path, netcdf, figures, seed, unit_m=0.01, stems={k: k for k in experiments})


@app.command(
    "logs",
    help="Reproduce journal Tables VII (M = 1, beacon 1) and IX (M = 2) on a GPS + USBL log pair, with the "
    "paper's values (and the thesis' Tables 6.2 and 6.6 for greedy and random disk) beside ours.\n\n"
    + _READINGS
    + "\n\nLogs: p_V(1) = [8.62, -6.77, 0] m in the journal's frame (moved to the frame of --origin), "
    "phi(1) = 13 deg counter-clockwise from east (a heading of 77 deg clockwise from north), 3 m/s, "
    "T = 1 s, w_max = 30 deg/s, "
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
            help="What errors are measured against: a truth.json of 'oceanloc simulate logs'; E,N,U in m "
            "(frame of --origin), once per beacon in id order; 'estimate' (the robust estimate over every "
            "range); default 'journal': the journal's 9.21,1.68,-1.15 and 2.79,0.44,-1.15, moved from its "
            "frame (origin 32.705,-117.236,-1.478) to this one.",
        ),
    ] = None,
    origin: Annotated[
        str | None, typer.Option(help="ENU origin LAT,LON[,H] (deg, deg, m); default: the earliest fix.")
    ] = None,
    tables_: Annotated[str, typer.Option("--tables", help="Which tables: VII, IX or VII,IX.")] = "VII,IX",
    runs: Runs = 100,
    epochs: Epochs = 50,
    planners: Planners = _ALL_PLANNERS,
    seed: Seed = None,
    json_path: JsonOut = None,
    netcdf: NetcdfOut = None,
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
    seed = 2019 if seed is None else seed
    names = _parse_planners(planners)
    table_names = [t.strip().upper() for t in tables_.split(",") if t.strip()]
    total = len(table_names) * len(names) * runs
    with open_executor(scheduler, workers) as executor, progress_bar(total, "replay runs") as advance:
        res = rep.replay_log_files(
            gps, ranges, truth=_parse_truth(truth), origin=None if origin is None else parse_origin(origin),
            tables=table_names, runs=runs, seed=seed, planners=names, epochs=epochs, speed_mps=speed,
            reach_m=reach, max_yaw_rate_deg_s=yaw_rate, sigma_range_m=sigma_range,
            prior_sigma_enu_m=parse_floats(prior_sigma, "--prior-sigma", 3), sound_speed_mps=sound_speed,
            max_gap_s=max_gap, executor=executor, progress=advance,
        )  # fmt: skip
    if res.logs is not None:
        err_console.print(escape("QC: " + res.logs.qc.summary(max_lines=5)), highlight=False)
    console.print(tables.logs_reference_line(res), highlight=False)
    titles = {"VII": "Table VII: one beacon (M = 1)", "IX": "Table IX: two beacons (M = 2), RMSEE of m = 1"}
    for name, exp in res.experiments.items():
        console.print(tables.settings_line(exp), highlight=False)
        title = f"{titles[name]}, {runs} runs (paper 100), seed {seed}; z = (ours - paper) / SE"
        console.print(tables.rows_table(exp, title, paper=True))
        if exp.convergence:
            console.print(tables.convergence_table(exp))
    stems = {name: f"table_{name.lower()}" for name in res.experiments}
    _write(res, res.experiments, json_path, netcdf, figures, seed, unit_m=1.0, stems=stems)


def _write(
    res: rep.GnssaReplays | rep.LogsReplay,
    experiments: dict[str, rep.ReplayExperiment],
    json_path: Path | None,
    netcdf: Path | None,
    figures: Path | None,
    seed: int,
    *,
    unit_m: float,
    stems: dict[str, str],
) -> None:
    """Figures, JSON and NetCDF of a replay command, each with the command's provenance."""
    prov = cli_provenance(seed=seed, inputs=res.inputs)
    if figures:
        from oceanloc.report.figures.replay import write_replay_figures

        out = ensure_dir(figures)
        for name, exp in experiments.items():
            write_replay_figures(exp, out, stems[name], unit_m=unit_m)
        console.print(f"wrote figures to {escape(str(out))}", highlight=False)
    if json_path:
        write_json(json_path, res, prov)
    if netcdf:
        write_netcdf(netcdf, res.to_dataset(), prov)
        err_console.print(f"wrote {escape(str(netcdf))}", highlight=False)


def _parse_planners(text: str) -> list[str]:
    """Canonical planner names (``recorded``, ``k0``, ``k2``, ``greedy``, ``random-disk``), in order."""
    names = [planner_name(p) for p in text.split(",") if p.strip()]
    if not names:
        raise ConfigError("--planners lists no planner")
    return list(dict.fromkeys(names))


def _parse_truth(values: list[str] | None) -> rep.LogTruth:
    """``--truth``: none (the journal's beacons), ``estimate``, a truth.json path or E,N,U per beacon."""
    if not values:
        return "journal"
    if len(values) == 1 and values[0].strip().lower() in ("estimate", "journal"):
        return values[0].strip().lower()
    if len(values) == 1 and (values[0].endswith(".json") or Path(values[0]).is_file()):
        return Path(values[0])
    return {b + 1: parse_floats(v, "--truth", 3) for b, v in enumerate(values)}
