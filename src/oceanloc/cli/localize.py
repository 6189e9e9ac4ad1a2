"""``oceanloc localize``: locate transponders from recorded data (GNSS-A ping files, GPS + range logs)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.table import Table

from oceanloc.cli import root
from oceanloc.cli._common import console, ensure_dir, err_console, write_json
from oceanloc.errors import ConfigError
from oceanloc.estimation.gnssa import GnssaOptions, GnssaResult, localize_gnssa
from oceanloc.field.repeatability import SurveySpread, survey_spread
from oceanloc.geo.plate_motion import SECONDS_PER_YEAR, SiteVelocity, given_site_velocity, plate_site_velocity
from oceanloc.io.gnssa import (
    GPS_EPOCH_2020_UNIX_S,
    PUBLISHED_SOUND_SPEED_MPS,
    GnssaSurvey,
    lajolla_paths,
    read_gnssa,
    survey_sound_speeds_mps,
)
from oceanloc.io.qc import QcReport
from oceanloc.io.usbl import AlignedRanges

app = typer.Typer(help="Locate transponders from recorded field data.", no_args_is_help=True)
root.app.add_typer(app, name="localize")

ACCEPTANCE_STD_ENU_M = np.array([0.025, 0.035, 0.06])
"""Target standard deviation across the La Jolla surveys (E, N, U), from the issue's acceptance."""


@app.command("gnssa")
def gnssa(
    files: Annotated[
        list[Path] | None,
        typer.Argument(
            help="GNSS-A ping files; none: the five packaged La Jolla surveys.", show_default=False
        ),
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
            help="Secular velocity of the transponder, to compare surveys at one epoch: a plate of the "
            "ITRF2014 plate-motion model (PCFC, NOAM), 'VE,VN[,VU]' in mm/yr, 'none', or 'auto' (PCFC for "
            "the La Jolla surveys, known by file name; none otherwise).",
        ),
    ] = "auto",
    json_path: Annotated[Path | None, typer.Option("--json", help="Write the results as JSON here.")] = None,
    figures: Annotated[
        Path | None, typer.Option("--figures", help="Write residual figures (PNG) in this folder.")
    ] = None,
    show_exclusions: Annotated[bool, typer.Option(help="List every excluded ping with its reason.")] = False,
) -> None:
    """Robust MAP position of a seafloor transponder from GNSS-Acoustic surveys, and their spread."""
    paths = list(files) if files else lajolla_paths()
    if not files:
        err_console.print(f"no file given: using the {len(paths)} packaged La Jolla surveys")
    speeds = survey_sound_speeds_mps(paths, sound_speed or [])
    surveys, results = [], []
    for path, speed in zip(paths, speeds, strict=True):
        survey = read_gnssa(path)
        if survey.qc.issues:
            err_console.print(survey.qc.summary(max_lines=10), highlight=False)
        opts = GnssaOptions(
            sound_speed_mps=speed,
            estimate_sound_speed=not fixed_sound_speed,
            sigma_sound_speed_mps=sigma_sound_speed,
            knot_spacing_s=knot_spacing if knot_spacing > 0 else None,
            max_tan_incidence=max_tan_incidence if max_tan_incidence > 0 else None,
            outlier_threshold=outlier_threshold,
            estimate_gradient=gradient,
            sigma_gradient_per_km=sigma_gradient,
            estimate_refraction=refraction,
            gnss_common_mode=gnss_common_mode,
        )
        surveys.append(survey)
        results.append(localize_gnssa(survey, opts))
    _print_results(results)
    if show_exclusions:
        for r in results:
            for e in r.exclusions:
                console.print(f"{r.name}: {e}", highlight=False)
    velocity = parse_site_velocity(site_velocity, surveys)
    spread = as_surveyed = None
    if len(results) >= 2:
        spread, as_surveyed = survey_spread(results, velocity), survey_spread(results)
        _print_spread(spread, as_surveyed if velocity is not None else None)
    if figures is not None:
        from oceanloc.report.figures.field import gnssa_residual_figure, gnssa_spread_figure

        ensure_dir(figures)
        for s, r in zip(surveys, results, strict=True):
            gnssa_residual_figure(s, r, figures / f"{s.name}_residuals.png")
        if spread is not None:
            gnssa_spread_figure(results, spread, figures / "gnssa_spread.png")
        err_console.print(f"wrote figures to {figures}")
    if json_path is not None:
        write_json(json_path, gnssa_json(results, spread, as_surveyed))


