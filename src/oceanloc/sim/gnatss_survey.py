"""A synthetic GNSS-A array survey with a known truth, written in GNATSS's input formats.

A surface platform (a wave glider) loops around the array centre; its GNSS antenna position, roll,
pitch and heading are known each ping; the transducer hangs below the antenna at a body-frame lever arm
(forward, rightward, downward; GNATSS's ``atd_offsets`` convention: rotation ``R = Rz(heading)
Ry(pitch) Rx(roll)`` of the body offsets into north-east-down). Each interrogation reaches the array's
transponders; the two-way travel time is the straight-ray path at each transponder's harmonic-mean
sound speed of the profile (:meth:`~oceanloc.io.gnatss.SoundSpeedProfile.harmonic_mean_mps`: GNATSS's
own model), optionally scaled by an unmodelled sound-speed drift in time and a horizontal slowness
gradient, plus the transponder's internal delay and white timing noise. The positions written carry
white GNSS noise with the covariance written beside them. A few gross travel-time errors and missing
replies can be added.

Files (:func:`write_gnatss_survey`): ``config.yaml`` (GNATSS configuration: array centre, a-priori
transponder positions = truth + a common offset, internal delays, solver limits), ``pxp_tt``,
``POS_FREED_TRANS_TWTT``, ``gps_solution.csv`` (Level-2), ``ctd_profile.txt``, ``GPS_POS_FREED``
(antenna), ``RPH`` (attitude), ``antenna.csv`` (the same antenna track and attitude as one antenna CSV,
:mod:`oceanloc.io.antenna_csv`) and ``truth.json``.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import pymap3d

from oceanloc._typing import FloatArray
from oceanloc.geo.enu import EnuOrigin
from oceanloc.io.antenna_csv import write_antenna_csv
from oceanloc.io.gnatss import (
    ArrayPings,
    SoundSpeedProfile,
    write_gnatss_config,
    write_gps_pos_freed,
    write_level2_csv,
    write_pos_freed_trans_twtt,
    write_pxp_tt,
    write_roll_pitch_heading,
    write_sound_speed_profile,
)
from oceanloc.io.qc import QcReport
from oceanloc.models.sound_profile import SoundSpeedProfile as LayeredProfile
from oceanloc.models.sound_profile import ray_travel_time_s


@dataclass(frozen=True, slots=True, kw_only=True)
class ArraySurveySpec:
    """Settings of the synthetic array survey (units in the names; angles in degrees).

    ``sound_speed_drift`` is the relative change of every sound speed over the survey (linear in time,
    plus a half-amplitude sinusoid of period ``drift_period_s``); ``gradient_per_km`` the relative
    change of slowness per kilometre east and north of the centre. Both are unmodelled by a fixed
    harmonic-mean speed.
    """

    n_pings: int = 2000
    ping_interval_s: float = 15.0
    start_j2000_s: float = 741_009_600.0
    site_id: str = "SYN1"
    center_lat_deg: float = 45.30
    center_lon_deg: float = -124.97
    geoid_undulation_m: float = -26.59
    array_radius_m: float = 1000.0
    depths_m: tuple[float, ...] = (1500.0, 1520.0, 1485.0)
    internal_delays_s: tuple[float, ...] = (0.20, 0.60, 1.00)
    apriori_offset_enu_m: tuple[float, float, float] = (0.60, -0.40, 0.30)
    track_radius_m: tuple[float, float] = (20.0, 160.0)
    track_period_s: float = 14_400.0
    lever_arm_frd_m: tuple[float, float, float] = (0.30, -0.10, 1.20)
    roll_amplitude_deg: float = 6.0
    pitch_amplitude_deg: float = 4.0
    sigma_gnss_enu_m: tuple[float, float, float] = (0.02, 0.02, 0.04)
    sigma_twtt_s: float = 1e-5
    gross_fraction: float = 0.004
    gross_error_s: float = 2e-3
    missing_fraction: float = 0.0
    sound_speed_drift: float = 0.0
    drift_period_s: float = 7200.0
    gradient_per_km: tuple[float, float] = (0.0, 0.0)
    residual_limit_cm: float = 25.0
    distance_limit_m: float = 150.0
    ray_traced: bool = False
    seed: int = 13

    def __post_init__(self) -> None:
        if len(self.depths_m) != len(self.internal_delays_s) or len(self.depths_m) < 1:
            raise ValueError("one depth and one internal delay per transponder")


def sound_speed_profile(max_depth_m: float = 2500.0) -> tuple[FloatArray, FloatArray]:
    """A mid-latitude North-Pacific-like profile: warm mixed layer, thermocline, deep linear increase.

    Depth (m, positive down, every 10 m from 0) and speed (m/s).
    """
    z = np.arange(0.0, max_depth_m + 1.0, 10.0)
    c = (
        1478.0
        + 24.0 * np.exp(-z / 180.0)
        + 0.0165 * np.maximum(z - 800.0, 0.0)
        - 0.004 * np.minimum(z, 800.0)
    )
    return z, c


@dataclass(frozen=True, slots=True, kw_only=True)
class ArraySurveyTruth:
    """What the synthetic survey was made of (all positions in ENU about the array centre, metres).

    Attributes
    ----------
    origin : EnuOrigin
        Array centre (ellipsoidal height 0).
    ids : tuple of str
    transponders_enu_m : (m, 3) float
        True transponder positions.
    apriori_enu_m : (m, 3) float
        The a-priori positions written in the configuration (truth + the common offset).
    transponders_xyz_m : (m, 3) float
        True positions, Earth-fixed.
    sound_speed_mps : (m,) float
        Harmonic-mean speed of each transponder's column (before drift and gradient).
    lever_arm_frd_m : (3,) float
    pings : ArrayPings
        The replies as written (noisy positions, measured travel times).
    gross : (n,) bool
        Replies given a gross travel-time error.
    """

    origin: EnuOrigin
    ids: tuple[str, ...]
    transponders_enu_m: FloatArray
    apriori_enu_m: FloatArray
    transponders_xyz_m: FloatArray
    sound_speed_mps: FloatArray
    lever_arm_frd_m: FloatArray
    pings: ArrayPings
    gross: np.ndarray
    spec: ArraySurveySpec = field(repr=False)

    def to_record(self) -> dict:
        """Plain JSON-ready truth."""
        return {
            "origin": {
                "lat_deg": self.origin.lat_deg,
                "lon_deg": self.origin.lon_deg,
                "h_m": self.origin.h_m,
            },
            "ids": list(self.ids),
            "transponders_enu_m": self.transponders_enu_m.tolist(),
            "apriori_enu_m": self.apriori_enu_m.tolist(),
            "transponders_xyz_m": self.transponders_xyz_m.tolist(),
            "sound_speed_mps": self.sound_speed_mps.tolist(),
            "lever_arm_frd_m": self.lever_arm_frd_m.tolist(),
            "n_replies": self.pings.n_replies,
            "n_gross": int(self.gross.sum()),
            "spec": {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self.spec).items()},
        }


def body_to_enu(rph_deg: FloatArray, offset_frd_m: FloatArray) -> FloatArray:
    """Body-frame (forward, rightward, downward) offsets rotated to (east, north, up), ``(n, 3)`` m.

    ``R = Rz(heading) Ry(pitch) Rx(roll)`` maps body axes to north-east-down (heading clockwise from
    north); east = NED[1], north = NED[0], up = -NED[2].
    """
    r, p, h = np.radians(np.asarray(rph_deg, dtype=float)).T
    cr, sr, cp, sp, ch, sh = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(h), np.sin(h)
    f, rt, d = np.asarray(offset_frd_m, dtype=float)
    north = ch * cp * f + (ch * sp * sr - sh * cr) * rt + (ch * sp * cr + sh * sr) * d
    east = sh * cp * f + (sh * sp * sr + ch * cr) * rt + (sh * sp * cr - ch * sr) * d
    down = -sp * f + cp * sr * rt + cp * cr * d
    return np.stack([east, north, -down], axis=-1)


def _platform(spec: ArraySurveySpec, t_rel_s: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Antenna ENU (m) and roll, pitch, heading (deg) at times since the start (s)."""
    r_lo, r_hi = spec.track_radius_m
    omega = 2.0 * np.pi / 1800.0  # one loop per half hour
    radius = r_lo + (r_hi - r_lo) * 0.5 * (1.0 - np.cos(2.0 * np.pi * t_rel_s / spec.track_period_s))
    ang = omega * t_rel_s
    e, n = radius * np.cos(ang), radius * np.sin(ang)
    heading = np.degrees(np.arctan2(np.cos(ang), -np.sin(ang)))  # direction of travel, clockwise from N
    up = 0.3 * np.sin(2.0 * np.pi * t_rel_s / 8.0) + spec.geoid_undulation_m + 0.2  # waves; antenna 0.2 m up
    roll = spec.roll_amplitude_deg * np.sin(2.0 * np.pi * t_rel_s / 7.0)
    pitch = spec.pitch_amplitude_deg * np.sin(2.0 * np.pi * t_rel_s / 5.3 + 1.0)
    return np.stack([e, n, up], axis=-1), np.stack([roll, pitch, heading], axis=-1)


