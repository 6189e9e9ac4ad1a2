"""Terminal tables (rich) for field data: GNSS-A surveys, GNATSS-format array solutions, localized GPS +
range logs, range noise (the survey journal's are in :mod:`.survey_journal`).

Every numeric column header states its unit; text that comes from a user (file names, survey names) is
escaped; each table fits 100 columns. Bearings and headings are degrees clockwise from true north.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from rich.markup import escape
from rich.table import Table

from oceanloc.estimation.gnssa import GnssaResult, gnssa_epoch_utc
from oceanloc.field.gnatss_input import GnatssLocalization
from oceanloc.field.gnssa_surveys import GnssaSurveys
from oceanloc.field.range_logs import LogLocalization, NoiseAnalysis
from oceanloc.field.repeatability import SurveySpread
from oceanloc.geo.plate_motion import SECONDS_PER_YEAR
from oceanloc.report.tables.survey_journal import compact_table as _table
from oceanloc.report.tables.survey_journal import origin_text
from oceanloc.sim.logs import BeaconTruth

_MM_YR = 1e3 * SECONDS_PER_YEAR


def _survey_name(name: str) -> str:
    return escape(name.removeprefix("gnssa_data_"))


def gnssa_positions_table(results: Sequence[GnssaResult]) -> Table:
    """Transponder positions in each file's topocentric frame, their 1-sigma and ping counts."""
    table = _table("GNSS-A transponder positions (file frame)")
    for col in ("survey", "E m", "N m", "U m", "1σ E/N/U cm", "used/excl", "RMS cm"):
        table.add_column(col, justify="left" if col == "survey" else "right")
    for r in results:
        e, n, u = r.position_enu_m
        se, sn, su = 100.0 * r.sigma_enu_m
        table.add_row(
            _survey_name(r.name),
            f"{e:+.3f}",
            f"{n:+.3f}",
            f"{u:+.3f}",
            f"{se:.1f}/{sn:.1f}/{su:.1f}",
            f"{r.pings_used}/{len(r.exclusions)}",
            f"{100 * r.residual_rms_m:.1f}",
        )
    return table


def gnssa_acoustic_table(results: Sequence[GnssaResult]) -> Table:
    """The estimated acoustic model of each survey (sound speed, its gradient, refraction, noise)."""
    table = _table("Acoustic model (estimated)")
    for col in ("survey", "c m/s", "dc/dE, dc/dN m/s/km", "κ ppm", "σ path cm", "β cm/tan"):
        table.add_column(col, justify="left" if col == "survey" else "right")
    for r in results:
        # a relative slowness gradient g per km is a speed gradient of -g c per km
        dc = -r.gradient_per_km * r.sound_speed_mps
        table.add_row(
            _survey_name(r.name),
            f"{r.sound_speed_mps:.1f}",
            f"{dc[0]:+.2f}, {dc[1]:+.2f}",
            f"{r.refraction_ppm:.1f}",
            f"{100 * r.sigma_path_m:.1f}",
            f"{100 * r.beta_m:.2f}",
        )
    return table


def gnssa_geodetic_table(results: Sequence[GnssaResult]) -> Table | None:
    """Positions as latitude, longitude and ellipsoidal height (None when no file has a header origin)."""
    table = _table("As latitude, longitude, ellipsoidal height (WGS84)")
    for col in ("survey", "epoch UTC", "latitude deg", "longitude deg", "height m"):
        table.add_column(col, justify="left" if col == "survey" else "right")
    for r in results:
        if r.position_geodetic is not None:
            lat, lon, h = r.position_geodetic
            table.add_row(
                _survey_name(r.name), gnssa_epoch_utc(r.epoch_s)[:16], f"{lat:.8f}", f"{lon:.8f}", f"{h:.3f}"
            )
    return table if table.row_count else None


def gnssa_tables(results: Sequence[GnssaResult]) -> list[Table]:
    """The per-survey tables of ``localize gnssa``: positions, acoustic model, latitude/longitude."""
    geo = gnssa_geodetic_table(results)
    return [gnssa_positions_table(results), gnssa_acoustic_table(results), *([geo] if geo else [])]


def gnssa_spread_table(spread: SurveySpread, targets_enu_m: Sequence[float] | None = None) -> Table:
    """Spread across surveys per axis, what the sigmas predict and the chi-square test; with
    ``targets_enu_m`` (E, N, U in metres) a target column and whether it is met."""
    title = f"Spread across {spread.n_surveys} surveys"
    if spread.velocity is not None:
        v = spread.velocity.velocity_enu_mm_yr
        title += (
            f", moved to {gnssa_epoch_utc(spread.reference_epoch_s)[:10]} by the site velocity"
            f" ({escape(spread.velocity.source)}: E {v[0]:+.1f}, N {v[1]:+.1f} mm/yr)"
        )
    else:
        title += ", as surveyed"
    table = _table(title)
    cols = ["axis", "std cm", "RMS σ cm", "chi2", "chi2 95% range", "σ explain"]
    if targets_enu_m is not None:
        cols += ["target cm", "met"]
    for col in cols:
        table.add_column(col, justify="right")
    lo, hi = spread.chi2_bounds
    ok = spread.sigmas_explain_spread
    for j, axis in enumerate("ENU"):
        cells = [
            axis,
            f"{100 * spread.std_enu_m[j]:.1f}",
            f"{100 * spread.rms_sigma_enu_m[j]:.1f}",
            f"{spread.chi2_enu[j]:.1f}",
            f"{lo:.1f}-{hi:.1f}",
            "yes" if ok[j] else "no",
        ]
        if targets_enu_m is not None:
            target = float(targets_enu_m[j])
            cells += [f"{100 * target:.1f}", "yes" if spread.std_enu_m[j] <= target else "no"]
        table.add_row(*cells)
    return table