def parse_site_velocity(spec: str, surveys: list[GnssaSurvey]) -> SiteVelocity | None:
    """The ``--site-velocity`` value as a :class:`SiteVelocity` (None: compare positions as surveyed)."""
    text = spec.strip()
    if text.lower() == "none":
        return None
    if text.lower() == "auto":
        if not surveys or any(s.name not in PUBLISHED_SOUND_SPEED_MPS for s in surveys):
            return None
        text = "PCFC"
    if "," in text:
        try:
            values = tuple(float(v) for v in text.split(","))
        except ValueError:
            raise ConfigError(f"--site-velocity: {spec!r} is not 'VE,VN[,VU]' in mm/yr") from None
        return given_site_velocity(values)
    origin = next((s.origin for s in surveys if s.origin is not None), None)
    if origin is None:
        raise ConfigError(f"--site-velocity {spec}: a plate velocity needs a file header with Lat0 and Lon0")
    return plate_site_velocity(origin.lat_deg, origin.lon_deg, text.upper())


def gnssa_json(
    results: list[GnssaResult], spread: SurveySpread | None, as_surveyed: SurveySpread | None
) -> dict:
    """The ``--json`` payload: one entry per survey and the spread across them (``spread``: at one
    epoch, moved by its site velocity; ``as_surveyed`` under ``at_survey_epochs``; None for one survey)."""
    surveys = []
    for r in results:
        e, n, u = r.position_enu_m
        se, sn, su = r.sigma_enu_m
        surveys.append(
            {
                "file": r.name,
                "epoch_utc": _utc(r.epoch_s),
                "n_m": n,
                "e_m": e,
                "u_m": u,
                "sigma_n_m": sn,
                "sigma_e_m": se,
                "sigma_u_m": su,
                "sound_speed_mps": r.sound_speed_mps,
                "pings_used": r.pings_used,
                "pings_excluded": len(r.exclusions),
                "residual_rms_m": r.residual_rms_m,
                "gradient_e_per_km": r.gradient_per_km[0],
                "gradient_n_per_km": r.gradient_per_km[1],
                "refraction_ppm": r.refraction_ppm,
                "sigma_path_m": r.sigma_path_m,
                "beta_m": r.beta_m,
            }
        )
    payload: dict = {"surveys": surveys}
    if spread is not None and as_surveyed is not None:
        velocity = spread.velocity
        payload["spread"] = _spread_json(spread)
        payload["spread"]["reference_epoch_utc"] = _utc(spread.reference_epoch_s)
        payload["spread"]["site_velocity"] = (
            None
            if velocity is None
            else {"source": velocity.source, **_enu_mm_yr(velocity.velocity_enu_mm_yr)}
        )
        if spread.fitted_velocity_enu_mps is not None and spread.fitted_velocity_sigma_enu_mps is not None:
            fit = spread.fitted_velocity_enu_mps * _MM_YR
            fit_sigma = spread.fitted_velocity_sigma_enu_mps * _MM_YR
            payload["spread"]["fitted_velocity"] = {
                f"{axis}_mm_yr": [fit[j], fit_sigma[j]] for axis, j in (("e", 0), ("n", 1), ("u", 2))
            }
        payload["spread"]["at_survey_epochs"] = _spread_json(as_surveyed)
    else:
        payload["spread"] = {"std_n_m": None, "std_e_m": None, "std_u_m": None}
    return payload


_MM_YR = 1e3 * SECONDS_PER_YEAR


def _enu_mm_yr(v: np.ndarray) -> dict:
    return {"e_mm_yr": float(v[0]), "n_mm_yr": float(v[1]), "u_mm_yr": float(v[2])}


def _spread_json(s: SurveySpread) -> dict:
    out: dict = {"std_n_m": s.std_enu_m[1], "std_e_m": s.std_enu_m[0], "std_u_m": s.std_enu_m[2]}
    for axis, j in (("n", 1), ("e", 0), ("u", 2)):
        out[f"chi2_{axis}"] = s.chi2_enu[j]
        out[f"sigmas_explain_{axis}"] = bool(s.sigmas_explain_spread[j])
    out["chi2_95_range"] = s.chi2_bounds.tolist()
    return out