def _enu_cov_to_ecef(cov_enu: FloatArray, origin: EnuOrigin) -> FloatArray:
    lat, lon = np.radians(origin.lat_deg), np.radians(origin.lon_deg)
    sl, cl, so, co = np.sin(lat), np.cos(lat), np.sin(lon), np.cos(lon)
    r = np.array([[-so, -sl * co, cl * co], [co, -sl * so, cl * so], [0.0, cl, sl]])  # ENU -> ECEF
    return r @ cov_enu @ r.T


def _to_ecef(enu: FloatArray, origin: EnuOrigin) -> FloatArray:
    x, y, z = pymap3d.enu2ecef(
        enu[..., 0], enu[..., 1], enu[..., 2], origin.lat_deg, origin.lon_deg, origin.h_m
    )
    return np.stack([x, y, z], axis=-1)


def _ray_legs_s(
    prof: LayeredProfile, tx: FloatArray, rx: FloatArray, tp: FloatArray, surface_m: float
) -> FloatArray:
    """Two-way eigenray time (s) of transmit ``tx`` and receive ``rx`` transducer positions ``(n, m, 3)``
    to the transponders ``tp`` ``(m, 3)``, ENU metres, with the sea surface at ENU height ``surface_m``."""
    total = np.zeros(rx.shape[:2])
    for end in (np.broadcast_to(tx, rx.shape), rx):
        top = np.maximum(surface_m - end[..., 2], 0.0)
        bottom = np.broadcast_to(surface_m - tp[:, 2], top.shape)
        horizontal = np.linalg.norm(end[..., :2] - tp[:, :2], axis=-1)
        t, _, _ = ray_travel_time_s(prof, top.ravel(), bottom.ravel(), horizontal.ravel())
        total = total + t.reshape(top.shape)
    return total


