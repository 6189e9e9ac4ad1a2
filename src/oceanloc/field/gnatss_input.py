"""GNSS-A array surveys in GNATSS's formats: read them, solve them (oceanloc's way or GNATSS's), report.

:func:`load_gnatss_input` reads a GNATSS configuration YAML and the files it (or the caller) names:
``pxp_tt`` + ``POS_FREED_TRANS_TWTT``, or ``pxp_tt`` + GNSS antenna positions with attitude
(``GPS_POS_FREED`` + roll/pitch/heading, or an antenna CSV: :mod:`oceanloc.io.antenna_csv`) and the
configuration's lever arm (:func:`antenna_pings`), or the Level-2 CSV; the sound-speed profile; a
deletion file.
:func:`localize_gnatss_input` solves the array with

- ``method="oceanloc"`` (default): :func:`~oceanloc.estimation.gnssa_array.localize_gnssa_array` with
  oceanloc's defaults (ray-traced travel times through the profile, sound-speed scale in time and
  horizontal gradient estimated, noise estimated, the automatic outlier loop), independent positions or
  the common shift of the configuration's a-priori geometry;
- ``method="gnatss"``: GNATSS's own estimate (:func:`~oceanloc.estimation.gnatss_compat.gnatss_solve`:
  fixed harmonic-mean speeds, its weights, common shift, its residual limits).

Both give a :class:`GnatssLocalization`: positions in ENU about the array centre and as latitude,
longitude and height, their covariance, the iterations, and per reply the residual, whether it was
excluded and why. It writes the per-ping CSVs in GNATSS's columns (:meth:`write_csvs`), a NetCDF
dataset (:meth:`to_dataset`) and the JSON record (:meth:`to_record`, with its ``pings`` key).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pymap3d

from oceanloc._typing import BoolArray, FloatArray
from oceanloc.errors import ConfigError, DataError
from oceanloc.estimation.gnatss_compat import GnatssSettings, GnatssSolution, apriori_xyz_m, gnatss_solve
from oceanloc.estimation.gnssa_array import ArrayGeometry, GnssaArrayOptions, localize_gnssa_array
from oceanloc.geo.ecef import ecef_to_enu_m, enu_rotation
from oceanloc.geo.enu import EnuOrigin, enu_to_geodetic
from oceanloc.io.antenna_csv import AntennaCsv, is_antenna_csv, read_antenna_csv
from oceanloc.io.gnatss import (
    J2000_UNIX_S,
    RESIDUAL_SPEED_MPS,
    AntennaPositions,
    ArrayPings,
    Attitude,
    EpochResiduals,
    GnatssConfig,
    PxpTravelTimes,
    SoundSpeedProfile,
    in_windows,
    j2000_iso,
    join_pxp_positions,
    read_deletions,
    read_gnatss_config,
    read_gps_pos_freed,
    read_level2_csv,
    read_pos_freed_trans_twtt,
    read_pxp_tt,
    read_roll_pitch_heading,
    read_sound_speed_profile,
    write_deletions_csv,
    write_epoch_residuals,
)
from oceanloc.io.gnssa_array import array_survey_from_transducers
from oceanloc.models.attitude import interpolate_track, rotation_enu_from_body, transducer_enu_m
from oceanloc.models.sound_profile import SoundSpeedProfile as ModelProfile

METHODS: tuple[str, ...] = ("oceanloc", "gnatss")
SOLUTIONS: tuple[str, ...] = ("independent", "common_shift")


@dataclass(frozen=True, slots=True, kw_only=True)
class AntennaReplies:
    """Per reply of an :class:`~oceanloc.io.gnatss.ArrayPings` built from an antenna track: the GNSS
    antenna's position (ENU about the array centre) and covariance, and the body-to-ENU rotation, at
    transmit and at receive, with the body-frame lever arm and its covariance. The estimator places the
    transducer at ``x_A + R l`` itself, so it can carry the lever arm as an unknown with a prior
    (:mod:`oceanloc.estimation.gnssa_array`).

    Attributes
    ----------
    transmit_enu_m, receive_enu_m : (n, 3) float
    transmit_cov_m2, receive_cov_m2 : (n, 3, 3) float
        ENU covariance of the antenna position, m^2.
    transmit_rotation, receive_rotation : (n, 3, 3) float
    lever_arm_frd_m : (3,) float
        Forward, rightward, downward, metres.
    lever_arm_cov_m2 : (3, 3) float
        Its covariance (zeros: known exactly).
    """

    transmit_enu_m: FloatArray
    transmit_cov_m2: FloatArray
    transmit_rotation: FloatArray
    receive_enu_m: FloatArray
    receive_cov_m2: FloatArray
    receive_rotation: FloatArray
    lever_arm_frd_m: FloatArray
    lever_arm_cov_m2: FloatArray

    def select(self, keep: BoolArray) -> AntennaReplies:
        """The replies where ``keep`` is True."""
        return AntennaReplies(
            transmit_enu_m=self.transmit_enu_m[keep], transmit_cov_m2=self.transmit_cov_m2[keep],
            transmit_rotation=self.transmit_rotation[keep], receive_enu_m=self.receive_enu_m[keep],
            receive_cov_m2=self.receive_cov_m2[keep], receive_rotation=self.receive_rotation[keep],
            lever_arm_frd_m=self.lever_arm_frd_m, lever_arm_cov_m2=self.lever_arm_cov_m2,
        )  # fmt: skip


@dataclass(frozen=True, slots=True, kw_only=True)
class GnatssInput:
    """A GNATSS-format survey, read: configuration, replies, profile, deletions, per-transponder speeds;
    ``antenna`` when the replies came from an antenna track with attitude (else None)."""

    config: GnatssConfig
    pings: ArrayPings
    profile: SoundSpeedProfile | None
    deletions: FloatArray
    sound_speed_mps: FloatArray
    inputs: tuple[str, ...]
    antenna: AntennaReplies | None = None


def lever_arm_covariance(sigma_m: float | Sequence[float] | None) -> FloatArray:
    """The lever arm's covariance from one 1-sigma for every component or three (forward, rightward,
    downward), metres: ``diag(sigma^2)``; zeros for None.

    Raises
    ------
    ConfigError
        A sigma that is negative, not finite, or not one or three values.
    """
    if sigma_m is None:
        return np.zeros((3, 3))
    sig = np.atleast_1d(np.asarray(sigma_m, dtype=float))
    if sig.size not in (1, 3) or not np.all(np.isfinite(sig)) or np.any(sig < 0.0) or np.any(sig > 10.0):
        raise ConfigError(
            f"--lever-arm-sigma must be one or three (forward, rightward, downward) values in [0, 10] m, "
            f"got {sig.tolist()}"
        )
    return np.diag(np.broadcast_to(sig, (3,)) ** 2)


def antenna_pings(
    travel: PxpTravelTimes,
    antenna: AntennaPositions | AntennaCsv,
    attitude: Attitude | None,
    ids: tuple[str, ...],
    lever_arm_frd_m: FloatArray,
    origin: EnuOrigin,
    lever_arm_cov_m2: FloatArray | None = None,
) -> tuple[ArrayPings, AntennaReplies]:
    """Per-reply transducer positions from GNSS antenna positions, attitude and the body-frame lever arm,
    and the antenna samples they came from.

    What GNATSS's posfilter does, without its Kalman filter: the antenna track (``GPS_POS_FREED``:
    Earth-fixed positions and sigmas; or an antenna CSV, :mod:`oceanloc.io.antenna_csv`: full
    covariances, and the attitude in the same rows unless ``attitude`` is given) and the roll, pitch,
    heading are interpolated linearly to each interrogation and each reply epoch (``time + travel
    time``; :func:`~oceanloc.models.attitude.interpolate_track`), and the transducer is placed at
    ``x_A + R(roll, pitch, heading) l`` (:func:`~oceanloc.models.attitude.transducer_enu_m`, body frame
    forward-starboard-down as GNATSS's ``atd_offsets``). The antenna covariance is carried over to the
    transducer; the lever arm's covariance is not added per reply (its error is common to every ping)
    but handed to the estimator as the lever arm's prior (:class:`AntennaReplies`). Replies whose
    epochs lie outside either record are recorded in the travel-time file's QC and skipped.

    Raises
    ------
    ConfigError
        No attitude (neither ``attitude`` nor attitude columns in the antenna CSV), or both.
    DataError
        No reply within the records.
    """
    if isinstance(antenna, AntennaCsv):
        if (antenna.rph_deg is None) == (attitude is None):
            raise ConfigError(
                f"{antenna.path}: roll, pitch, heading come either from the antenna CSV's roll_deg, "
                "pitch_deg, heading_deg columns or from --attitude, exactly one of them"
            )
        ant_t, ant_xyz, ant_cov_xyz = antenna.t_s, antenna.xyz_m, antenna.cov_xyz_m2
        att_t, att_deg = (attitude.t_s, attitude.rph_deg) if attitude else (antenna.t_s, antenna.rph_deg)
        att_path = attitude.path if attitude else antenna.path
    else:
        if attitude is None:
            raise ConfigError(f"{antenna.path}: GPS_POS_FREED antenna positions need --attitude")
        ant_t, ant_xyz = antenna.t_s, antenna.xyz_m
        ant_cov_xyz = np.einsum("ki,ij->kij", antenna.sigma_xyz_m**2, np.eye(3))
        att_t, att_deg, att_path = attitude.t_s, attitude.rph_deg, attitude.path
    rot = enu_rotation(origin)
    ant_enu = ecef_to_enu_m(ant_xyz, origin)
    ant_cov = rot @ ant_cov_xyz @ rot.T
    t_tx = travel.t_transmit_s
    t_rx = t_tx[:, None] + np.nan_to_num(travel.twtt_s)
    lo, hi = max(ant_t[0], att_t[0]), min(ant_t[-1], att_t[-1])
    tx_ok = (t_tx >= lo) & (t_tx <= hi)
    ok = np.isfinite(travel.twtt_s) & tx_ok[:, None] & (t_rx >= lo) & (t_rx <= hi)
    for i in np.flatnonzero(~tx_ok):
        travel.qc.add(
            travel.path,
            int(travel.line[i]),
            "invalid fix",
            f"interrogation {t_tx[i]:.3f} s outside the antenna or attitude record",
        )
    rows, tps = np.nonzero(ok)
    if rows.size == 0:
        where = antenna.path if att_path == antenna.path else f"{antenna.path}) and attitude ({att_path}"
        raise DataError(f"{travel.path}: no reply lies within the antenna ({where}) records")
    lever = np.asarray(lever_arm_frd_m, dtype=float)

    def sample(t: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        pos, cov, _ = interpolate_track(ant_t, t, ant_enu, ant_cov, np.zeros((ant_t.size, 3)))
        _, _, att = interpolate_track(
            att_t, t, np.zeros((att_t.size, 3)), np.zeros((att_t.size, 3, 3)), att_deg
        )
        r = rotation_enu_from_body(att[:, 0], att[:, 1], att[:, 2])
        enu = transducer_enu_m(pos, r, lever)
        x, y, z = pymap3d.enu2ecef(
            enu[:, 0], enu[:, 1], enu[:, 2], origin.lat_deg, origin.lon_deg, origin.h_m
        )
        return pos, cov, r, np.stack([x, y, z], axis=-1)

    a_tx, c_tx, r_tx, tx_xyz = sample(t_tx[rows])
    a_rx, c_rx, r_rx, rx_xyz = sample(t_rx[rows, tps])
    travel.qc.records_kept = int(np.unique(rows).size)
    pings = ArrayPings(
        path=travel.path, ids=ids, transponder=tps.astype(np.int64), t_transmit_s=t_tx[rows],
        twtt_s=travel.twtt_s[rows, tps], transmit_xyz_m=tx_xyz, receive_xyz_m=rx_xyz,
        transmit_cov_m2=rot.T @ c_tx @ rot, receive_cov_m2=rot.T @ c_rx @ rot, line=travel.line[rows],
        qc=travel.qc,
    )  # fmt: skip
    replies = AntennaReplies(
        transmit_enu_m=a_tx, transmit_cov_m2=c_tx, transmit_rotation=r_tx, receive_enu_m=a_rx,
        receive_cov_m2=c_rx, receive_rotation=r_rx, lever_arm_frd_m=lever,
        lever_arm_cov_m2=np.zeros((3, 3)) if lever_arm_cov_m2 is None else np.asarray(lever_arm_cov_m2),
    )  # fmt: skip
    return pings, replies


def load_gnatss_input(
    config_path: str | Path,
    *,
    pxp_tt: str | Path | None = None,
    positions: str | Path | None = None,
    level2: str | Path | None = None,
    ssp: str | Path | None = None,
    deletions: str | Path | None = None,
    antenna: str | Path | None = None,
    attitude: str | Path | None = None,
    lever_arm_sigma_m: float | Sequence[float] | None = None,
) -> GnatssInput:
    """Read a GNATSS survey; paths given here override the configuration's ``solver.input_files``.

    Replies come from ``pxp_tt`` + ``positions`` (``POS_FREED_TRANS_TWTT``) if both are given; from
    ``pxp_tt`` + ``antenna`` with the configuration's ``posfilter.atd_offsets`` lever arm
    (:func:`antenna_pings`), the antenna being a ``GPS_POS_FREED`` file with an ``attitude`` (roll,
    pitch, heading) file or an antenna CSV (:mod:`oceanloc.io.antenna_csv`, recognised by its header)
    that carries the attitude itself; else from ``level2`` (or the configuration's ``gps_solution``).
    ``lever_arm_sigma_m`` (one or three 1-sigmas, forward, rightward, downward, metres) is the lever
    arm's uncertainty, the estimator's prior on it (antenna input only). Each transponder's speed is the
    profile's harmonic mean from ``harmonic_mean_start_depth`` to its a-priori depth, rounded to 1 mm/s
    as GNATSS does (or the configuration's ``sv_mean`` when there is no profile).

    Raises
    ------
    ConfigError
        If no reply source or no sound speed is given, or the inputs do not go together.
    DataError
        From the readers (bad files).
    """
    config = read_gnatss_config(config_path)
    ins = config.inputs
    antenna_is_csv = antenna is not None and is_antenna_csv(antenna)
    if (antenna is None and attitude is not None) or (
        antenna is not None and not antenna_is_csv and attitude is None
    ):
        raise ConfigError(
            "--antenna and --attitude go together (GNSS antenna positions and roll, pitch, heading), "
            "unless --antenna is an antenna CSV with roll_deg, pitch_deg, heading_deg columns"
        )
    if antenna is not None and (pxp_tt is None or positions is not None):
        raise ConfigError("--antenna and --attitude need --pxp-tt (and no --positions)")
    if (pxp_tt is None) != (positions is None) and antenna is None:
        raise ConfigError("--pxp-tt and --positions go together (travel times and transducer positions)")
    if lever_arm_sigma_m is not None and antenna is None:
        raise ConfigError(
            "--lever-arm-sigma needs --antenna: the lever arm applies to antenna positions, not to "
            "transducer positions (--positions, --level2)"
        )
    lever_cov = lever_arm_covariance(lever_arm_sigma_m)
    used: list[str] = [str(config_path)]
    replies: AntennaReplies | None = None
    if antenna is not None and pxp_tt is not None:
        if config.atd_offsets_frd_m is None:
            raise ConfigError(
                f"{config_path}: --antenna needs the lever arm posfilter.atd_offsets (forward, rightward, "
                "downward)"
            )
        travel = read_pxp_tt(pxp_tt, len(config.ids))
        track = read_antenna_csv(antenna) if antenna_is_csv else read_gps_pos_freed(antenna)
        att = read_roll_pitch_heading(attitude) if attitude is not None else None
        for extra in (track.qc, *((att.qc,) if att else ())):
            travel.qc.issues.extend(extra.issues)
            travel.qc.lines_read += extra.lines_read
        pings, replies = antenna_pings(
            travel, track, att, config.ids, np.asarray(config.atd_offsets_frd_m), config.array_center,
            lever_cov,
        )  # fmt: skip
        used += [str(pxp_tt), str(antenna), *((str(attitude),) if attitude is not None else ())]
    elif pxp_tt is not None and positions is not None:
        pings = join_pxp_positions(
            read_pxp_tt(pxp_tt, len(config.ids)), read_pos_freed_trans_twtt(positions), config.ids
        )
        used += [str(pxp_tt), str(positions)]
    else:
        l2 = level2 or ins.get("gps_solution")
        if l2 is None:
            raise ConfigError(
                f"{config_path}: no replies: give --pxp-tt and --positions, or --level2 "
                "(or solver.input_files.gps_solution in the configuration)"
            )
        pings = read_level2_csv(l2, config.ids)
        used.append(str(l2))
    ssp_path = ssp or ins.get("sound_speed")
    profile = read_sound_speed_profile(ssp_path) if ssp_path else None
    if profile is not None:
        used.append(str(ssp_path))
        start = config.harmonic_mean_start_depth_m
        speeds = np.round([profile.harmonic_mean_mps(start, t.height_m) for t in config.transponders], 3)
    elif all(t.sv_mean_mps is not None for t in config.transponders):
        speeds = np.array([t.sv_mean_mps for t in config.transponders], dtype=float)
    else:
        raise ConfigError(f"{config_path}: no sound speed: give --ssp (or sv_mean for every transponder)")
    del_path = deletions or ins.get("deletions")
    windows = read_deletions(del_path) if del_path else np.zeros((0, 2))
    if del_path:
        used.append(str(del_path))
    return GnatssInput(
        config=config,
        pings=pings,
        profile=profile,
        deletions=windows,
        sound_speed_mps=speeds,
        inputs=tuple(used),
        antenna=replies,
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class GnatssLocalization:
    """An array's position from a GNATSS-format survey, by either method.

    Attributes
    ----------
    method, solution : str
    ids : tuple of str
    origin : EnuOrigin
        The array centre: the ENU origin.
    positions_enu_m : (m, 3) float
    covariance_enu_m2 : (m, 3, 3) float
        Each transponder's position covariance (for the common shift: the shift's, shared).
    positions_geodetic : (m, 3) float
        Latitude (deg), longitude (deg), ellipsoidal height (m).
    apriori_enu_m : (m, 3) float
    iterations : tuple of dict
        Per iteration (GNATSS) or outlier round (oceanloc): what changed, as plain data.
    converged : bool
    sound_speed_mps : (m,) float
        Speed used per transponder (GNATSS's fixed ones, or oceanloc's reference times its estimated
        mean scale).
    t_s : (n,) float
        Every reply's interrogation time, J2000 s.
    transponder : (n,) int
    residual_m : (n,) float
        Two-way path residual at the solution, metres.
    excluded : (n,) bool
    reason : tuple of str
        Why each excluded reply was excluded ("" when used).
    deletions : (d, 2) float
        The deletion windows applied, J2000 s.
    extra : dict
        Method-specific plain data (oceanloc: the estimator's record; GNATSS: its outlier epochs).
    inputs : tuple of str
    """

    method: str
    solution: str
    ids: tuple[str, ...]
    origin: EnuOrigin
    positions_enu_m: FloatArray
    covariance_enu_m2: FloatArray
    positions_geodetic: FloatArray
    apriori_enu_m: FloatArray
    iterations: tuple[dict, ...]
    converged: bool
    sound_speed_mps: FloatArray
    t_s: FloatArray
    transponder: np.ndarray
    residual_m: FloatArray
    excluded: BoolArray
    reason: tuple[str, ...]
    deletions: FloatArray
    extra: dict
    inputs: tuple[str, ...]

    @property
    def sigma_enu_m(self) -> FloatArray:
        return np.sqrt(np.maximum(np.diagonal(self.covariance_enu_m2, axis1=1, axis2=2), 0.0))

    @property
    def centre_enu_m(self) -> FloatArray:
        return self.positions_enu_m.mean(axis=0)

    def pings_record(self) -> dict[str, list]:
        """Per reply: ``t_s``, ``transponder`` (id), ``residual_m``, ``excluded``, ``reason``."""
        return {
            "t_s": [float(v) for v in self.t_s],
            "transponder": [self.ids[int(k)] for k in self.transponder],
            "residual_m": [float(v) for v in self.residual_m],
            "excluded": [bool(v) for v in self.excluded],
            "reason": list(self.reason),
        }

    def to_record(self) -> dict[str, Any]:
        """Plain JSON-ready data: transponders (ENU about the array centre and geodetic), the centre, the
        iterations, and ``pings``."""
        sig = self.sigma_enu_m
        tps = []
        for k, tid in enumerate(self.ids):
            e, n, u = (float(v) for v in self.positions_enu_m[k])
            lat, lon, h = (float(v) for v in self.positions_geodetic[k])
            tps.append(
                {
                    "id": tid,
                    "e_m": e,
                    "n_m": n,
                    "u_m": u,
                    "sigma_e_m": float(sig[k, 0]),
                    "sigma_n_m": float(sig[k, 1]),
                    "sigma_u_m": float(sig[k, 2]),
                    "lat_deg": lat,
                    "lon_deg": lon,
                    "h_m": h,
                    "sound_speed_mps": float(self.sound_speed_mps[k]),
                    "replies_used": int(np.sum(~self.excluded & (self.transponder == k))),
                }
            )
        c = self.centre_enu_m
        c_geo = enu_to_geodetic(c, self.origin)
        return {
            "method": self.method,
            "solution": self.solution,
            "origin": {
                "lat_deg": self.origin.lat_deg,
                "lon_deg": self.origin.lon_deg,
                "h_m": self.origin.h_m,
            },
            "transponders": tps,
            "centre": {
                "e_m": float(c[0]),
                "n_m": float(c[1]),
                "u_m": float(c[2]),
                "lat_deg": float(c_geo[0]),
                "lon_deg": float(c_geo[1]),
                "h_m": float(c_geo[2]),
            },
            "replies": int(self.t_s.size),
            "replies_excluded": int(self.excluded.sum()),
            "converged": bool(self.converged),
            "iterations": list(self.iterations),
            "deletions": self.deletions.tolist(),
            "pings": self.pings_record(),
            "details": self.extra,
        }

    def to_dataset(self) -> Any:
        """The solution, covariance and iterations as an :class:`xarray.Dataset` (units on each variable)."""
        import xarray as xr

        n_it = len(self.iterations)
        keys = sorted({k for it in self.iterations for k, v in it.items() if isinstance(v, int | float)})
        it_vars = {
            f"iteration_{k}": (
                ("iteration",),
                [float(it.get(k, np.nan)) for it in self.iterations],
                _attrs(_unit_of(k), k.replace("_", " ")),
            )
            for k in keys
        }
        tp, ax, rp = ("transponder",), ("transponder", "axis"), ("reply",)
        geo = self.positions_geodetic
        data_vars = {
            "position_enu": (
                ax,
                self.positions_enu_m,
                _attrs("m", "transponder east, north, up about the centre"),
            ),
            "covariance_enu": (
                ("transponder", "axis", "axis2"),
                self.covariance_enu_m2,
                _attrs("m2", "transponder position covariance (ENU)"),
            ),
            "latitude": (tp, geo[:, 0], _attrs("degrees_north", "latitude")),
            "longitude": (tp, geo[:, 1], _attrs("degrees_east", "longitude")),
            "height": (tp, geo[:, 2], _attrs("m", "ellipsoidal height")),
            "apriori_enu": (ax, self.apriori_enu_m, _attrs("m", "a-priori position (ENU)")),
            "sound_speed": (tp, self.sound_speed_mps, _attrs("m s-1", "sound speed used")),
            "reply_time": (rp, self.t_s, _attrs("s", "interrogation time, J2000 seconds")),
            "reply_transponder": (rp, self.transponder.astype(np.int32), _attrs("1", "transponder index")),
            "reply_residual": (rp, self.residual_m, _attrs("m", "two-way path residual")),
            "reply_excluded": (rp, self.excluded.astype(np.int8), _attrs("1", "excluded (1) or used (0)")),
            **it_vars,
        }
        return xr.Dataset(
            data_vars=data_vars,
            coords={
                "transponder": ("transponder", list(self.ids)),
                "axis": ("axis", ["e", "n", "u"]),
                "axis2": ("axis2", ["e", "n", "u"]),
                "iteration": (
                    "iteration",
                    np.arange(1, n_it + 1),
                    _attrs("1", "iteration (or outlier round)"),
                ),
            },
            attrs={
                "title": f"GNSS-A array solution ({self.method}, {self.solution})",
                "origin_lat_deg": self.origin.lat_deg,
                "origin_lon_deg": self.origin.lon_deg,
                "origin_h_m": self.origin.h_m,
                "converged": int(self.converged),
            },
        )

    def epoch_residuals(self) -> EpochResiduals:
        """Residuals per interrogation in GNATSS's ``residuals.csv`` shape: one-way cm at 1500 m/s."""
        times, inv = np.unique(self.t_s, return_inverse=True)
        table = np.full((times.size, len(self.ids)), np.nan)
        c0 = self.sound_speed_mps[self.transponder]
        table[inv, self.transponder] = 100.0 * RESIDUAL_SPEED_MPS * (self.residual_m / c0) / 2.0
        return EpochResiduals(t_s=times, ids=self.ids, residual_cm=table)

    def write_csvs(self, folder: str | Path) -> list[Path]:
        """Write ``residuals.csv`` (every interrogation), ``outliers.csv`` (excluded replies with the reason
        for each: ``time, iso_string, transponder, residual_cm, reason``) and ``deletions.csv`` (the
        deletion windows plus each excluded interrogation, GNATSS's ``starttime, endtime``)."""
        import csv

        out = Path(folder)
        out.mkdir(parents=True, exist_ok=True)
        paths = [write_epoch_residuals(out / "residuals.csv", self.epoch_residuals())]
        c0 = self.sound_speed_mps[self.transponder]
        cm = 100.0 * RESIDUAL_SPEED_MPS * (self.residual_m / c0) / 2.0
        with (out / "outliers.csv").open("w", encoding="utf-8", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["time", "iso_string", "transponder", "residual_cm", "reason"])
            for i in np.flatnonzero(self.excluded):
                w.writerow(
                    [
                        f"{self.t_s[i]:.6f}",
                        j2000_iso(self.t_s[i]),
                        self.ids[int(self.transponder[i])],
                        f"{cm[i]:.4f}",
                        self.reason[i],
                    ]
                )
        paths.append(out / "outliers.csv")
        gone = np.unique(self.t_s[self.excluded])
        windows = np.concatenate([self.deletions.reshape(-1, 2), np.column_stack([gone, gone])])
        paths.append(write_deletions_csv(out / "deletions.csv", windows))
        return paths


def _attrs(units: str, long_name: str) -> dict[str, str]:
    return {"units": units, "long_name": long_name}


def _unit_of(key: str) -> str:
    for suffix, unit in (("_cm", "cm"), ("_m", "m"), ("_s", "s"), ("_mps", "m s-1")):
        if key.endswith(suffix):
            return unit
    return "1"


def localize_gnatss_input(
    data: GnatssInput,
    *,
    method: str = "oceanloc",
    solution: str = "independent",
    options: GnssaArrayOptions | None = None,
    settings: GnatssSettings | None = None,
) -> GnatssLocalization:
    """Solve a GNATSS-format survey (see the module docstring).

    Raises
    ------
    ConfigError
        An unknown method or solution.
    DataError
        From the estimators (a survey that cannot be solved reliably).
    """
    if method not in METHODS:
        raise ConfigError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    if solution not in SOLUTIONS:
        raise ConfigError(f"solution must be one of {', '.join(SOLUTIONS)}, got {solution!r}")
    cfg = data.config
    origin = cfg.array_center
    apriori_enu = ecef_to_enu_m(apriori_xyz_m(cfg), origin)
    p = data.pings
    ant = data.antenna
    opts = options or GnssaArrayOptions(solution=solution)
    if method == "gnatss":
        if ant is not None and np.any(ant.lever_arm_cov_m2 != 0.0):
            raise ConfigError(
                "a lever-arm sigma is used by --method oceanloc only (GNATSS fixes the lever arm)"
            )
        sol = gnatss_solve(p, cfg, data.sound_speed_mps, settings, data.deletions)
        return _from_gnatss(sol, data, apriori_enu)
    if opts.estimate_lever_arm and ant is None:
        raise ConfigError(
            "--estimate-lever-arm needs --antenna (antenna positions with attitude): transducer positions "
            "(--positions, --level2) have no lever arm to calibrate"
        )
    deleted = in_windows(p.t_transmit_s, data.deletions)
    keep = ~deleted
    pk = p.select(keep)
    rot = enu_rotation(origin)
    t_unique, first, ping = np.unique(pk.t_transmit_s, return_index=True, return_inverse=True)
    common = {
        "name": Path(p.path).name, "t_transmit_s": t_unique, "reply_ping": ping,
        "reply_transponder": pk.transponder, "twtt_s": pk.twtt_s,
        "turnaround_s": np.array([t.internal_delay_s for t in cfg.transponders]), "transponder_ids": cfg.ids,
        "origin": origin, "approx_positions_enu_m": apriori_enu, "line": pk.line, "path": p.path, "qc": p.qc,
        "time_origin_unix_s": J2000_UNIX_S,  # GNATSS's times are J2000 seconds: the record's epoch_utc
    }  # fmt: skip
    if ant is None:
        survey = array_survey_from_transducers(
            transmit_enu_m=ecef_to_enu_m(pk.transmit_xyz_m[first], origin),
            transmit_cov_m2=rot @ pk.transmit_cov_m2[first] @ rot.T,
            receive_enu_m=ecef_to_enu_m(pk.receive_xyz_m, origin),
            receive_cov_m2=rot @ pk.receive_cov_m2 @ rot.T,
            **common,
        )
    else:
        ak = ant.select(keep)
        survey = array_survey_from_transducers(
            transmit_enu_m=ak.transmit_enu_m[first], transmit_cov_m2=ak.transmit_cov_m2[first],
            transmit_rotation=ak.transmit_rotation[first], receive_enu_m=ak.receive_enu_m,
            receive_cov_m2=ak.receive_cov_m2, receive_rotation=ak.receive_rotation,
            lever_arm_body_m=ak.lever_arm_frd_m, lever_arm_cov_m2=ak.lever_arm_cov_m2, **common,
        )  # fmt: skip
    if opts.surface_height_m is None:  # GNATSS's depth zero: the geoid (depth = -orthometric height)
        opts = dataclasses.replace(opts, surface_height_m=cfg.geoid_undulation_m - origin.h_m)
    profile = (
        None
        if data.profile is None
        else ModelProfile(
            depth_m=data.profile.depth_m, speed_mps=data.profile.speed_mps, source=data.profile.path
        )
    )
    geometry = ArrayGeometry(positions_enu_m=apriori_enu) if opts.solution == "common_shift" else None
    res = localize_gnssa_array(survey, opts, profile=profile, geometry=geometry)
    m = len(cfg.ids)
    cov = np.stack([res.position_covariance_m2(k) for k in range(m)])
    geo = np.stack([enu_to_geodetic(res.positions_enu_m[k], origin) for k in range(m)])
    residual = np.full(p.n_replies, np.nan)
    residual[keep] = res.residual_m
    excluded = np.ones(p.n_replies, dtype=bool)
    excluded[np.flatnonzero(keep)] = ~res.used
    reasons = np.full(p.n_replies, "", dtype=object)
    reasons[deleted] = "deleted (deletion file)"
    kept_idx = np.flatnonzero(keep)
    for x in res.exclusions:
        reasons[kept_idx[x.reply]] = x.reason
    reasons[excluded & (reasons == "")] = "excluded"
    scale = 1.0 + res.speed_correction_ppm * 1e-6
    record = res.to_record()
    record.pop("exclusions", None)
    if p.qc.issues:
        record["qc"] = p.qc.summary(max_lines=10)  # the lines the readers skipped, printed by the CLI
    return GnatssLocalization(
        method="oceanloc",
        solution=res.solution,
        ids=cfg.ids,
        origin=origin,
        positions_enu_m=res.positions_enu_m,
        covariance_enu_m2=cov,
        positions_geodetic=geo,
        apriori_enu_m=apriori_enu,
        iterations=tuple(it.to_record() for it in res.iterations),
        converged=res.converged,
        sound_speed_mps=np.full(m, res.reference_speed_mps * scale),
        t_s=p.t_transmit_s,
        transponder=p.transponder,
        residual_m=residual,
        excluded=excluded,
        reason=tuple(str(r) for r in reasons),
        deletions=data.deletions,
        extra=record,
        inputs=data.inputs,
    )


def _from_gnatss(sol: GnatssSolution, data: GnatssInput, apriori_enu: FloatArray) -> GnatssLocalization:
    origin = data.config.array_center
    m = len(sol.ids)
    rot = enu_rotation(origin)
    cov = np.broadcast_to(rot @ sol.covariance_xyz_m2 @ rot.T, (m, 3, 3)).copy()
    pos = ecef_to_enu_m(sol.position_xyz_m, origin)
    geo = np.stack([enu_to_geodetic(pos[k], origin) for k in range(m)])
    p = data.pings
    c = sol.sound_speed_mps[p.transponder]
    reasons = list(sol.reply_reason)
    its = tuple(
        {
            "rms_residual_cm": it.rms_residual_cm,
            "error_factor": it.error_factor,
            "shift_x_m": float(it.shift_xyz_m[0]),
            "shift_y_m": float(it.shift_xyz_m[1]),
            "shift_z_m": float(it.shift_xyz_m[2]),
        }
        for it in sol.iterations
    )
    return GnatssLocalization(
        method="gnatss",
        solution="common_shift",
        ids=sol.ids,
        origin=origin,
        positions_enu_m=pos,
        covariance_enu_m2=cov,
        positions_geodetic=geo,
        apriori_enu_m=apriori_enu,
        iterations=its,
        converged=sol.converged,
        sound_speed_mps=sol.sound_speed_mps,
        t_s=p.t_transmit_s,
        transponder=p.transponder,
        residual_m=sol.residual_s * c,
        excluded=~sol.reply_used,
        reason=tuple(reasons),
        deletions=sol.deleted_windows,
        extra={
            "outlier_t_s": sol.outlier_t_s.tolist(),
            "position_xyz_m": sol.position_xyz_m.tolist(),
            **({"qc": p.qc.summary(max_lines=10)} if p.qc.issues else {}),
        },
        inputs=data.inputs,
    )


def gnatss_example_config() -> Path:
    """The packaged synthetic GNATSS-format survey's configuration (``oceanloc.data.gnatss_synthetic``)."""
    from importlib import resources

    return Path(str(resources.files("oceanloc.data.gnatss_synthetic") / "config.yaml"))


def process_gnatss_survey(
    config_path: str | Path | None,
    *,
    pxp_tt: str | Path | None = None,
    positions: str | Path | None = None,
    level2: str | Path | None = None,
    ssp: str | Path | None = None,
    deletions: str | Path | None = None,
    antenna: str | Path | None = None,
    attitude: str | Path | None = None,
    method: str = "oceanloc",
    solution: str = "independent",
    lever_arm_sigma_m: float | Sequence[float] | None = None,
    estimate_lever_arm: bool = False,
) -> GnatssLocalization:
    """Read and solve a GNATSS-format survey (the packaged example when ``config_path`` is None): the one
    call behind ``oceanloc localize gnssa --format gnatss``. ``lever_arm_sigma_m``: the lever arm's
    1-sigma (its prior in the estimator); ``estimate_lever_arm``: calibrate it (prior 1 m per component
    unless a sigma is given); both need antenna input and ``method="oceanloc"``."""
    if method not in METHODS:
        raise ConfigError(f"--method must be one of {', '.join(METHODS)}, got {method!r}")
    if solution not in SOLUTIONS:
        raise ConfigError(f"--solution must be one of {', '.join(SOLUTIONS)}, got {solution!r}")
    if method == "gnatss" and (estimate_lever_arm or lever_arm_sigma_m is not None):
        raise ConfigError(
            "--estimate-lever-arm and --lever-arm-sigma need --method oceanloc (GNATSS fixes the lever arm)"
        )
    data = load_gnatss_input(
        config_path or gnatss_example_config(),
        pxp_tt=pxp_tt, positions=positions, level2=level2, ssp=ssp, deletions=deletions, antenna=antenna,
        attitude=attitude, lever_arm_sigma_m=lever_arm_sigma_m,
    )  # fmt: skip
    opts = GnssaArrayOptions(solution=solution, estimate_lever_arm=estimate_lever_arm)
    return localize_gnatss_input(data, method=method, solution=solution, options=opts)