def _utc(epoch_s: float) -> str:
    """A GNSS-A epoch (seconds after 2020-01-01 UTC) as an ISO 8601 UTC time."""
    from datetime import UTC, datetime

    return datetime.fromtimestamp(GPS_EPOCH_2020_UNIX_S + epoch_s, tz=UTC).isoformat(timespec="seconds")


def _print_results(results: list[GnssaResult]) -> None:
    table = Table(title="GNSS-A transponder positions (file frame)")
    for col in ("survey", "N m", "E m", "U m", "1σ N/E/U cm", "used/excl", "RMS cm"):
        table.add_column(col, justify="right")
    acoustic = Table(title="Acoustic model (estimated)")
    for col in ("survey", "c m/s", "dc/dE, dc/dN m/s/km", "κ ppm", "σ path cm", "β cm/tan"):
        acoustic.add_column(col, justify="right")
    geo_table = Table(title="As latitude, longitude, ellipsoidal height (WGS84)")
    for col in ("survey", "latitude deg", "longitude deg", "height m"):
        geo_table.add_column(col, justify="right")
    for r in results:
        e, n, u = r.position_enu_m
        se, sn, su = 100.0 * r.sigma_enu_m
        name = r.name.removeprefix("gnssa_data_")
        table.add_row(
            name,
            f"{n:+.3f}",
            f"{e:+.3f}",
            f"{u:+.3f}",
            f"{sn:.1f}/{se:.1f}/{su:.1f}",
            f"{r.pings_used}/{len(r.exclusions)}",
            f"{100 * r.residual_rms_m:.1f}",
        )
        # a relative slowness gradient g per km is a speed gradient of -g c per km
        dc = -r.gradient_per_km * r.sound_speed_mps
        acoustic.add_row(
            name,
            f"{r.sound_speed_mps:.1f}",
            f"{dc[0]:+.2f}, {dc[1]:+.2f}",
            f"{r.refraction_ppm:.1f}",
            f"{100 * r.sigma_path_m:.1f}",
            f"{100 * r.beta_m:.2f}",
        )
        if r.position_geodetic is not None:
            lat, lon, h = r.position_geodetic
            geo_table.add_row(name, f"{lat:.8f}", f"{lon:.8f}", f"{h:.3f}")
    console.print(table)
    console.print(acoustic)
    if geo_table.row_count:
        console.print(geo_table)


def _print_spread(spread: SurveySpread, as_surveyed: SurveySpread | None) -> None:
    title = f"Spread across {spread.n_surveys} surveys"
    if spread.velocity is not None:
        v = spread.velocity.velocity_enu_mm_yr
        title += (
            f", moved to {_utc(spread.reference_epoch_s)[:10]} by the site velocity"
            f" ({spread.velocity.source}: E {v[0]:+.1f}, N {v[1]:+.1f} mm/yr)"
        )
    table = Table(title=title)
    for col in ("axis", "std cm", "RMS σ cm", "chi2", "95% range", "σ explain", "target", "met"):
        table.add_column(col, justify="right")
    lo, hi = spread.chi2_bounds
    ok = spread.sigmas_explain_spread
    for k, (axis, tgt) in enumerate(zip(("N", "E", "U"), ACCEPTANCE_STD_ENU_M[[1, 0, 2]], strict=True)):
        j = (1, 0, 2)[k]
        table.add_row(
            axis,
            f"{100 * spread.std_enu_m[j]:.1f}",
            f"{100 * spread.rms_sigma_enu_m[j]:.1f}",
            f"{spread.chi2_enu[j]:.1f}",
            f"{lo:.1f}-{hi:.1f}",
            "yes" if ok[j] else "no",
            f"{100 * tgt:.1f}",
            "yes" if spread.std_enu_m[j] <= tgt else "no",
        )
    console.print(table)
    if as_surveyed is not None:
        c = as_surveyed.chi2_enu
        console.print(
            f"as surveyed (no site velocity): std N/E/U {100 * as_surveyed.std_enu_m[1]:.1f}/"
            f"{100 * as_surveyed.std_enu_m[0]:.1f}/{100 * as_surveyed.std_enu_m[2]:.1f} cm, "
            f"chi2 {c[1]:.1f}/{c[0]:.1f}/{c[2]:.1f}",
            highlight=False,
        )
    if spread.fitted_velocity_enu_mps is not None and spread.fitted_velocity_sigma_enu_mps is not None:
        fit = spread.fitted_velocity_enu_mps * _MM_YR
        sig = spread.fitted_velocity_sigma_enu_mps * _MM_YR
        console.print(
            f"velocity the surveys imply (weighted fit): E {fit[0]:+.0f} ± {sig[0]:.0f}, "
            f"N {fit[1]:+.0f} ± {sig[1]:.0f}, U {fit[2]:+.0f} ± {sig[2]:.0f} mm/yr",
            highlight=False,
        )