def simulate_array_survey(spec: ArraySurveySpec) -> ArraySurveyTruth:
    """Draw the synthetic survey (deterministic for a given ``spec.seed``)."""
    rng = np.random.default_rng(spec.seed)
    origin = EnuOrigin(lat_deg=spec.center_lat_deg, lon_deg=spec.center_lon_deg, h_m=0.0)
    m = len(spec.depths_m)
    ids = tuple(f"{spec.site_id}-{k + 1}" for k in range(m))
    az = np.radians(90.0 - 120.0 * np.arange(m) + 30.0)
    truth_enu = np.stack(
        [
            spec.array_radius_m * np.cos(az),
            spec.array_radius_m * np.sin(az),
            -np.asarray(spec.depths_m) + spec.geoid_undulation_m,
        ],
        axis=-1,
    )
    z, c = sound_speed_profile()
    prof = SoundSpeedProfile(path="", depth_m=z, speed_mps=c, qc=QcReport())
    c_hm = np.array([prof.harmonic_mean_mps(0.0, d) for d in spec.depths_m])
    lever = np.asarray(spec.lever_arm_frd_m, dtype=float)
    n = spec.n_pings
    t_tx_rel = np.arange(n) * spec.ping_interval_s
    ant_tx, rph_tx = _platform(spec, t_tx_rel)
    trans_tx = ant_tx + body_to_enu(rph_tx, lever)
    delays = np.asarray(spec.internal_delays_s)
    duration = max(n * spec.ping_interval_s, 1.0)

    def speed(t_rel: FloatArray, pos: FloatArray) -> FloatArray:
        frac = t_rel / duration
        drift = spec.sound_speed_drift * (frac + 0.5 * np.sin(2.0 * np.pi * t_rel / spec.drift_period_s))
        g = np.asarray(spec.gradient_per_km) * 1e-3
        slowness_scale = 1.0 + g[0] * pos[..., 0] + g[1] * pos[..., 1]
        return c_hm * (1.0 + drift)[:, None] / slowness_scale

    # receive epochs depend on the travel time: two fixed-point passes are exact to well below 1 us
    twtt = np.full((n, m), 2.0 * spec.depths_m[0] / 1500.0) + delays
    for _ in range(3):
        ant_rx, rph_rx = _platform(spec, t_tx_rel[:, None] + twtt)
        trans_rx = ant_rx + body_to_enu(rph_rx.reshape(-1, 3), lever).reshape(n, m, 3)
        path = np.linalg.norm(truth_enu - trans_tx[:, None, :], axis=-1) + np.linalg.norm(
            truth_enu - trans_rx, axis=-1
        )
        mid = 0.5 * (
            0.5 * (trans_tx[:, None, :] + trans_rx) + truth_enu
        )  # ray midpoint: gradient sampled there
        if spec.ray_traced:
            layered = LayeredProfile(depth_m=z, speed_mps=c, source="synthetic")
            twtt = _ray_legs_s(layered, trans_tx[:, None, :], trans_rx, truth_enu, spec.geoid_undulation_m)
            twtt = twtt * c_hm / speed(t_tx_rel, mid) + delays
        else:
            twtt = path / speed(t_tx_rel, mid) + delays
    measured = twtt + rng.normal(0.0, spec.sigma_twtt_s, twtt.shape)
    gross = rng.random(twtt.shape) < spec.gross_fraction
    measured = measured + np.where(gross, rng.choice([-1.0, 1.0], twtt.shape) * spec.gross_error_s, 0.0)
    missing = rng.random(twtt.shape) < spec.missing_fraction
    missing[missing.all(axis=1), 0] = False  # every interrogation keeps one reply
    measured = np.where(missing, np.nan, np.round(measured, 6))
    gross &= ~missing

    sig = np.asarray(spec.sigma_gnss_enu_m, dtype=float)
    cov_enu = np.diag(sig**2)
    noisy_tx = trans_tx + rng.normal(0.0, 1.0, trans_tx.shape) * sig
    noisy_rx = trans_rx + rng.normal(0.0, 1.0, trans_rx.shape) * sig
    cov_xyz = _enu_cov_to_ecef(cov_enu, origin)
    rows, tps = np.nonzero(~missing)
    t_tx = spec.start_j2000_s + t_tx_rel
    k = rows.size
    pings = ArrayPings(
        path="",
        ids=ids,
        transponder=tps.astype(np.int64),
        t_transmit_s=t_tx[rows],
        twtt_s=measured[rows, tps],
        transmit_xyz_m=_to_ecef(noisy_tx[rows], origin),
        receive_xyz_m=_to_ecef(noisy_rx[rows, tps], origin),
        transmit_cov_m2=np.broadcast_to(cov_xyz, (k, 3, 3)).copy(),
        receive_cov_m2=np.broadcast_to(cov_xyz, (k, 3, 3)).copy(),
        line=rows.astype(np.int64) + 1,
        qc=QcReport(),
    )
    offset = np.asarray(spec.apriori_offset_enu_m, dtype=float)
    return ArraySurveyTruth(
        origin=origin,
        ids=ids,
        transponders_enu_m=truth_enu,
        apriori_enu_m=truth_enu + offset,
        transponders_xyz_m=_to_ecef(truth_enu, origin),
        sound_speed_mps=c_hm,
        lever_arm_frd_m=lever,
        pings=pings,
        gross=gross[rows, tps],
        spec=spec,
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class GnatssSurveyFiles:
    """Paths of a written synthetic survey."""

    folder: Path
    config: Path
    pxp_tt: Path
    pos_freed_trans_twtt: Path
    level2_csv: Path
    sound_speed: Path
    gps_pos_freed: Path
    roll_pitch_heading: Path
    truth: Path
    antenna_csv: Path


EXAMPLE_SPEC = ArraySurveySpec(
    n_pings=200,
    ping_interval_s=36.0,
    track_period_s=7200.0,
    array_radius_m=600.0,
    track_radius_m=(20.0, 700.0),
    internal_delays_s=(0.2, 2.2, 4.2),
    distance_limit_m=1000.0,
    residual_limit_cm=60.0,
    seed=2026,
)
"""The packaged example (``oceanloc.data.gnatss_synthetic``): 200 interrogations (36 s apart, 2 h) of three
transponders 600 m from the centre, the platform looping out to 700 m and back (so each transponder is
seen from many angles). The internal delays are 2 s apart so that the replies never change order: GNATSS
pairs each interrogation's replies with its transponders by their order in time."""


def gnatss_config_dict(
    truth: ArraySurveyTruth, folder: Path, output: Path | None = None, relative: bool = False
) -> dict:
    """The GNATSS configuration of a synthetic survey (solver on the Level-2 CSV and the CTD profile);
    ``relative``: input paths relative to the configuration's folder (a packaged example)."""
    spec = truth.spec
    base = Path() if relative else folder
    lat, lon, h = pymap3d.enu2geodetic(
        truth.apriori_enu_m[:, 0], truth.apriori_enu_m[:, 1], truth.apriori_enu_m[:, 2],
        truth.origin.lat_deg, truth.origin.lon_deg, truth.origin.h_m,
    )  # fmt: skip
    return {
        "site_id": spec.site_id,
        "campaign": "synthetic",
        "array_center": {"lat": spec.center_lat_deg, "lon": spec.center_lon_deg, "alt": 0.0},
        "transponders": [
            {
                "lat": float(lat[k]),
                "lon": float(lon[k]),
                "height": float(h[k] - spec.geoid_undulation_m),
                "internal_delay": float(spec.internal_delays_s[k]),
                "pxp_id": truth.ids[k],
            }
            for k in range(len(truth.ids))
        ],
        "travel_times_variance": float(spec.sigma_twtt_s**2),
        "travel_times_correction": 0.0,
        "transducer_delay_time": 0.0,
        "posfilter": {
            "atd_offsets": dict(
                zip(("forward", "rightward", "downward"), map(float, spec.lever_arm_frd_m), strict=True)
            )
        },
        "solver": {
            "reference_ellipsoid": {"semi_major_axis": 6378137.0, "reverse_flattening": 298.257223563},
            "gps_sigma_limit": 0.05,
            "std_dev": True,
            "geoid_undulation": spec.geoid_undulation_m,
            "bisection_tolerance": 1e-10,
            "harmonic_mean_start_depth": 0.0,
            "distance_limit": spec.distance_limit_m,
            "residual_limit": spec.residual_limit_cm,
            "input_files": {
                "sound_speed": {"path": str(base / "ctd_profile.txt")},
                "gps_solution": {"path": str(base / "gps_solution.csv")},
            },
        },
        "output": {"path": str(output or base / "gnatss-output") + "/"},
    }


def write_gnatss_survey(
    spec: ArraySurveySpec, folder: str | Path, relative: bool = False
) -> tuple[ArraySurveyTruth, GnatssSurveyFiles]:
    """Simulate the survey and write it in GNATSS's formats into ``folder`` (created); ``relative``: the
    configuration names its inputs relative to its folder."""
    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    truth = simulate_array_survey(spec)
    pings = truth.pings
    n_tp = len(truth.ids)
    t_unique, first = np.unique(pings.t_transmit_s, return_index=True)
    table = np.full((t_unique.size, n_tp), np.nan)
    row = np.searchsorted(t_unique, pings.t_transmit_s)
    table[row, pings.transponder] = pings.twtt_s
    write_pxp_tt(out / "pxp_tt", t_unique, table)
    # one position per epoch: the interrogation, then each reply
    t_all = np.concatenate([t_unique, pings.t_receive_s])
    xyz_all = np.concatenate([pings.transmit_xyz_m[first], pings.receive_xyz_m])
    cov_all = np.concatenate([pings.transmit_cov_m2[first], pings.receive_cov_m2])
    order = np.argsort(t_all, kind="stable")
    write_pos_freed_trans_twtt(out / "POS_FREED_TRANS_TWTT", t_all[order], xyz_all[order], cov_all[order])
    write_level2_csv(out / "gps_solution.csv", pings)
    z, c = sound_speed_profile()
    write_sound_speed_profile(out / "ctd_profile.txt", z, c)
    # antenna positions and attitude at the same epochs (the transducer is at the lever arm below)
    t_rel = t_all[order] - spec.start_j2000_s
    _, rph = _platform(spec, t_rel)
    x, y, zz = (xyz_all[order, i] for i in range(3))
    e, nn, u = pymap3d.ecef2enu(x, y, zz, truth.origin.lat_deg, truth.origin.lon_deg, truth.origin.h_m)
    ant = np.stack([e, nn, u], axis=-1) - body_to_enu(rph, truth.lever_arm_frd_m)  # same GNSS noise
    sig_enu = np.asarray(spec.sigma_gnss_enu_m)
    sig_xyz = np.sqrt(
        np.diag(_enu_cov_to_ecef(np.diag(sig_enu**2), truth.origin))
    )  # the format's ECEF sigmas
    ant_xyz = np.round(_to_ecef(ant, truth.origin), 4)  # the digits GPS_POS_FREED carries
    sig_xyz = np.round(sig_xyz, 4)
    rph = np.round(np.column_stack([rph[:, 0], rph[:, 1], rph[:, 2] % 360.0]), 5)  # the RPH file's digits
    write_gps_pos_freed(out / "GPS_POS_FREED", t_all[order], ant_xyz, np.tile(sig_xyz, (t_rel.size, 1)))
    write_roll_pitch_heading(out / "RPH", t_all[order], rph)
    # the same track and attitude as one antenna CSV (UTC times, latitude/longitude/height, ECEF sigmas)
    cov_ant = np.broadcast_to(np.diag(sig_xyz**2), (t_rel.size, 3, 3))
    write_antenna_csv(
        out / "antenna.csv", t_all[order], ant_xyz, cov_ant, rph, time="iso", position="geodetic",
        covariance="sd_xyz",
    )  # fmt: skip
    write_gnatss_config(out / "config.yaml", gnatss_config_dict(truth, out, relative=relative))
    (out / "truth.json").write_text(json.dumps(truth.to_record(), indent=1), encoding="utf-8")
    files = GnatssSurveyFiles(
        folder=out, config=out / "config.yaml", pxp_tt=out / "pxp_tt",
        pos_freed_trans_twtt=out / "POS_FREED_TRANS_TWTT", level2_csv=out / "gps_solution.csv",
        sound_speed=out / "ctd_profile.txt", gps_pos_freed=out / "GPS_POS_FREED",
        roll_pitch_heading=out / "RPH", truth=out / "truth.json", antenna_csv=out / "antenna.csv",
    )  # fmt: skip
    return truth, files
