"""``oceanloc localize``: locate transponders from recorded data (GNSS-A ping files, GPS + range logs)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from oceanloc.cli import root
from oceanloc.cli._common import (
    JsonOut,
    cli_provenance,
    console,
    ensure_dir,
    err_console,
    escape,
    write_json,
    write_netcdf,
)
from oceanloc.cli._options import parse_origin
from oceanloc.errors import ConfigError
from oceanloc.estimation.gnssa import GnssaOptions
from oceanloc.field.gnatss_input import GnatssLocalization, process_gnatss_survey
from oceanloc.field.gnssa_surveys import process_gnssa_surveys
from oceanloc.field.range_logs import LogPair, localize_log_files, range_noise_files
from oceanloc.io.gnssa import lajolla_paths
from oceanloc.report.tables import field as tables
from oceanloc.reproduce.lajolla_gnssa import TARGET_STD_ENU_M

app = typer.Typer(help="Locate transponders from recorded field data.", no_args_is_help=True)
root.app.add_typer(app, name="localize")


@app.command("gnssa")
def gnssa(
    files: Annotated[
        list[Path] | None,
        typer.Argument(
            help="GNSS-A ping files; none: the five packaged La Jolla surveys. With --format gnatss: one "
            "GNATSS configuration YAML (none: the packaged synthetic array survey).",
            show_default=False,
        ),
    ] = None,
    fmt: Annotated[
        str,
        typer.Option(
            "--format",
            help="Input format: 'lajolla' (one transponder, the Wave Glider column files) or 'gnatss' (a "
            "GNATSS configuration with pxp_tt + POS_FREED_TRANS_TWTT, pxp_tt + --antenna, or a Level-2 CSV).",
        ),
    ] = "lajolla",
    pxp_tt: Annotated[Path | None, typer.Option("--pxp-tt", help="gnatss: pxp_tt travel times (us).")] = None,
    positions: Annotated[
        Path | None, typer.Option("--positions", help="gnatss: POS_FREED_TRANS_TWTT transducer positions.")
    ] = None,
    level2: Annotated[
        Path | None, typer.Option("--level2", help="gnatss: Level-2 per-reply CSV (gps_solution.csv).")
    ] = None,
    ssp: Annotated[
        Path | None, typer.Option("--ssp", help="gnatss: sound-speed profile (depth, speed).")
    ] = None,
    antenna: Annotated[
        Path | None,
        typer.Option(
            "--antenna",
            help="gnatss: GNSS antenna positions with --pxp-tt: a GPS_POS_FREED file (with --attitude) or "
            "an antenna CSV (recognised by its header; roll, pitch, heading columns make --attitude "
            "unneeded). The lever arm is the configuration's posfilter.atd_offsets.",
        ),
    ] = None,
    attitude: Annotated[
        Path | None, typer.Option("--attitude", help="gnatss: roll, pitch, heading file (deg) for --antenna.")
    ] = None,
    deletions: Annotated[
        Path | None, typer.Option("--deletions", help="gnatss: deletion file (deletns.dat or deletions.csv).")
    ] = None,
    lever_arm_sigma: Annotated[
        str | None,
        typer.Option(
            "--lever-arm-sigma",
            help="gnatss with --antenna: 1-sigma of the lever arm, m: one value or 'F,R,D' (forward, "
            "rightward, downward); the estimator's prior on the lever arm, propagated to the solution.",
        ),
    ] = None,
    estimate_lever_arm: Annotated[
        bool,
        typer.Option(
            "--estimate-lever-arm",
            help="gnatss with --antenna: calibrate the lever arm (needs heading variation; prior: "
            "--lever-arm-sigma, else 1 m).",
        ),
    ] = False,
    method: Annotated[
        str, typer.Option(help="gnatss: 'oceanloc' (its estimator) or 'gnatss' (GNATSS's own settings).")
    ] = "oceanloc",
    solution: Annotated[
        str, typer.Option(help="gnatss: 'independent' positions or the array's 'common_shift'.")
    ] = "independent",
    csv_dir: Annotated[
        Path | None,
        typer.Option("--csv", help="gnatss: write residuals/outliers/deletions CSVs (GNATSS columns) here."),
    ] = None,
    netcdf: Annotated[
        Path | None,
        typer.Option("--netcdf", help="gnatss: write the solution, covariance, iterations (NetCDF)."),
    ] = None,
    sound_speed: Annotated[
        list[float] | None,
        typer.Option(
            "--sound-speed",
            help="Sound speed in m/s: one value for all files or one per file (default: the published "
            "value for known files).",
        ),
    ] = None,
    fixed_sound_speed: Annotated[
        bool, typer.Option("--fixed-sound-speed", help="Do not estimate the sound speed (use it as given).")
    ] = False,
    sigma_sound_speed: Annotated[float, typer.Option(help="Prior 1-sigma of the sound speed, m/s.")] = 3.0,
    knot_spacing: Annotated[
        float,
        typer.Option(help="Sound-speed knot spacing in s (piecewise linear in time); 0: one constant speed."),
    ] = 900.0,
    max_tan_incidence: Annotated[
        float,
        typer.Option(help="Elevation cut: drop pings farther than this many depths horizontally (0: off)."),
    ] = 0.0,
    outlier_threshold: Annotated[float, typer.Option(help="Normalized-residual outlier threshold.")] = 3.0,
    gradient: Annotated[
        bool, typer.Option(help="Estimate a horizontal sound-speed (slowness) gradient, east and north.")
    ] = True,
    sigma_gradient: Annotated[
        float, typer.Option(help="Prior 1-sigma of each gradient component, relative change per km.")
    ] = 1e-3,
    refraction: Annotated[
        bool, typer.Option(help="Estimate the ray-bending coefficient kappa of L (1 - kappa tan^2).")
    ] = False,
    gnss_common_mode: Annotated[
        bool,
        typer.Option(help="Add the survey-wide (time-correlated) GNSS error to the reported sigmas."),
    ] = True,
    site_velocity: Annotated[
        str,
        typer.Option(
            help="Secular velocity of the transponder, to compare surveys at one epoch: 'auto' (the plate "
            "the files' header Lat0/Lon0 lies on, ITRF2014 plate-motion model), a plate (PCFC, NOAM), "
            "'VE,VN[,VU]' in mm/yr, or 'none'.",
        ),
    ] = "auto",
    json_path: JsonOut = None,
    figures: Annotated[
        Path | None, typer.Option("--figures", help="Write residual figures (PNG) in this folder.")
    ] = None,
    show_exclusions: Annotated[bool, typer.Option(help="List every excluded ping with its reason.")] = False,
) -> None:
    """Robust MAP position of a seafloor transponder from GNSS-Acoustic surveys, and their spread; or of a
    transponder array from a GNATSS-format survey (--format gnatss)."""
    if fmt not in ("lajolla", "gnatss"):
        raise ConfigError(f"--format must be 'lajolla' or 'gnatss', got {fmt!r}")
    if fmt == "gnatss":
        if files and len(files) > 1:
            raise ConfigError("--format gnatss takes one configuration YAML")
        loc = process_gnatss_survey(
            files[0] if files else None, pxp_tt=pxp_tt, positions=positions, level2=level2, ssp=ssp,
            deletions=deletions, antenna=antenna, attitude=attitude, method=method, solution=solution,
            lever_arm_sigma_m=_lever_arm_sigma(lever_arm_sigma), estimate_lever_arm=estimate_lever_arm,
        )  # fmt: skip
        _report_gnatss(loc, json_path, csv_dir, netcdf, show_exclusions)
        return
    paths = list(files) if files else lajolla_paths()
    if not files:
        err_console.print(f"no file given: using the {len(paths)} packaged La Jolla surveys")
    opts = GnssaOptions(
        estimate_sound_speed=not fixed_sound_speed, sigma_sound_speed_mps=sigma_sound_speed,
        knot_spacing_s=knot_spacing if knot_spacing > 0 else None,
        max_tan_incidence=max_tan_incidence if max_tan_incidence > 0 else None,
        outlier_threshold=outlier_threshold, estimate_gradient=gradient,
        sigma_gradient_per_km=sigma_gradient, estimate_refraction=refraction,
        gnss_common_mode=gnss_common_mode,
    )  # fmt: skip
    res = process_gnssa_surveys(paths, opts, sound_speeds_mps=sound_speed or [], site_velocity=site_velocity)
    for survey in res.surveys:
        if survey.qc.issues:
            err_console.print(escape(survey.qc.summary(max_lines=10)), highlight=False)
    for table in tables.gnssa_tables(res.results):
        console.print(table)
    if show_exclusions:
        for r in res.results:
            for e in r.exclusions:
                console.print(escape(f"{r.name}: {e}"), highlight=False)
    if res.spread is not None:
        console.print(tables.gnssa_spread_table(res.spread, None if files else TARGET_STD_ENU_M))
    for line in tables.gnssa_spread_lines(res):
        console.print(line, highlight=False)
    if figures is not None:
        from oceanloc.report.figures.field import write_gnssa_figures

        written = write_gnssa_figures(res, ensure_dir(figures))
        err_console.print(f"wrote {len(written)} figures to {escape(str(figures))}")
    if json_path is not None:
        write_json(json_path, res, cli_provenance(inputs=res.paths))


def _lever_arm_sigma(text: str | None) -> list[float] | None:
    """``--lever-arm-sigma``: one value or three comma-separated, metres."""
    if text is None:
        return None
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise ConfigError(
            f"--lever-arm-sigma must be one number or three 'F,R,D' in metres, got {text!r}"
        ) from None
    return values


def _report_gnatss(
    loc: GnatssLocalization, json_path: Path | None, csv_dir: Path | None, netcdf: Path | None, show: bool
) -> None:
    """Tables, then the files asked for (JSON record with pings, GNATSS-column CSVs, NetCDF)."""
    if loc.extra.get("qc"):
        err_console.print(escape(str(loc.extra["qc"])), highlight=False)
    console.print(tables.gnatss_positions_table(loc))
    console.print(tables.gnatss_geodetic_table(loc))
    for line in tables.gnatss_summary_lines(loc):  # each a line, never wrapped (grep-able)
        console.print(escape(line), highlight=False, soft_wrap=True)
    if show:
        for t, k, r, x in zip(loc.t_s, loc.transponder, loc.reason, loc.excluded, strict=True):
            if x:
                console.print(escape(f"{t:.3f} s {loc.ids[int(k)]}: {r}"), highlight=False)
    prov = cli_provenance(inputs=list(loc.inputs))
    if csv_dir is not None:
        written = loc.write_csvs(ensure_dir(csv_dir))
        err_console.print(f"wrote {len(written)} CSV files to {escape(str(csv_dir))}")
    if netcdf is not None:
        write_netcdf(netcdf, loc.to_dataset(), prov)
    if json_path is not None:
        write_json(json_path, loc, prov)


GpsLogArg = Annotated[Path, typer.Argument(help="NMEA 0183 GPS log (GGA with RMC or ZDA dates).")]
RangeLogArg = Annotated[Path, typer.Argument(help="USBL range CSV (utc,beacon,range_m|owtt_s|twtt_s).")]
SoundSpeed = Annotated[float, typer.Option(help="Sound speed for travel-time columns, m/s.")]
MaxGap = Annotated[float, typer.Option(help="Largest GPS gap to interpolate across, s.")]


@app.command("logs")
def logs(
    gps: GpsLogArg,
    ranges: RangeLogArg,
    origin: Annotated[
        str | None, typer.Option(help="ENU origin LAT,LON[,H] (deg, deg, m); default: the earliest fix.")
    ] = None,
    truth: Annotated[
        Path | None, typer.Option(help="truth.json of 'oceanloc simulate logs': add each beacon's error.")
    ] = None,
    sound_speed: SoundSpeed = 1500.0,
    sigma_range: Annotated[float, typer.Option(help="Total range sigma (USBL and GPS), m.")] = 1.006,
    sigma_gps: Annotated[float, typer.Option(help="GPS part of it (per horizontal axis), m.")] = 1.0,
    gps_correlation: Annotated[
        float, typer.Option(help="GPS error time constant, s (Gauss-Markov); 0: white, as in the journal.")
    ] = 60.0,
    max_gap: MaxGap = 2.0,
    beacon: Annotated[
        list[int] | None,
        typer.Option(
            "--beacon", help="An expected beacon id (repeat); ranges to others are QC'd. Default: any."
        ),
    ] = None,
    json_path: JsonOut = None,
) -> None:
    """Locate the beacons of a GPS + USBL range log pair (ENU origin: --origin, else the earliest fix).

    A beacon with fewer than 4 ranges is listed as not localized; the others are solved."""
    loc = localize_log_files(
        gps, ranges, origin=None if origin is None else parse_origin(origin), truth=truth,
        sound_speed_mps=sound_speed, max_gap_s=max_gap, sigma_range_m=sigma_range, sigma_gps_m=sigma_gps,
        gps_correlation_s=gps_correlation if gps_correlation > 0 else None, beacons=beacon or None,
    )  # fmt: skip
    _print_qc(loc.logs)
    console.print(tables.beacons_table(loc))
    for line in loc.not_localized_lines():
        err_console.print(escape(line), highlight=False)
    if json_path is not None:
        write_json(json_path, loc, cli_provenance(inputs=loc.inputs))


@app.command("noise")
def noise(
    gps: GpsLogArg,
    ranges: RangeLogArg,
    sound_speed: SoundSpeed = 1500.0,
    sigma_gps: Annotated[
        float, typer.Option(help="GPS error projected on the line of sight, m (journal VI-B: 1 m DGPS).")
    ] = 1.0,
    max_speed: Annotated[
        float, typer.Option(help="Stationary: slower than this over the window, m/s.")
    ] = 0.3,
    window: Annotated[float, typer.Option(help="Stationary-test window, s.")] = 30.0,
    min_duration: Annotated[float, typer.Option(help="Shortest stationary segment analysed, s.")] = 120.0,
    max_gap: MaxGap = 2.0,
    json_path: JsonOut = None,
    figures: Annotated[
        Path | None, typer.Option("--figures", help="Write the running-estimate figure (PNG) here.")
    ] = None,
) -> None:
    """Range noise per beacon on the stationary segments (PLANS eq. 30) and the total sigma with GPS error."""
    res = range_noise_files(
        gps, ranges, sound_speed_mps=sound_speed, sigma_gps_m=sigma_gps, max_speed_mps=max_speed,
        window_s=window, min_duration_s=min_duration, max_gap_s=max_gap,
    )  # fmt: skip
    _print_qc(res.logs)
    console.print(tables.range_noise_table(res))
    console.print(tables.range_noise_line(res), highlight=False)
    if figures is not None:
        from oceanloc.report.figures.field import write_range_noise_figure

        path = write_range_noise_figure(list(res.estimates), ensure_dir(figures) / "range_noise.png")
        err_console.print(f"wrote {escape(str(path))}")
    if json_path is not None:
        write_json(json_path, res, cli_provenance(inputs=res.logs.inputs))


def _print_qc(logs: LogPair) -> None:
    """The QC summary of a log pair and the ranges dropped for want of GPS, on stderr (escaped)."""
    err_console.print(escape("QC: " + logs.qc.summary(max_lines=10)), highlight=False)
    if logs.aligned.dropped_no_gps:
        err_console.print(
            f"{logs.aligned.dropped_no_gps} ranges dropped: no GPS fix within {logs.max_gap_s:g} s"
        )
