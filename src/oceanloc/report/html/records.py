"""Reports of the JSON records oceanloc writes: simulated survey, Monte Carlo, GNSS-A (surveys of one
transponder, or one survey of an array), reproduction, drift.

Each ``*_report(record)`` reads the record's keys only (as written by ``to_record``); nothing is
recomputed except the chi-square bounds the record's statistic is compared with.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import stats

from oceanloc.errors import DataError
from oceanloc.estimation.consistency import confidence_ellipse
from oceanloc.geo.enu import EnuOrigin
from oceanloc.report.html.model import Check, Circle, Estimate, MapLayers, Report, Series, Table

ELLIPSE95_SCALE = math.sqrt(stats.chi2.ppf(0.95, 2))
"""Semi-axis of the 95 % ellipse over the 1-sigma axis, two dof (2.448)."""


def _chi2_bounds(dof: int, confidence: float = 0.95) -> tuple[float, float]:
    a = (1.0 - confidence) / 2.0
    return float(stats.chi2.ppf(a, dof)), float(stats.chi2.ppf(1.0 - a, dof))


def _fmt(x: float, digits: int = 4) -> str:
    return f"{x:.{digits}g}"


def survey_report(rec: dict) -> Report:
    """One simulated survey (``simulate survey --runs 1 --json``): sites, estimates, errors, NEES."""
    tps = rec["transponders"]
    estimates = tuple(
        Estimate(
            label=f"m={t['m']}",
            east_m=t["estimate_enu_m"][0],
            north_m=t["estimate_enu_m"][1],
            semi_major_m=t["ellipse95_semi_axes_m"][0],
            semi_minor_m=t["ellipse95_semi_axes_m"][1],
            angle_rad=math.radians(t["ellipse95_angle_deg"]),
            truth_en_m=(t["truth_enu_m"][0], t["truth_enu_m"][1]),
            detail=f"error {t['error_m']:.3f} m, sd U {t['sigma_u_m']:.3f} m",
        )
        for t in tps
    )
    sites = np.asarray(rec["sites_enu_m"], dtype=float).reshape(-1, 3)[:, :2]
    layers = MapLayers(sites_en_m=sites, sites_label="measurement sites (in order)", estimates=estimates)
    err = np.asarray(rec["error_norm_m"], dtype=float).reshape(len(rec["log_det"]), -1)
    epoch = np.arange(1, err.shape[0] + 1)
    errors = Series(
        title="Position error by epoch",
        x_label="epoch n",
        y_label="error (m)",
        log_y=True,
        lines=tuple((f"m={t['m']}", epoch, err[:, i], "lines+markers", None) for i, t in enumerate(tps)),
    )
    logdet = Series(
        title="log det Y_n by epoch",
        x_label="epoch n",
        y_label="log det Y_n (nats)",
        lines=(("log det Y_n", epoch, np.asarray(rec["log_det"]), "lines+markers", None),),
    )
    lo, hi = _chi2_bounds(rec["nees_dof"])
    nees = rec["nees_final"]
    checks = (
        Check(
            name=f"NEES at the last epoch within the 95 % chi-square interval ({rec['nees_dof']} dof)",
            passed=lo <= nees <= hi,
            value=_fmt(nees),
            bound=f"[{lo:.3g}, {hi:.3g}]",
            detail="one run: a check of this run only",
        ),
    )
    table = Table(
        title="Transponders",
        header=(
            "m",
            "truth E,N,U (m)",
            "estimate E,N,U (m)",
            "error (m)",
            "95% a x b (m)",
            "angle (deg)",
            "sd U (m)",
        ),
        rows=tuple(
            (
                str(t["m"]),
                ", ".join(f"{v:.3f}" for v in t["truth_enu_m"]),
                ", ".join(f"{v:.3f}" for v in t["estimate_enu_m"]),
                f"{t['error_m']:.4f}",
                f"{t['ellipse95_semi_axes_m'][0]:.4f} x {t['ellipse95_semi_axes_m'][1]:.4f}",
                f"{t['ellipse95_angle_deg']:.1f}",
                f"{t['sigma_u_m']:.4f}",
            )
            for t in tps
        ),
    )
    return Report(
        kind="survey",
        title=f"Simulated survey {rec['scenario']} ({rec['planner_label']}, {rec['epochs']} epochs)",
        summary=(
            f"{len(tps)} transponders, {sites.shape[0]} measurement sites, seed {rec['seed']}",
            f"NEES at the last epoch {nees:.2f} ({rec['nees_dof']} dof)",
            f"mean planning time {rec['plan_time_s'] * 1e3:.2f} ms per epoch",
        ),
        map=layers,
        series=(errors, logdet),
        tables=(table,),
        checks=checks,
        provenance=rec.get("provenance", {}),
    )


def montecarlo_report(rec: dict) -> Report:
    """A Monte Carlo of surveys (``simulate survey --runs N --json``): RMSEE, log det, NEES by epoch."""
    rmsee = np.asarray(rec["rmsee_m"], dtype=float).reshape(len(rec["logdet_mean"]), -1)
    epoch = np.arange(1, rmsee.shape[0] + 1)
    cons = rec.get("consistency_by_epoch", {})
    series = [
        Series(
            title="RMS error by epoch",
            x_label="epoch n",
            y_label="RMSEE (m)",
            log_y=True,
            lines=tuple(
                (f"m={i + 1}", epoch, rmsee[:, i], "lines+markers", None) for i in range(rmsee.shape[1])
            ),
        ),
        Series(
            title="log det Y_n by epoch (mean and mean +- sd)",
            x_label="epoch n",
            y_label="log det Y_n (nats)",
            lines=(
                ("mean", epoch, np.asarray(rec["logdet_mean"]), "lines+markers", None),
                ("mean + sd", epoch, np.add(rec["logdet_mean"], rec["logdet_std"]), "lines", None),
                ("mean - sd", epoch, np.subtract(rec["logdet_mean"], rec["logdet_std"]), "lines", None),
            ),
        ),
    ]
    checks = []
    n = rec.get("nees")
    if n:
        checks.append(
            Check(
                name=f"mean NEES at epoch {n['epoch']} within its 95 % band "
                f"({n['dof']} dof, {rec['runs']} runs)",
                passed=bool(n["mean_within_band"]),
                value=_fmt(n["mean"]),
                bound=f"[{n['mean_band'][0]:.3g}, {n['mean_band'][1]:.3g}]",
                detail=f"p = {n['p_value']:.3f}",
            )
        )
    if cons:
        frac = np.asarray(cons["fraction_above_quantile"], dtype=float)
        series.append(
            Series(
                title=f"Mean NEES by epoch ({cons['dof']} dof, {cons['runs']} runs)",
                x_label="epoch n",
                y_label="mean NEES",
                log_y=True,
                lines=(
                    ("mean NEES", epoch, np.asarray(cons["mean_nees"]), "lines+markers", None),
                    (
                        f"{cons['confidence']:.0%} chi-square quantile",
                        epoch,
                        np.full(epoch.size, cons["chi2_quantile"]),
                        "lines",
                        None,
                    ),
                ),
            )
        )
        checks.append(
            Check(
                name="runs above the chi-square quantile at the last epoch",
                passed=bool(frac[-1] <= 1.0 - cons["confidence"] + 3 * math.sqrt(0.05 * 0.95 / cons["runs"])),
                value=f"{frac[-1]:.3f}",
                bound=f"<= {1 - cons['confidence']:.2f} + 3 standard errors",
            )
        )
    if "converged_fraction" in rec:
        checks.append(
            Check(
                name="estimator converged (share of epoch fits)",
                passed=rec["converged_fraction"] >= 0.99,
                value=f"{rec['converged_fraction']:.4f}",
                bound=">= 0.99",
            )
        )
    return Report(
        kind="montecarlo",
        title=f"Monte Carlo {rec['scenario']} ({rec['planner_label']}, {rec['runs']} runs, "
        f"{rec['epochs']} epochs)",
        summary=(f"seed {rec['seed']}", f"mean planning time {rec['plan_time_s'] * 1e3:.2f} ms per epoch"),
        series=tuple(series),
        checks=tuple(checks),
        provenance=rec.get("provenance", {}),
        notes=("A Monte Carlo record holds statistics over runs, not one track: no map.",),
    )


def _ping_series(label: str, pings: dict) -> Series:
    """Residual per ping of a GNSS-A survey: the used ones by transponder, the excluded ones by reason.

    ``pings`` holds equal-length lists ``t_s``, ``transponder``, ``residual_m``, ``excluded`` (bool) and
    ``reason`` (text, empty for a used ping).
    """
    t = np.asarray(pings["t_s"], dtype=float)
    tp = np.asarray([str(x) for x in pings["transponder"]])
    res = np.asarray(pings["residual_m"], dtype=float)
    excl = np.asarray(pings["excluded"], dtype=bool)
    reason = np.asarray([str(x) for x in pings.get("reason") or [""] * t.size])
    if not (t.size == tp.size == res.size == excl.size == reason.size):
        raise ValueError(f"pings of {label}: t_s, transponder, residual_m, excluded, reason differ in length")
    lines = [
        (f"transponder {x} used", t[~excl & (tp == x)], res[~excl & (tp == x)], "markers", None)
        for x in np.unique(tp[~excl])
    ]
    for why in np.unique(reason[excl]):
        sel = excl & (reason == why)
        lines.append(
            (
                f"excluded: {why or 'no reason given'}",
                t[sel],
                res[sel],
                "markers",
                [f"transponder {x}: {why}" for x in tp[sel]],
            )
        )
    return Series(
        title=f"Residuals per ping: {label} ({int(excl.sum())} of {t.size} excluded)",
        x_label="ping time (s, as in the record)",
        y_label="residual (m)",
        lines=tuple(lines),
    )


def gnssa_report(rec: dict) -> Report:
    """GNSS-A surveys (``localize gnssa --json``): positions with ellipses, sound speed, spread checks."""
    sv = rec["surveys"]
    estimates = tuple(
        Estimate(
            label=s["file"],
            east_m=s["e_m"],
            north_m=s["n_m"],
            semi_major_m=ELLIPSE95_SCALE * max(s["sigma_e_m"], s["sigma_n_m"]),
            semi_minor_m=ELLIPSE95_SCALE * min(s["sigma_e_m"], s["sigma_n_m"]),
            angle_rad=0.0 if s["sigma_e_m"] >= s["sigma_n_m"] else math.pi / 2,
            detail=f"{s['file']}: {s['pings_used']} pings used, {s['pings_excluded']} excluded",
        )
        for s in sv
    )
    pos = np.array([[s["e_m"], s["n_m"]] for s in sv])
    layers = MapLayers(sites_en_m=pos, sites_label="survey positions (in time order)", estimates=estimates)
    t = [s["epoch_utc"] for s in sv]
    hover = [f"{s['file']}" for s in sv]
    series = [
        Series(
            title="Sound speed estimated per survey",
            x_label="survey epoch (UTC)",
            y_label="sound speed (m/s)",
            lines=(("sound speed", t, np.array([s["sound_speed_mps"] for s in sv]), "lines+markers", hover),),
        ),
        Series(
            title="Horizontal sound-speed gradient per survey",
            x_label="survey epoch (UTC)",
            y_label="gradient (1/km)",
            lines=tuple(
                (
                    f"gradient {c.upper()}",
                    t,
                    np.array([s.get(f"gradient_{c}_per_km", np.nan) for s in sv]),
                    "lines+markers",
                    hover,
                )
                for c in ("e", "n")
            ),
        ),
        Series(
            title="Residual RMS and pings per survey",
            x_label="survey epoch (UTC)",
            y_label="residual RMS (m)",
            lines=(
                (
                    "residual RMS",
                    t,
                    np.array([s["residual_rms_m"] for s in sv]),
                    "lines+markers",
                    [f"{s['file']}: {s['pings_used']} used, {s['pings_excluded']} excluded" for s in sv],
                ),
            ),
        ),
    ]
    groups = [(s["file"], s["pings"]) for s in sv if s.get("pings")]
    if rec.get("pings"):
        groups.append(("all surveys", rec["pings"]))
    series += [_ping_series(label, pings) for label, pings in groups]
    checks = []
    sp = rec["spread"]
    for title, block in (
        ("about the fitted velocity", sp),
        ("at the survey epochs", sp.get("at_survey_epochs")),
    ):
        if not block:
            continue
        lo, hi = block["chi2_95_range"]
        for c, name in (("n", "north"), ("e", "east"), ("u", "up")):
            checks.append(
                Check(
                    name=f"between-survey spread {name} {title}: sigmas explain it (chi-square)",
                    passed=bool(block[f"sigmas_explain_{c}"]),
                    value=_fmt(block[f"chi2_{c}"]),
                    bound=f"[{lo:.3g}, {hi:.3g}]",
                    detail=f"spread sd {block[f'std_{c}_m'] * 100:.2f} cm",
                )
            )
    table = Table(
        title="Surveys",
        header=(
            "file",
            "epoch (UTC)",
            "E (m)",
            "N (m)",
            "U (m)",
            "sd E (m)",
            "sd N (m)",
            "sd U (m)",
            "sound speed (m/s)",
            "pings used",
            "pings excluded",
            "residual RMS (m)",
        ),
        rows=tuple(
            (
                s["file"],
                s["epoch_utc"],
                f"{s['e_m']:.4f}",
                f"{s['n_m']:.4f}",
                f"{s['u_m']:.4f}",
                f"{s['sigma_e_m']:.4f}",
                f"{s['sigma_n_m']:.4f}",
                f"{s['sigma_u_m']:.4f}",
                f"{s['sound_speed_mps']:.2f}",
                str(s["pings_used"]),
                str(s["pings_excluded"]),
                f"{s['residual_rms_m']:.4f}",
            )
            for s in sv
        ),
    )
    vel = sp.get("site_velocity", {})
    return Report(
        kind="gnssa",
        title=f"GNSS-A: {len(sv)} surveys of one transponder",
        summary=(
            f"reference epoch {sp.get('reference_epoch_utc', '?')}",
            f"site velocity {vel.get('source', '?')}: E {vel.get('e_mm_yr', float('nan')):.1f} mm/yr, "
            f"N {vel.get('n_mm_yr', float('nan')):.1f} mm/yr",
            f"between-survey sd N {sp['std_n_m'] * 100:.2f} cm, E {sp['std_e_m'] * 100:.2f} cm, "
            f"U {sp['std_u_m'] * 100:.2f} cm",
        ),
        map=layers,
        series=tuple(series),
        tables=(table,),
        checks=tuple(checks),
        provenance=rec.get("provenance", {}),
        notes=(
            "Positions are offsets from the reference position, metres; ellipses from each survey's "
            "east and north sigmas (the record holds no east-north covariance)."
            + ("" if groups else " The record holds per-survey residual statistics, not per-ping residuals."),
        ),
    )


def gnssa_array_report(rec: dict) -> Report:
    """One GNSS-A survey of an array (``localize gnssa --format gnatss --json``): transponders with their
    95 % ellipses, the array centre, residuals per ping, the sound-speed correction, iterations, checks.

    The ellipses are the east-north blocks of ``details.covariance_m2`` (three rows and columns per
    transponder, east, north, up, in the order of ``transponders``).
    """
    tps = rec["transponders"]
    d = rec["details"]
    cov = np.asarray(d["covariance_m2"], dtype=float).reshape(3 * len(tps), 3 * len(tps))
    idx = np.arange(len(tps))[:, None] * 3 + np.arange(2)
    en_cov = cov[idx[:, :, None], idx[:, None, :]]
    en = np.array([[t["e_m"], t["n_m"]] for t in tps], dtype=float)
    ell = confidence_ellipse(en, en_cov, 0.95)
    estimates = tuple(
        Estimate(
            label=str(t["id"]),
            east_m=float(en[i, 0]),
            north_m=float(en[i, 1]),
            semi_major_m=float(ell.semi_major_m[i]),
            semi_minor_m=float(ell.semi_minor_m[i]),
            angle_rad=float(ell.angle_rad[i]),
            detail=f"U {t['u_m']:.3f} m, sd U {t['sigma_u_m']:.3f} m; {t['replies_used']} replies used",
        )
        for i, t in enumerate(tps)
    )
    c = rec["centre"]
    o = rec["origin"]
    layers = MapLayers(
        sites_en_m=np.array([[c["e_m"], c["n_m"]]], dtype=float),
        sites_label="array centre (estimated)",
        sites_connect=False,
        estimates=estimates,
        origin=EnuOrigin(lat_deg=o["lat_deg"], lon_deg=o["lon_deg"], h_m=o["h_m"]),
    )
    series = [_ping_series("array", rec["pings"])]
    if d.get("knot_times_s") and d.get("sound_speed_knots_mps"):
        t_k = np.asarray(d["knot_times_s"], dtype=float)
        v_k = np.asarray(d["sound_speed_knots_mps"], dtype=float)
        sd_k = np.asarray(d.get("sound_speed_knot_sigma_mps") or np.full(t_k.size, np.nan), dtype=float)
        series.append(
            Series(
                title="Sound speed at the knots of its correction over time",
                x_label="time (s, as in the record)",
                y_label="sound speed (m/s)",
                lines=(
                    (
                        "sound speed at the knots",
                        t_k,
                        v_k,
                        "lines+markers",
                        [f"sd {s:.3f} m/s" for s in sd_k],
                    ),
                    ("knot + sd", t_k, v_k + sd_k, "lines", None),
                    ("knot - sd", t_k, v_k - sd_k, "lines", None),
                ),
            )
        )
    used, excl = int(rec["replies"]) - int(rec["replies_excluded"]), int(rec["replies_excluded"])
    checks = (
        Check(
            name="solver converged",
            passed=bool(rec["converged"]),
            value="yes" if rec["converged"] else "no",
            detail=f"{len(rec['iterations'])} iterations, status {d.get('status', '?')}",
        ),
        Check(
            name="replies used vs excluded: at most 5 % excluded",
            passed=excl <= 0.05 * int(rec["replies"]),
            value=f"{used} used, {excl} excluded",
            bound=f"<= {0.05 * int(rec['replies']):.0f} excluded",
            detail=f"of {rec['replies']} replies",
        ),
    )
    keys = ("round", "replies_used", "sigma_path_m", "beta_m", "cost", "map_iterations", "position_change_m")
    tables = (
        Table(
            title="Transponders",
            header=(
                "id",
                "E (m)",
                "N (m)",
                "U (m)",
                "sd E (m)",
                "sd N (m)",
                "sd U (m)",
                "95% a x b (m)",
                "replies used",
            ),
            rows=tuple(
                (
                    str(t["id"]),
                    f"{t['e_m']:.4f}",
                    f"{t['n_m']:.4f}",
                    f"{t['u_m']:.4f}",
                    f"{t['sigma_e_m']:.4f}",
                    f"{t['sigma_n_m']:.4f}",
                    f"{t['sigma_u_m']:.4f}",
                    f"{e.semi_major_m:.4f} x {e.semi_minor_m:.4f}",
                    str(t["replies_used"]),
                )
                for t, e in zip(tps, estimates, strict=True)
            ),
        ),
        Table(
            title="Iterations",
            header=(
                "iteration",
                "round",
                "replies used",
                "sigma path (m)",
                "beta (m)",
                "cost",
                "MAP iterations",
                "position change (m)",
                "excluded",
            ),
            rows=tuple(
                (
                    str(i + 1),
                    *(_fmt(float(it[k])) if isinstance(it[k], float) else str(it[k]) for k in keys),
                    str(it.get("excluded", "")),
                )
                for i, it in enumerate(rec["iterations"])
            ),
        ),
    )
    sc = d.get("centre_sigma_enu_m") or [float("nan")] * 3
    return Report(
        kind="gnssa-array",
        title=f"GNSS-A array: {len(tps)} transponders ({rec.get('method', '?')}, {rec.get('solution', '?')})",
        summary=(
            f"survey epoch {d.get('epoch_utc', '?')}, file {d.get('file', '?')}",
            f"array centre E {c['e_m']:.4f} m, N {c['n_m']:.4f} m, U {c['u_m']:.4f} m "
            f"(sd {sc[0] * 100:.1f}, {sc[1] * 100:.1f}, {sc[2] * 100:.1f} cm)",
            f"{used} of {rec['replies']} replies used; sound-speed correction "
            f"{d.get('speed_correction_ppm', float('nan')):.1f} ppm; residual RMS "
            f"{d.get('residual_rms_m', float('nan')):.4f} m",
        ),
        map=layers,
        series=tuple(series),
        tables=tables,
        checks=checks,
        provenance=rec.get("provenance", {}),
        notes=(
            "East-north about the record's origin (the array centre the survey was configured with), "
            "metres; ellipses from the east-north blocks of the transponders' covariance.",
        ),
    )


def reproduction_report(rec: dict) -> Report:
    """A reproduction (``reproduce garcia2019 --json``): acceptance checks, paper beside ours, curves."""
    checks = tuple(
        Check(name=c["name"], passed=bool(c["passed"]), detail=c.get("detail", ""))
        for c in rec.get("checks", [])
    )
    tables = []
    if rec.get("verdicts"):
        tables.append(
            Table(
                title="Verdicts",
                header=("item", "status", "evidence"),
                rows=tuple((v["item"], v["status"], v["evidence"]) for v in rec["verdicts"]),
            )
        )
    for name, rows in rec.get("tables", {}).items():
        tables.append(
            Table(
                title=f"Table {name}: paper beside ours",
                header=(
                    "epoch n",
                    "planner",
                    "RMSE ours (m)",
                    "RMSE paper (m)",
                    "log det ours (nats)",
                    "log det paper (nats)",
                    "sd ours (nats)",
                    "sd paper (nats)",
                    "z",
                    "agreement",
                ),
                rows=tuple(
                    (
                        str(r["epoch"]),
                        r["planner"],
                        f"{r['rmse_m']:.3f}",
                        f"{r['paper_rmse_m']:.3f}",
                        f"{r['logdet_mean']:.2f}",
                        f"{r['paper_logdet_mean']:.2f}",
                        f"{r['logdet_std']:.2f}",
                        f"{r['paper_logdet_std']:.2f}",
                        f"{r['logdet_z']:.2f}",
                        r["agreement"],
                    )
                    for r in rows
                ),
            )
        )
    series = []
    for study, planners in rec.get("studies", {}).items():
        series.append(
            Series(
                title=f"{study}: log det Y_n by epoch (mean over runs)",
                x_label="epoch n",
                y_label="log det Y_n (nats)",
                lines=tuple(
                    (
                        p["planner_label"],
                        np.arange(1, len(p["logdet_mean"]) + 1),
                        np.asarray(p["logdet_mean"]),
                        "lines",
                        None,
                    )
                    for p in planners.values()
                ),
            )
        )
        series.append(
            Series(
                title=f"{study}: RMS error by epoch (RMS over transponders)",
                x_label="epoch n",
                y_label="RMSEE (m)",
                log_y=True,
                lines=tuple(
                    (
                        p["planner_label"],
                        np.arange(1, len(p["rmsee_m"]) + 1),
                        np.sqrt(np.mean(np.square(np.asarray(p["rmsee_m"], dtype=float)), axis=1)),
                        "lines",
                        None,
                    )
                    for p in planners.values()
                ),
            )
        )
    prov = rec.get("provenance", {})
    n_pass = sum(c.passed for c in checks)
    return Report(
        kind="reproduction",
        title=f"Reproduction: {prov.get('scenario', 'paper')} ({rec.get('runs', '?')} runs)",
        summary=(f"{n_pass} of {len(checks)} acceptance checks pass", f"seed {rec.get('seed')}"),
        series=tuple(series),
        tables=tuple(tables),
        checks=checks,
        provenance=prov,
        notes=("A reproduction record holds statistics over runs, not one track: no map.",),
    )


def drift_report(rec: dict, scenario: object | None = None) -> Report:
    """A drift plan (``drift-plan --json``): drift and flight legs, start, goal, obstacles, current field.

    ``scenario`` (a :class:`~oceanloc.config.drift.DriftScenario`, when its name loads) adds the obstacles
    and the current field; the record alone gives the route.
    """
    res = rec["result"]
    path = res.get("path")
    if not path:
        raise DataError(
            f"drift plan: no path in the record (status {res.get('status')}: {res.get('message')})"
        )
    xy = np.column_stack([path["x_m"], path["y_m"]])
    flight = np.asarray(path["flight"], dtype=bool)
    legs = []
    for label, want in (("flight legs", True), ("drift legs", False)):
        pts = []
        for i in np.flatnonzero(flight == want):
            pts += [xy[i], xy[i + 1], [np.nan, np.nan]]
        if pts:
            legs.append((label, np.asarray(pts)))
    circles = [
        Circle(
            label="goal tolerance",
            east_m=rec["goal_m"][0],
            north_m=rec["goal_m"][1],
            radius_m=rec["goal_tolerance_m"],
        )
    ]
    polygons: list = []
    current = None
    if scenario is not None:
        obs = scenario.obstacles  # type: ignore[attr-defined]
        for r in np.asarray(obs.rectangles_m).reshape(-1, 4):
            polygons.append(("obstacle", np.array([[r[0], r[2]], [r[1], r[2]], [r[1], r[3]], [r[0], r[3]]])))
        polygons += [("obstacle", np.asarray(p)) for p in obs.polygons_m]
        b = np.asarray(obs.bounds_m, dtype=float)
        gx, gy = np.meshgrid(np.linspace(b[0], b[1], 21), np.linspace(b[2], b[3], 21))
        grid = np.column_stack([gx.ravel(), gy.ravel()])
        uv = np.asarray(scenario.current.velocity(grid), dtype=float).reshape(-1, 2)  # type: ignore[attr-defined]
        current = np.column_stack([grid, uv])
    layers = MapLayers(
        sites_en_m=np.array([rec["start_m"], rec["goal_m"]], dtype=float),
        sites_label="start (1) and goal (2)",
        sites_connect=False,
        legs=tuple(legs),
        circles=tuple(circles),
        polygons=tuple(polygons),
        current=current,
    )
    t_h = np.asarray(path["t_s"]) / 3600.0
    dist = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    series = (
        Series(
            title="Distance along the route",
            x_label="time (h)",
            y_label="distance (m)",
            lines=(("distance", t_h, dist, "lines", None),),
        ),
    )
    e = rec["energy"]
    checks = (
        Check(
            name="planner status", passed=res["status"] == "exact", value=res["status"], detail=res["message"]
        ),
        Check(
            name="energy budget: net energy after the route",
            passed=e["net_wh"] >= 0.0,
            value=f"{e['net_wh']:.2f} Wh",
            bound=">= 0 Wh",
        ),
        Check(
            name="route saves energy over the direct flight",
            passed=res["flight_energy_wh"] <= res["direct_flight_wh"],
            value=f"{res['flight_energy_wh']:.2f} Wh",
            bound=f"<= {res['direct_flight_wh']:.2f} Wh",
        ),
    )
    return Report(
        kind="drift",
        title=f"Drift plan {rec['scenario']} (planner {rec['planner']})",
        summary=(
            f"currents: {rec['currents']}",
            f"{path['flights']} flights, {path['flight_distance_m']:.0f} m flown, "
            f"drift {path['drift_time_s'] / 3600:.2f} h, "
            f"duration {path['duration_s'] / 3600:.2f} h",
            f"flight energy {res['flight_energy_wh']:.2f} Wh "
            f"(direct flight {res['direct_flight_wh']:.2f} Wh, "
            f"saving {res['saving']:.0%})",
            rec.get("convention", ""),
        ),
        map=layers,
        series=series,
        checks=checks,
        provenance=rec.get("provenance", {}),
    )