def gnssa_spread_lines(surveys: GnssaSurveys) -> list[str]:
    """Plain lines under the spread table: how the site velocity was chosen, the spread as surveyed and
    the velocity the surveys imply."""
    lines = [f"site velocity ({escape(surveys.site_velocity.spec)}): {escape(surveys.site_velocity.reason)}"]
    raw, spread = surveys.as_surveyed, surveys.spread
    if raw is not None and spread is not None and spread.velocity is not None:
        s, c = 100 * raw.std_enu_m, raw.chi2_enu
        lines.append(
            f"as surveyed (no site velocity): std E/N/U {s[0]:.1f}/{s[1]:.1f}/{s[2]:.1f} cm, "
            f"chi2 {c[0]:.1f}/{c[1]:.1f}/{c[2]:.1f}"
        )
    if spread is not None and spread.fitted_velocity_enu_mps is not None:
        fit = spread.fitted_velocity_enu_mps * _MM_YR
        sig = np.asarray(spread.fitted_velocity_sigma_enu_mps) * _MM_YR
        lines.append(
            f"velocity the surveys imply (weighted fit): E {fit[0]:+.0f} ± {sig[0]:.0f}, "
            f"N {fit[1]:+.0f} ± {sig[1]:.0f}, U {fit[2]:+.0f} ± {sig[2]:.0f} mm/yr"
        )
    return lines


def beacons_table(loc: LogLocalization) -> Table:
    """``localize logs``: each beacon's ENU position (from the origin in the title), 1-sigma, latitude and
    longitude, ranges used and excluded; with a truth file, the distance to the true position."""
    how = loc.logs.origin_source
    table = _table(f"Beacons, ENU from {origin_text(loc.logs.origin, how)}")
    cols = ["beacon", "E m", "N m", "U m", "1σ E/N/U m", "lat deg", "lon deg", "used/excl", "RMS m"]
    if loc.truth_enu_m is not None:
        cols.append("error m")
    for col in cols:
        table.add_column(col, justify="right")
    for i, e in enumerate(loc.estimates):
        sig = np.sqrt(np.diag(e.covariance_m2))
        cells = [
            str(e.beacon),
            *(f"{v:+.2f}" for v in e.position_enu_m),
            "/".join(f"{v:.2f}" for v in sig),
            f"{loc.geodetic[i, 0]:.6f}",
            f"{loc.geodetic[i, 1]:.6f}",
            f"{int(e.used.sum())}/{e.n_excluded}",
            f"{e.residual_rms_m:.2f}",
        ]
        if loc.truth_enu_m is not None:
            err = loc.error_m(i)
            cells.append("-" if err is None else f"{err:.2f}")
        table.add_row(*cells)
    return table


def range_noise_table(noise: NoiseAnalysis) -> Table:
    """``localize noise``: eq. (30) per beacon and stationary segment (times from the first range)."""
    table = _table("Range noise on stationary segments (eq. 30)")
    for col in ("beacon", "segment s", "ranges", "outliers", "range m", "σ mm", "± mm"):
        table.add_column(col, justify="right")
    t0 = noise.t0_unix_s
    for e in noise.estimates:
        table.add_row(
            str(e.beacon),
            f"{e.t_start_s - t0:.0f}-{e.t_end_s - t0:.0f}",
            str(e.n_ranges),
            str(e.n_outliers),
            f"{e.running.final_range_m:.3f}",
            f"{1e3 * e.sigma_m:.0f}",
            f"{1e3 * e.sigma_se_m:.0f}",
        )
    return table


def range_noise_line(noise: NoiseAnalysis) -> str:
    """The total range sigma the noise analysis recommends (journal VI-B)."""
    return (
        f"sigma_USBL = max over beacons = {1e3 * noise.sigma_usbl_m:.0f} mm; with sigma_GPS = "
        f"{noise.sigma_gps_m:g} m the total range sigma is {noise.sigma_total_m:.3f} m (journal VI-B); "
        "use it as --sigma-range"
    )


