"""GNSS-Acoustic array surveys: pings from a surface platform to any number of seafloor transponders.

:class:`GnssaArraySurvey` is the one input type of
:func:`oceanloc.estimation.gnssa_array.localize_gnssa_array`. It is laid out "long": ``n`` pings (one
transmit each) and ``m`` replies (observations), each reply naming its ping and its transponder, so a
ping may be answered by some, all or none of the transponders.

Positions are kept as the GNSS antenna's (ENU about :attr:`~GnssaArraySurvey.origin`, with full 3x3
covariances), the body-to-ENU rotation at that instant (:mod:`oceanloc.models.attitude`) and one body-frame
lever arm with its covariance; the transducer positions are ``x_A + R l``. A survey whose file already
gives transducer positions (GNATSS's ``POS_FREED_TRANS_TWTT``, the La Jolla format) has identity rotations
and a zero lever arm known exactly.

Builders:

- :func:`array_survey_from_transducers`: transducer positions at transmit and at each reply's receive;
- :func:`array_survey_from_track`: a GNSS antenna track with attitude (:class:`AntennaTrack`),
  interpolated to the transmit times and to each reply's receive time ``t_transmit + TWTT``;
- :func:`array_survey_from_gnssa`: a La Jolla single-transponder survey
  (:class:`~oceanloc.io.gnssa.GnssaSurvey`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from oceanloc._typing import ArrayLike, FloatArray, IntArray
from oceanloc.errors import ConfigError, DataError
from oceanloc.geo.enu import EnuOrigin
from oceanloc.io.gnssa import GPS_EPOCH_2020_UNIX_S, GnssaSurvey
from oceanloc.io.qc import QcReport
from oceanloc.models.attitude import interpolate_track, rotation_enu_from_body, transducer_jacobians

_MAX_TWTT_S = 60.0


@dataclass(frozen=True, slots=True, kw_only=True)
class AntennaTrack:
    """GNSS antenna positions with attitude, time-ordered.

    Attributes
    ----------
    t_s : (k,) float
        Epochs, seconds (the survey's time base), strictly increasing.
    position_enu_m : (k, 3) float
        Antenna position (E, N, U) about the survey origin, metres.
    covariance_enu_m2 : (k, 3, 3) float
        Its covariance, square metres.
    attitude_deg : (k, 3) float
        Roll, pitch, heading, degrees (:mod:`oceanloc.models.attitude` conventions).
    attitude_sigma_deg : (3,) float
        1-sigma of roll, pitch and heading, degrees, propagated into each transducer position's covariance
        through the lever arm (zeros: attitude taken as exact).
    """

    t_s: FloatArray
    position_enu_m: FloatArray
    covariance_enu_m2: FloatArray
    attitude_deg: FloatArray
    attitude_sigma_deg: FloatArray = field(default_factory=lambda: np.zeros(3))

    def at(self, t_s: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Position, covariance and attitude interpolated at ``t_s``
        (:func:`~oceanloc.models.attitude.interpolate_track`)."""
        return interpolate_track(
            self.t_s, t_s, self.position_enu_m, self.covariance_enu_m2, self.attitude_deg
        )


@dataclass(frozen=True, slots=True, kw_only=True)
class GnssaArraySurvey:
    """One GNSS-A survey of an array: ``n`` pings, ``m`` replies, ``J`` transponders.

    Attributes
    ----------
    name, path : str
        Survey name and the file (or files) it was read from.
    origin : EnuOrigin or None
        Geodetic origin of the ENU frame.
    transponder_ids : tuple of str
        ``J`` transponder names.
    t_transmit_s : (n,) float
        Transmit times, seconds.
    transmit_antenna_enu_m : (n, 3) float
    transmit_antenna_cov_m2 : (n, 3, 3) float
        Antenna position at transmit and its covariance (attitude error included).
    transmit_rotation : (n, 3, 3) float
        Body-to-ENU rotation at transmit.
    reply_ping : (m,) int
        Ping (row of the transmit arrays) of each reply.
    reply_transponder : (m,) int
        Transponder (index into ``transponder_ids``) of each reply.
    twtt_s : (m,) float
        Measured two-way travel times, seconds, turn-around delay included (see :attr:`turnaround_s`).
    t_receive_s : (m,) float
        Receive times (``t_transmit + twtt`` unless the file says otherwise), seconds.
    receive_antenna_enu_m, receive_antenna_cov_m2, receive_rotation : (m, 3), (m, 3, 3), (m, 3, 3)
        The same at each reply's receive time.
    lever_arm_body_m : (3,) float
        Antenna-to-transducer lever arm, forward, starboard, down, metres.
    lever_arm_cov_m2 : (3, 3) float
        Its covariance (zeros: known exactly).
    turnaround_s : (J,) float
        Turn-around delay of each transponder, subtracted from the TWTT, seconds.
    approx_positions_enu_m : (J, 3) float or None
        Approximate transponder positions (a deployment log, a previous campaign), metres.
    line : (m,) int
        Source line of each reply (0 where none).
    qc : QcReport
        Lines the readers skipped, with reasons.
    time_origin_unix_s : float
        Unix time of the survey's time 0 (default 2020-01-01 UTC, the La Jolla files'; a reader of
        another format sets its own, e.g. 946728000 for J2000 seconds).
    """

    name: str
    path: str
    origin: EnuOrigin | None
    transponder_ids: tuple[str, ...]
    t_transmit_s: FloatArray
    transmit_antenna_enu_m: FloatArray
    transmit_antenna_cov_m2: FloatArray
    transmit_rotation: FloatArray
    reply_ping: IntArray
    reply_transponder: IntArray
    twtt_s: FloatArray
    t_receive_s: FloatArray
    receive_antenna_enu_m: FloatArray
    receive_antenna_cov_m2: FloatArray
    receive_rotation: FloatArray
    lever_arm_body_m: FloatArray
    lever_arm_cov_m2: FloatArray
    turnaround_s: FloatArray
    approx_positions_enu_m: FloatArray | None = None
    line: IntArray | None = None
    qc: QcReport = field(default_factory=QcReport)
    time_origin_unix_s: float = GPS_EPOCH_2020_UNIX_S

    def __post_init__(self) -> None:
        n, m, j = self.t_transmit_s.shape[0], self.twtt_s.shape[0], len(self.transponder_ids)
        shapes = {
            "transmit_antenna_enu_m": (self.transmit_antenna_enu_m.shape, (n, 3)),
            "transmit_antenna_cov_m2": (self.transmit_antenna_cov_m2.shape, (n, 3, 3)),
            "transmit_rotation": (self.transmit_rotation.shape, (n, 3, 3)),
            "reply_ping": (self.reply_ping.shape, (m,)),
            "reply_transponder": (self.reply_transponder.shape, (m,)),
            "t_receive_s": (self.t_receive_s.shape, (m,)),
            "receive_antenna_enu_m": (self.receive_antenna_enu_m.shape, (m, 3)),
            "receive_antenna_cov_m2": (self.receive_antenna_cov_m2.shape, (m, 3, 3)),
            "receive_rotation": (self.receive_rotation.shape, (m, 3, 3)),
            "lever_arm_body_m": (self.lever_arm_body_m.shape, (3,)),
            "lever_arm_cov_m2": (self.lever_arm_cov_m2.shape, (3, 3)),
            "turnaround_s": (self.turnaround_s.shape, (j,)),
        }
        for name, (got, want) in shapes.items():
            if got != want:
                raise ConfigError(f"GnssaArraySurvey.{name} has shape {got}, expected {want}")
        if self.approx_positions_enu_m is not None and self.approx_positions_enu_m.shape != (j, 3):
            raise ConfigError(f"approx_positions_enu_m must be ({j}, 3)")
        if m == 0:
            raise DataError(f"{self.path or self.name}: no reply from any transponder")
        if np.any((self.reply_ping < 0) | (self.reply_ping >= n)):
            raise ConfigError("reply_ping indexes a ping that does not exist")
        if np.any((self.reply_transponder < 0) | (self.reply_transponder >= j)):
            raise ConfigError("reply_transponder indexes a transponder that does not exist")
        bad = ~np.isfinite(self.twtt_s) | (self.twtt_s <= 0.0) | (self.twtt_s >= _MAX_TWTT_S)
        if bad.any():
            i = int(np.argmax(bad))
            raise DataError(
                f"{self.path or self.name}: reply {i} has TWTT {self.twtt_s[i]} s outside (0, 60) s"
            )
        if self.line is None:
            object.__setattr__(self, "line", np.zeros(m, dtype=np.int64))

    @property
    def n_pings(self) -> int:
        return int(self.t_transmit_s.shape[0])

    @property
    def n_replies(self) -> int:
        return int(self.twtt_s.shape[0])

    @property
    def n_transponders(self) -> int:
        return len(self.transponder_ids)

    def transmit_enu_m(self, lever_arm_body_m: ArrayLike | None = None) -> FloatArray:
        """Transducer at transmit, ``x_A + R l`` (the survey's lever arm unless one is given), (n, 3) m."""
        lever = self.lever_arm_body_m if lever_arm_body_m is None else np.asarray(lever_arm_body_m, float)
        return self.transmit_antenna_enu_m + self.transmit_rotation @ lever

    def receive_enu_m(self, lever_arm_body_m: ArrayLike | None = None) -> FloatArray:
        """Transducer at each reply's receive time, (m, 3) m."""
        lever = self.lever_arm_body_m if lever_arm_body_m is None else np.asarray(lever_arm_body_m, float)
        return self.receive_antenna_enu_m + self.receive_rotation @ lever

    @property
    def replies_per_transponder(self) -> IntArray:
        return np.bincount(self.reply_transponder, minlength=self.n_transponders).astype(np.int64)


def _identity(k: int) -> FloatArray:
    return np.broadcast_to(np.eye(3), (k, 3, 3)).copy()


def array_survey_from_transducers(
    *,
    name: str,
    t_transmit_s: ArrayLike,
    transmit_enu_m: ArrayLike,
    transmit_cov_m2: ArrayLike,
    reply_ping: ArrayLike,
    reply_transponder: ArrayLike,
    twtt_s: ArrayLike,
    receive_enu_m: ArrayLike,
    receive_cov_m2: ArrayLike,
    turnaround_s: ArrayLike,
    transponder_ids: tuple[str, ...],
    t_receive_s: ArrayLike | None = None,
    origin: EnuOrigin | None = None,
    approx_positions_enu_m: ArrayLike | None = None,
    line: ArrayLike | None = None,
    path: str = "",
    qc: QcReport | None = None,
    time_origin_unix_s: float = GPS_EPOCH_2020_UNIX_S,
    transmit_rotation: ArrayLike | None = None,
    receive_rotation: ArrayLike | None = None,
    lever_arm_body_m: ArrayLike | None = None,
    lever_arm_cov_m2: ArrayLike | None = None,
) -> GnssaArraySurvey:
    """A survey from positions sampled at transmit and at each receive: see :class:`GnssaArraySurvey`.

    Without rotations and lever arm these are the transducer positions (identity rotations, a zero lever
    arm known exactly). With them they are the GNSS antenna's, already sampled at those epochs (e.g. by
    :func:`oceanloc.field.gnatss_input.antenna_pings`), and the transducer is ``x_A + R l``.
    """
    t_tx = np.asarray(t_transmit_s, dtype=float)
    ping = np.asarray(reply_ping, dtype=np.int64)
    twtt = np.asarray(twtt_s, dtype=float)
    t_rx = t_tx[ping] + twtt if t_receive_s is None else np.asarray(t_receive_s, dtype=float)
    return GnssaArraySurvey(
        name=name,
        path=path,
        origin=origin,
        transponder_ids=tuple(transponder_ids),
        t_transmit_s=t_tx,
        transmit_antenna_enu_m=np.asarray(transmit_enu_m, dtype=float),
        transmit_antenna_cov_m2=np.asarray(transmit_cov_m2, dtype=float),
        transmit_rotation=_identity(t_tx.size)
        if transmit_rotation is None
        else np.asarray(transmit_rotation, dtype=float),
        reply_ping=ping,
        reply_transponder=np.asarray(reply_transponder, dtype=np.int64),
        twtt_s=twtt,
        t_receive_s=t_rx,
        receive_antenna_enu_m=np.asarray(receive_enu_m, dtype=float),
        receive_antenna_cov_m2=np.asarray(receive_cov_m2, dtype=float),
        receive_rotation=_identity(twtt.size)
        if receive_rotation is None
        else np.asarray(receive_rotation, dtype=float),
        lever_arm_body_m=np.zeros(3) if lever_arm_body_m is None else np.asarray(lever_arm_body_m, float),
        lever_arm_cov_m2=np.zeros((3, 3))
        if lever_arm_cov_m2 is None
        else np.asarray(lever_arm_cov_m2, float),
        turnaround_s=np.asarray(turnaround_s, dtype=float).reshape(-1),
        approx_positions_enu_m=None
        if approx_positions_enu_m is None
        else np.asarray(approx_positions_enu_m, float),
        line=None if line is None else np.asarray(line, dtype=np.int64),
        qc=qc or QcReport(),
        time_origin_unix_s=time_origin_unix_s,
    )


def array_survey_from_track(
    *,
    name: str,
    track: AntennaTrack,
    t_transmit_s: ArrayLike,
    reply_ping: ArrayLike,
    reply_transponder: ArrayLike,
    twtt_s: ArrayLike,
    turnaround_s: ArrayLike,
    transponder_ids: tuple[str, ...],
    lever_arm_body_m: ArrayLike,
    lever_arm_cov_m2: ArrayLike | None = None,
    origin: EnuOrigin | None = None,
    approx_positions_enu_m: ArrayLike | None = None,
    line: ArrayLike | None = None,
    path: str = "",
    qc: QcReport | None = None,
    time_origin_unix_s: float = GPS_EPOCH_2020_UNIX_S,
) -> GnssaArraySurvey:
    """A survey from a GNSS antenna track with attitude and a body-frame lever arm.

    The track is interpolated to each transmit time and to each reply's receive time ``t_transmit +
    TWTT`` (the TWTT as measured, turn-around included: the reply reaches the transducer then). The
    attitude's 1-sigma is propagated into each position's covariance through the lever arm,
    ``J_att diag(sigma^2) J_att^T`` (:func:`~oceanloc.models.attitude.transducer_jacobians`).

    Raises
    ------
    DataError
        If a transmit or receive time lies outside the track.
    """
    t_tx = np.asarray(t_transmit_s, dtype=float)
    ping = np.asarray(reply_ping, dtype=np.int64)
    twtt = np.asarray(twtt_s, dtype=float)
    t_rx = t_tx[ping] + twtt
    lever = np.asarray(lever_arm_body_m, dtype=float)
    var_att = np.asarray(track.attitude_sigma_deg, dtype=float) ** 2

    def sample(t: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        pos, cov, att = track.at(t)
        rot = rotation_enu_from_body(att[:, 0], att[:, 1], att[:, 2])
        if np.any(var_att > 0.0):
            _, d_att = transducer_jacobians(att[:, 0], att[:, 1], att[:, 2], lever)
            cov = cov + np.einsum("nik,k,njk->nij", d_att, var_att, d_att)
        return pos, cov, rot

    pos_tx, cov_tx, rot_tx = sample(t_tx)
    pos_rx, cov_rx, rot_rx = sample(t_rx)
    return GnssaArraySurvey(
        name=name,
        path=path,
        origin=origin,
        transponder_ids=tuple(transponder_ids),
        t_transmit_s=t_tx,
        transmit_antenna_enu_m=pos_tx,
        transmit_antenna_cov_m2=cov_tx,
        transmit_rotation=rot_tx,
        reply_ping=ping,
        reply_transponder=np.asarray(reply_transponder, dtype=np.int64),
        twtt_s=twtt,
        t_receive_s=t_rx,
        receive_antenna_enu_m=pos_rx,
        receive_antenna_cov_m2=cov_rx,
        receive_rotation=rot_rx,
        lever_arm_body_m=lever,
        lever_arm_cov_m2=np.zeros((3, 3))
        if lever_arm_cov_m2 is None
        else np.asarray(lever_arm_cov_m2, float),
        turnaround_s=np.asarray(turnaround_s, dtype=float).reshape(-1),
        approx_positions_enu_m=None
        if approx_positions_enu_m is None
        else np.asarray(approx_positions_enu_m, float),
        line=None if line is None else np.asarray(line, dtype=np.int64),
        qc=qc or QcReport(),
        time_origin_unix_s=time_origin_unix_s,
    )


def array_survey_from_gnssa(survey: GnssaSurvey, turnaround_s: float = 0.0) -> GnssaArraySurvey:
    """A La Jolla single-transponder survey as an array survey of one transponder (diagonal covariances
    from the file's sigmas; its TWTT already has the turn-around removed, so ``turnaround_s`` is 0)."""
    n = survey.n_pings
    return array_survey_from_transducers(
        name=survey.name,
        path=survey.path,
        origin=survey.origin,
        t_transmit_s=survey.t_transmit_s,
        t_receive_s=survey.t_receive_s,
        transmit_enu_m=survey.transmit_enu_m,
        transmit_cov_m2=np.einsum("ni,ij->nij", survey.sigma_transmit_enu_m**2, np.eye(3)),
        receive_enu_m=survey.receive_enu_m,
        receive_cov_m2=np.einsum("ni,ij->nij", survey.sigma_receive_enu_m**2, np.eye(3)),
        reply_ping=np.arange(n),
        reply_transponder=np.zeros(n, dtype=np.int64),
        twtt_s=survey.twtt_s,
        turnaround_s=np.array([turnaround_s]),
        transponder_ids=(survey.name,),
        line=survey.line,
        qc=survey.qc,
    )