@app.command("logs")
def logs(
    gps: Annotated[Path, typer.Argument(help="NMEA 0183 GPS log (GGA with RMC or ZDA dates).")],
    ranges: Annotated[Path, typer.Argument(help="USBL range CSV (utc,beacon,range_m|owtt_s|twtt_s).")],
    sound_speed: Annotated[float, typer.Option(help="Sound speed for travel-time columns, m/s.")] = 1500.0,
    sigma_range: Annotated[float, typer.Option(help="Total range sigma (USBL and GPS), m.")] = 1.006,
    sigma_gps: Annotated[float, typer.Option(help="GPS part of it (per horizontal axis), m.")] = 1.0,
    gps_correlation: Annotated[
        float, typer.Option(help="GPS error time constant, s (Gauss-Markov); 0: white, as in the journal.")
    ] = 60.0,
    max_gap: Annotated[float, typer.Option(help="Largest GPS gap to interpolate across, s.")] = 2.0,
    json_path: Annotated[
        Path | None, typer.Option("--json", help="Write the estimates as JSON here.")
    ] = None,
) -> None:
    """Locate the beacons of a GPS + USBL range log pair (origin: the first GPS fix)."""
    from oceanloc.estimation.range_logs import localize_beacons
    from oceanloc.geo.enu import enu_to_geodetic

    aligned, qc = _read_aligned(gps, ranges, sound_speed, max_gap)
    estimates = localize_beacons(
        aligned,
        sigma_range_m=sigma_range,
        sigma_gps_m=sigma_gps,
        gps_correlation_s=gps_correlation if gps_correlation > 0 else None,
    )
    table = Table(
        title=f"Beacons (ENU from the first fix {aligned.origin.lat_deg:.6f}, {aligned.origin.lon_deg:.6f})"
    )
    for col in ("beacon", "E m", "N m", "U m", "1σ E/N/U m", "lat deg", "lon deg", "used/excl", "RMS m"):
        table.add_column(col, justify="right")
    payload = []
    for e in estimates:
        geo = enu_to_geodetic(e.position_enu_m, aligned.origin)
        sig = np.sqrt(np.diag(e.covariance_m2))
        table.add_row(
            str(e.beacon),
            *(f"{v:+.2f}" for v in e.position_enu_m),
            "/".join(f"{v:.2f}" for v in sig),
            f"{geo[0]:.7f}",
            f"{geo[1]:.7f}",
            f"{int(e.used.sum())}/{e.n_excluded}",
            f"{e.residual_rms_m:.2f}",
        )
        payload.append(
            {
                "beacon": e.beacon,
                "enu_m": e.position_enu_m,
                "sigma_enu_m": sig,
                "lat_deg": geo[0],
                "lon_deg": geo[1],
                "h_m": geo[2],
                "ranges_used": int(e.used.sum()),
                "ranges_excluded": e.n_excluded,
            }
        )
    console.print(table)
    if json_path is not None:
        write_json(
            json_path, {"beacons": payload, "qc": qc.counts(), "dropped_no_gps": aligned.dropped_no_gps}
        )