def truth_table(truth: BeaconTruth) -> Table:
    """``simulate logs``: the beacons' true positions, ENU from the earliest fix (the default origin of
    ``localize logs``, ``survey`` and ``replay logs``) and as latitude, longitude, height."""
    table = _table(f"True beacons, ENU from {origin_text(truth.origin, 'earliest fix')}")
    for col in ("beacon", "E m", "N m", "U m", "lat deg", "lon deg", "h m"):
        table.add_column(col, justify="right")
    for i, b in enumerate(truth.beacons):
        e, n, u = truth.enu_m[i]
        lat, lon, h = truth.geodetic[i]
        table.add_row(str(b), f"{e:+.2f}", f"{n:+.2f}", f"{u:+.2f}", f"{lat:.7f}", f"{lon:.7f}", f"{h:.2f}")
    return table


def gnatss_positions_table(loc: GnatssLocalization) -> Table:
    """An array's transponders: ENU about the array centre, 1-sigma and replies used."""
    table = _table(f"GNSS-A array ({escape(loc.method)}, {escape(loc.solution)}): ENU about the array centre")
    for col in ("transponder", "E m", "N m", "U m", "1σ E/N/U mm", "replies used"):
        table.add_column(col, justify="left" if col == "transponder" else "right")
    sig = 1e3 * loc.sigma_enu_m
    for k, tid in enumerate(loc.ids):
        e, n, u = loc.positions_enu_m[k]
        used = int(np.sum(~loc.excluded & (loc.transponder == k)))
        sig_text = f"{sig[k, 0]:.1f}/{sig[k, 1]:.1f}/{sig[k, 2]:.1f}"
        table.add_row(escape(tid), f"{e:+.4f}", f"{n:+.4f}", f"{u:+.4f}", sig_text, str(used))
    return table


def gnatss_geodetic_table(loc: GnatssLocalization) -> Table:
    """An array's transponders as WGS84 latitude, longitude and ellipsoidal height."""
    table = _table("GNSS-A array: geodetic positions (WGS84)")
    for col in ("transponder", "latitude °", "longitude °", "height m"):
        table.add_column(col, justify="left" if col == "transponder" else "right")
    for k, tid in enumerate(loc.ids):
        lat, lon, h = loc.positions_geodetic[k]
        table.add_row(escape(tid), f"{lat:.8f}", f"{lon:.8f}", f"{h:.4f}")
    return table


def gnatss_summary_lines(loc: GnatssLocalization) -> list[str]:
    """Replies used and excluded (by reason), convergence, sound speed."""
    reasons: dict[str, int] = {}
    for r, x in zip(loc.reason, loc.excluded, strict=True):
        if x:
            key = r.split(":")[0]
            reasons[key] = reasons.get(key, 0) + 1
    by = ", ".join(f"{k}: {v}" for k, v in sorted(reasons.items(), key=lambda kv: -kv[1]))
    speeds = "/".join(f"{c:.3f}" for c in loc.sound_speed_mps)
    lines = [
        f"{int((~loc.excluded).sum())} of {loc.excluded.size} replies used"
        + (f"; excluded: {by}" if by else ""),
        f"converged: {'yes' if loc.converged else 'no'} after {len(loc.iterations)} iterations; "
        f"sound speed {speeds} m/s",
    ]
    prior = loc.extra.get("lever_arm_prior_sigma_m")
    if loc.extra.get("lever_arm_estimated") or (prior and any(v > 0 for v in prior)):
        arm = ", ".join(
            f"{1e3 * a:.1f} +- {1e3 * s:.1f}"
            for a, s in zip(loc.extra["lever_arm_body_m"], loc.extra["lever_arm_sigma_m"], strict=True)
        )
        what = "estimated" if loc.extra.get("lever_arm_estimated") else "with its prior"
        prior_txt = "/".join(f"{1e3 * v:.1f}" for v in prior or [])
        lines.append(f"lever arm forward, right, down ({what}): {arm} mm")
        lines.append(f"lever arm prior sigma {prior_txt} mm")
    tests = loc.extra.get("model_tests") or []
    if tests:
        lines += [f"model: {_model_test_text(t)}" for t in tests]
    return lines


_MODEL_TEST_LABELS = {
    "gradient": "gradient",
    "sound_speed_variation": "speed variation",
    "sound_speed_scale": "speed scale",
    "gnss_serial_correlation": "GNSS common mode",
}


def _model_test_text(t: dict) -> str:
    """One model-selection test as text: kept or dropped, the statistic against its threshold (and the
    constant speed correction, in ppm, for the scale test)."""
    label = _MODEL_TEST_LABELS.get(t["name"], t["name"])
    verdict = (
        ("on" if t["kept"] else "off")
        if t["name"] == "gnss_serial_correlation"
        else ("kept" if t["kept"] else "dropped")
    )
    if t["dof"] == 0:
        return f"{label} {verdict} (too few replies to test)"
    value = ""
    if t["name"] == "sound_speed_scale" and t["estimate"]:
        value = f"{t['estimate'][0]:+.0f} +- {t['sigma'][0]:.0f} ppm, "
    sign = ">" if t["kept"] else "<="
    return f"{label} {verdict} ({value}{t['statistic']:.1f} {sign} {t['threshold']:.1f})"