@app.command("noise")
def noise(
    gps: Annotated[Path, typer.Argument(help="NMEA 0183 GPS log (GGA with RMC or ZDA dates).")],
    ranges: Annotated[Path, typer.Argument(help="USBL range CSV (utc,beacon,range_m|owtt_s|twtt_s).")],
    sound_speed: Annotated[float, typer.Option(help="Sound speed for travel-time columns, m/s.")] = 1500.0,
    sigma_gps: Annotated[
        float, typer.Option(help="GPS error projected on the line of sight, m (journal VI-B: 1 m DGPS).")
    ] = 1.0,
    max_speed: Annotated[
        float, typer.Option(help="Stationary: slower than this over the window, m/s.")
    ] = 0.3,
    window: Annotated[float, typer.Option(help="Stationary-test window, s.")] = 30.0,
    min_duration: Annotated[float, typer.Option(help="Shortest stationary segment analysed, s.")] = 120.0,
    max_gap: Annotated[float, typer.Option(help="Largest GPS gap to interpolate across, s.")] = 2.0,
    json_path: Annotated[
        Path | None, typer.Option("--json", help="Write the estimates as JSON here.")
    ] = None,
    figures: Annotated[
        Path | None, typer.Option("--figures", help="Write the running-estimate figure (PNG) here.")
    ] = None,
) -> None:
    """Range noise per beacon on the stationary segments (PLANS eq. 30) and the total sigma with GPS error."""
    from oceanloc.estimation.noise import (
        stationary_mask,
        stationary_range_noise,
        stationary_segments,
        total_range_sigma_m,
    )
    from oceanloc.io.usbl import format_utc

    if sigma_gps < 0.0 or max_speed <= 0.0 or window <= 0.0:
        raise ConfigError("--sigma-gps must be >= 0, --max-speed and --window positive")
    aligned, _ = _read_aligned(gps, ranges, sound_speed, max_gap)
    still = stationary_mask(aligned.t_unix_s, aligned.vehicle_enu_m, max_speed_mps=max_speed, window_s=window)
    segments = stationary_segments(aligned.t_unix_s, still, min_duration_s=min_duration)
    estimates = stationary_range_noise(aligned.t_unix_s, aligned.beacon, aligned.range_m, segments)
    if not estimates:
        raise ConfigError(
            f"{ranges}: no beacon has 10 or more ranges on a stationary segment of {min_duration:g} s or more"
        )
    t0 = aligned.t_unix_s[0]
    table = Table(title="Range noise on stationary segments (eq. 30)")
    for col in ("beacon", "segment s", "ranges", "outliers", "range m", "σ mm", "± mm"):
        table.add_column(col, justify="right")
    for e in estimates:
        table.add_row(
            str(e.beacon),
            f"{e.t_start_s - t0:.0f}-{e.t_end_s - t0:.0f}",
            str(e.n_ranges),
            str(e.n_outliers),
            f"{e.running.final_range_m:.3f}",
            f"{1e3 * e.sigma_m:.0f}",
            f"{1e3 * e.sigma_se_m:.0f}",
        )
    console.print(table)
    sigma_usbl = max(e.sigma_m for e in estimates)
    total = total_range_sigma_m(sigma_usbl, sigma_gps)
    console.print(
        f"sigma_USBL = max over beacons = {1e3 * sigma_usbl:.0f} mm; with sigma_GPS = {sigma_gps:g} m the"
        f" total range sigma is {total:.3f} m (journal VI-B); use it as --sigma-range"
    )
    if figures is not None:
        from oceanloc.report.figures.field import range_noise_figure

        err_console.print(f"wrote {range_noise_figure(estimates, ensure_dir(figures) / 'range_noise.png')}")
    if json_path is not None:
        write_json(
            json_path,
            {
                "beacons": [
                    {
                        "beacon": e.beacon,
                        "segment": e.segment,
                        "t_start_utc": format_utc(e.t_start_s),
                        "t_end_utc": format_utc(e.t_end_s),
                        "stationary_ranges": e.n_ranges,
                        "outliers": e.n_outliers,
                        "range_m": e.running.final_range_m,
                        "sigma_m": e.sigma_m,
                        "sigma_se_m": e.sigma_se_m,
                    }
                    for e in estimates
                ],
                "sigma_usbl_m": sigma_usbl,
                "sigma_gps_m": sigma_gps,
                "sigma_total_m": total,
            },
        )


def _read_aligned(
    gps: Path, ranges: Path, sound_speed_mps: float, max_gap_s: float
) -> tuple[AlignedRanges, QcReport]:
    """Read a GPS and a range log, print their QC summary, and align the ranges to the GPS track."""
    from oceanloc.io.nmea import read_nmea
    from oceanloc.io.usbl import align_ranges, read_usbl

    gps_log = read_nmea(gps)
    range_log = read_usbl(ranges, sound_speed_mps=sound_speed_mps)
    qc = gps_log.qc.merge(range_log.qc)
    err_console.print("QC: " + qc.summary(max_lines=10), highlight=False)
    aligned = align_ranges(gps_log, range_log, max_gap_s=max_gap_s)
    if aligned.dropped_no_gps:
        err_console.print(f"{aligned.dropped_no_gps} ranges dropped: no GPS fix within {max_gap_s} s")
    return aligned, qc
