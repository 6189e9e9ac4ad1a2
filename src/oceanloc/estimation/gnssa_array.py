"""GNSS-A localization of a transponder array: any number of transponders, partial replies, lever arm,
attitude, sound-speed profile; independent positions or the array's common shift.

Entry point: :func:`localize_gnssa_array` (survey: :class:`~oceanloc.io.gnssa_array.GnssaArraySurvey`,
options: :class:`GnssaArrayOptions`, preset :func:`gnatss_like_options`) -> :class:`GnssaArrayResult`.

Model, per reply ``o`` of ping ``i`` from transponder ``j`` (transducer ``a_i = A_i + R_i l`` at transmit,
``b_o = B_o + R_o l`` at receive, antenna positions ``A``, ``B``, body-to-ENU rotations ``R``, lever arm
``l``)::

    TWTT_o - tau_j = P_o / c(t_o),   P_o = c_ref [T(p_j, a_i) + T(p_j, b_o)] + g . G_o

- ``T`` is the one-way travel time of a leg through the sound-speed profile
  (:mod:`oceanloc.models.sound_profile`): ``straight`` (``L / c_ref``, no profile), ``harmonic`` (``L h_j``
  with the harmonic-mean slowness ``h_j`` between the surface and transponder ``j``'s initial depth, fixed:
  what GNATSS does) or ``ray`` (``L h(z_a, z_p) + delta``: the straight leg at the harmonic mean between
  the leg's own end depths, exact in the transponder's depth, plus the ray-bending correction ``delta``
  tabulated by :func:`~oceanloc.models.sound_profile.bending_table` and re-evaluated between solves; its
  derivative, below 1e-4 of the straight leg's, is left out of the Jacobian, so the estimate is the exact
  ray-traced one and only the convergence rate is affected);
- ``c(t)`` is the sound-speed scale, piecewise linear in time (knots with an exponentially correlated prior
  centred on ``c_ref``, the profile's harmonic mean): ``c(t) / c_ref - 1`` is the estimated relative
  correction to the whole profile (a uniform slowness scale leaves the rays' paths unchanged, so the
  ray-traced model stays exact under it);
- ``g . G_o`` is the horizontal slowness gradient term of
  :func:`~oceanloc.models.acoustics.gradient_path_m2` on both legs (shared by the transponders).

Unknowns: the transponders (``3J``; or the common shift ``s`` of a fixed geometry, ``p_j = q_j + s``), the
gradient, the lever arm (a calibration option, with its prior; otherwise kept as an unknown with the
survey's lever-arm covariance as its prior whenever that is not zero, so the lever arm's uncertainty,
common to every ping, enters the covariance as it should instead of per ping), then the knots.

Noise: per ping the replies share the transmit position's error, so each ping's replies are whitened
together with the Cholesky factor of ``V C_tx V^T + diag(u^T C_rx u + s^2 + beta^2 tan^2)`` (``V`` the
transmit legs' unit vectors): the GNSS covariances, full 3x3, projected on the legs (journal eqs. 46-52),
plus the path noise ``s`` and the far-ping term ``beta tan(incidence)`` estimated by maximum likelihood,
as in :mod:`oceanloc.estimation.gnssa`.

Robustness and uncertainty as in :mod:`oceanloc.estimation.gnssa`: a robust first fit per transponder
(on at most 400 of its replies, spread over the survey) screens every reply for gross travel times;
the outlier rule removes the replies with the largest normalized residual above ``outlier_threshold``
(up to ``1 + n / 1000`` per round, so ten thousand pings need no thousand solves); a delete-one-block
jackknife over contiguous time blocks (linearized at the solution: one normal-matrix downdate per
block) and the survey-wide GNSS error (common to the whole array; only when the residuals are serially
correlated, :func:`serial_correlation_test`) are added to the formal covariance.

Model selection (:func:`select_model`, on by default): after the outlier loop the gradient, the
speed's variation in time and its constant scale are each dropped when their likelihood-ratio
statistic is below Schwarz's threshold ``dof ln n``, so a short drift-free survey does not pay for
unused parameters (on the GNATSS oracle's 300-ping surveys the centre error falls from 28 to 4 mm)
while a drifting one keeps them; the tests are reported (:attr:`GnssaArrayResult.model_tests`).
Everything is vectorized over replies; the only Python loops run over transponders, rounds and blocks.

Use::

    survey = array_survey_from_track(...)          # or array_survey_from_transducers / _from_gnssa
    result = localize_gnssa_array(survey, GnssaArrayOptions(), profile=SoundSpeedProfile(...))
    result.positions_enu_m, result.covariance_m2, result.positions_geodetic   # (J, 3), (3J, 3J), (J, 3)
    result.residual_m[result.used], result.exclusions, result.iterations
    result.speed_scale(t), result.gradient_per_km                             # the profile correction
    localize_gnssa_array(survey, gnatss_like_options(residual_limit_m=...), profile=...)  # GNATSS's way
    localize_gnssa_array(survey, GnssaArrayOptions(solution="common_shift"), profile=...,
                         geometry=ArrayGeometry(positions_enu_m=previous_campaign_enu_m))
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from oceanloc._typing import BoolArray, FloatArray, IntArray
from oceanloc.errors import ConfigError, DataError
from oceanloc.estimation.gnssa import (
    _positive_part,
    _variance_components,
    gnssa_epoch_utc,
    hat_basis,
    robust_first_fit,
)
from oceanloc.estimation.map_gauss_newton import (
    GaussianPrior,
    MapOptions,
    MapResult,
    NormalEquations,
    solve_map,
)
from oceanloc.geo.enu import enu_to_geodetic
from oceanloc.io.gnssa import GPS_EPOCH_2020_UNIX_S
from oceanloc.io.gnssa_array import GnssaArraySurvey
from oceanloc.models.acoustics import gradient_path_jacobian, gradient_path_m2
from oceanloc.models.sound_profile import BendingTable, SoundSpeedProfile, bending_table

ACOUSTIC_MODELS: tuple[str, ...] = ("auto", "straight", "harmonic", "ray")
SOLUTIONS: tuple[str, ...] = ("independent", "common_shift")
OUTLIER_RULES: tuple[str, ...] = ("normalized", "residual")
SELECTION_CRITERIA: tuple[str, ...] = ("bic", "lr")
_ROBUST_FIT_REPLIES = 400
"""Replies per transponder the robust first fit uses (evenly spread); the screen then covers all."""
_SERIAL_MIN_REPLIES = 150
"""Fewest used replies of a transponder for :func:`serial_correlation_test` to count it: with ``n``
replies the lag-1 autocorrelation of white residuals has the standard error ``n^-1/2``, so a correlation
of 0.3 (GNSS errors a third of the residual variance) is found at the 1 % level with 90 % power when
``n >= ((2.33 + 1.28) / 0.3)^2``, about 145. With fewer, the conservative common-mode term stays."""


@dataclass(frozen=True, slots=True, kw_only=True)
class GnssaArrayOptions:
    """Settings of :func:`localize_gnssa_array` (defaults: oceanloc's own; see :func:`gnatss_like_options`).

    Attributes
    ----------
    solution : str
        ``independent`` (every transponder's position) or ``common_shift`` (one shift of the geometry
        given to :func:`localize_gnssa_array`).
    acoustic_model : str
        ``auto`` (``ray`` with a profile, ``straight`` without), ``straight``, ``harmonic`` or ``ray``.
    sound_speed_mps : float or None
        Reference speed ``c_ref``; None: the profile's harmonic mean from the surface to the transponders'
        mean initial depth (1500 without a profile).
    transponder_speeds_mps : tuple of float or None
        ``harmonic`` model only: the fixed harmonic-mean speed of each transponder, m/s (instead of the
        profile's).
    estimate_sound_speed : bool
        Estimate the sound-speed scale ``c(t)`` (knots); False fixes ``c = c_ref``.
    sigma_sound_speed_mps, knot_spacing_s, min_pings_per_knot, sound_speed_correlation_s
        As in :class:`~oceanloc.estimation.gnssa.GnssaOptions`.
    estimate_gradient : bool
    sigma_gradient_per_km : float
    estimate_lever_arm : bool
        Calibrate the lever arm (needs attitude variation, e.g. circling with changing heading).
    sigma_lever_arm_m : float
        Prior 1-sigma of each lever-arm component when calibrating and the survey gives no covariance.
    estimate_noise : bool
        Estimate ``sigma_path`` and ``beta`` (variance components); False keeps ``sigma_path_m``.
    sigma_path_m : float
        Path noise (timing, unmodelled propagation) before it is estimated, or fixed, metres two-way.
    range_dependent_weights : bool
        Estimate the far-ping term ``beta tan(incidence)``.
    outlier_rule : str
        ``normalized`` (``|r| / sigma > outlier_threshold``) or ``residual`` (GNATSS's: ``|r| >
        residual_limit_m``, all at once per round).
    outlier_threshold : float
    residual_limit_m : float
        Two-way path residual limit of the ``residual`` rule, metres.
    max_outlier_fraction : float
    prescreen, prescreen_sigmas, gross_error_m, max_gross_fraction
        The gross-error pre-screen of :mod:`oceanloc.estimation.gnssa`, per transponder.
    sigma_position_prior_m : float
        Position prior around the initial positions, metres.
    surface_height_m : float or None
        ENU height of the sea surface (profile depth 0); None: the mean transducer height at transmit.
    jackknife_blocks : int
        Time blocks of the linearized delete-one-block jackknife (0: off).
    gnss_common_mode : bool or None
        Add the survey-wide GNSS error to the covariance (common to every transponder): True always, False
        never, None (default) when the residuals are serially correlated (:func:`serial_correlation_test`
        at level ``selection_alpha``): white GNSS errors average out over the pings and are already in the
        formal covariance; errors correlated in time do not, and show in the residuals.
    serial_lags : int
        Lags of that test.
    max_rounds : int
        Largest number of outlier rounds.
    select_model : bool
        Keep only the sound-speed and gradient parameters the survey supports (see
        :func:`select_model`): the gradient, the speed's variation in time, then the constant scale, each
        dropped when its likelihood-ratio statistic is below the criterion's threshold.
    selection_criterion : str
        ``bic`` (default: Schwarz's, ``dof ln n`` for ``n`` used replies) or ``lr`` (the chi-square
        quantile ``1 - selection_alpha``).
    selection_alpha : float
        Significance level of the ``lr`` criterion and of the serial-correlation test, in (0, 0.5).
    """

    solution: str = "independent"
    acoustic_model: str = "auto"
    sound_speed_mps: float | None = None
    transponder_speeds_mps: tuple[float, ...] | None = None
    estimate_sound_speed: bool = True
    sigma_sound_speed_mps: float = 3.0
    knot_spacing_s: float | None = 900.0
    min_pings_per_knot: int = 40
    sound_speed_correlation_s: float = 1800.0
    estimate_gradient: bool = True
    sigma_gradient_per_km: float = 1e-3
    estimate_lever_arm: bool = False
    sigma_lever_arm_m: float = 1.0
    estimate_noise: bool = True
    sigma_path_m: float = 0.05
    range_dependent_weights: bool = True
    outlier_rule: str = "normalized"
    outlier_threshold: float = 3.0
    residual_limit_m: float = 1.0
    max_outlier_fraction: float = 0.2
    prescreen: bool = True
    prescreen_sigmas: float = 8.0
    gross_error_m: float = 5.0
    max_gross_fraction: float = 0.4
    sigma_position_prior_m: float = 1000.0
    surface_height_m: float | None = None
    jackknife_blocks: int = 10
    gnss_common_mode: bool | None = None
    serial_lags: int = 10
    max_rounds: int = 200
    select_model: bool = True
    selection_criterion: str = "bic"
    selection_alpha: float = 0.01

    def __post_init__(self) -> None:
        if self.solution not in SOLUTIONS:
            raise ConfigError(f"solution {self.solution!r} is none of {', '.join(SOLUTIONS)}")
        if self.acoustic_model not in ACOUSTIC_MODELS:
            raise ConfigError(
                f"acoustic_model {self.acoustic_model!r} is none of {', '.join(ACOUSTIC_MODELS)}"
            )
        if self.outlier_rule not in OUTLIER_RULES:
            raise ConfigError(f"outlier_rule {self.outlier_rule!r} is none of {', '.join(OUTLIER_RULES)}")
        if self.sound_speed_mps is not None and not 1300.0 <= self.sound_speed_mps <= 1700.0:
            raise ConfigError(f"sound speed {self.sound_speed_mps} m/s is outside [1300, 1700]")
        positive = {
            "sigma_sound_speed_mps": self.sigma_sound_speed_mps,
            "sigma_gradient_per_km": self.sigma_gradient_per_km,
            "sigma_lever_arm_m": self.sigma_lever_arm_m,
            "sigma_path_m": self.sigma_path_m,
            "residual_limit_m": self.residual_limit_m,
            "gross_error_m": self.gross_error_m,
            "sigma_position_prior_m": self.sigma_position_prior_m,
        }
        for name, value in positive.items():
            if not (value > 0.0 and np.isfinite(value)):
                raise ConfigError(f"{name} must be a positive number, got {value}")
        if self.outlier_threshold <= 1.0:
            raise ConfigError(f"outlier_threshold must exceed 1, got {self.outlier_threshold}")
        if not 0.0 <= self.max_outlier_fraction < 0.5:
            raise ConfigError("max_outlier_fraction must be in [0, 0.5)")
        if not 0.0 <= self.max_gross_fraction < 0.5:
            raise ConfigError("max_gross_fraction must be in [0, 0.5)")
        if self.jackknife_blocks == 1 or self.jackknife_blocks < 0:
            raise ConfigError("jackknife_blocks must be 0 (off) or at least 2")
        if self.knot_spacing_s is not None and self.knot_spacing_s <= 0.0:
            raise ConfigError("knot_spacing_s must be positive (or None for one constant speed)")
        if self.serial_lags < 1:
            raise ConfigError(f"serial_lags must be at least 1, got {self.serial_lags}")
        if self.selection_criterion not in SELECTION_CRITERIA:
            raise ConfigError(
                f"selection_criterion {self.selection_criterion!r} is none of {', '.join(SELECTION_CRITERIA)}"
            )
        if not 0.0 < self.selection_alpha < 0.5:
            raise ConfigError(f"selection_alpha must be in (0, 0.5), got {self.selection_alpha}")


def gnatss_like_options(**overrides: object) -> GnssaArrayOptions:
    """GNATSS's settings: a fixed harmonic-mean speed per transponder from the profile, no sound-speed,
    gradient or noise estimation, a TWTT sigma of 1e-5 s (GNATSS's ``travel_times_variance`` 1e-10 s^2,
    about 1.5 cm of two-way path), its residual outlier limit, no pre-screen, jackknife or common-mode
    term. Keyword arguments override any field (e.g. ``residual_limit_m``, ``transponder_speeds_mps``)."""
    base = GnssaArrayOptions(
        acoustic_model="harmonic",
        estimate_sound_speed=False,
        estimate_gradient=False,
        estimate_noise=False,
        sigma_path_m=1500.0 * 1e-5,
        range_dependent_weights=False,
        outlier_rule="residual",
        residual_limit_m=1.0,
        prescreen=False,
        jackknife_blocks=0,
        gnss_common_mode=False,
        select_model=False,
    )
    return dataclasses.replace(base, **overrides)  # type: ignore[arg-type]


@dataclass(frozen=True, slots=True, kw_only=True)
class ArrayGeometry:
    """A transponder array's geometry from a prior campaign, for the ``common_shift`` solution.

    Attributes
    ----------
    positions_enu_m : (J, 3) float
        Transponder positions in the survey's ENU frame (the shift is estimated relative to these), metres.
    """

    positions_enu_m: FloatArray


@dataclass(frozen=True, slots=True, kw_only=True)
class ReplyExclusion:
    """One excluded reply and why."""

    reply: int
    ping: int
    transponder: str
    line: int
    time_s: float
    reason: str
    residual_m: float

    def __str__(self) -> str:
        return f"line {self.line} (t={self.time_s:.1f} s, {self.transponder}): {self.reason}"

    def to_record(self) -> dict:
        return {
            "reply": self.reply,
            "ping": self.ping,
            "transponder": self.transponder,
            "line": self.line,
            "time_s": float(self.time_s),
            "reason": self.reason,
            "residual_m": float(self.residual_m),
        }


@dataclass(frozen=True, slots=True, kw_only=True)
class ArrayIteration:
    """One solve of the outer loop: what was used and what came out."""

    round: int
    replies_used: int
    sigma_path_m: float
    beta_m: float
    cost: float
    map_iterations: int
    position_change_m: float
    excluded: int

    def to_record(self) -> dict:
        return {k: (float(v) if isinstance(v, float) else v) for k, v in dataclasses.asdict(self).items()}


@dataclass(frozen=True, slots=True, kw_only=True)
class ModelTest:
    """One likelihood-ratio test of :func:`select_model`: does the survey support a group of parameters?

    Attributes
    ----------
    name : str
        ``gradient`` (east and north slowness gradient), ``sound_speed_variation`` (the knots of ``c(t)``
        against one constant speed) or ``sound_speed_scale`` (that constant speed against ``c_ref``).
    dof : int
        Parameters the smaller model lacks (constraints tested).
    statistic : float
        Increase of the weighted cost (``-2 log`` posterior) when they are removed.
    threshold : float
        The criterion's threshold: ``dof ln n`` (BIC), or the chi-square quantile ``1 - alpha`` for
        ``dof`` degrees of freedom.
    p_value : float
        Chi-square tail probability of ``statistic``.
    kept : bool
        The parameters stayed in the model (``statistic > threshold``).
    estimate, sigma : tuple of float
        The tested parameters in the bigger model and their 1-sigma: the gradient (east, north) per km,
        the range of the knot speeds (max - min) m/s, or the constant correction in ppm.
    unit : str
    """

    name: str
    dof: int
    statistic: float
    threshold: float
    p_value: float
    kept: bool
    estimate: tuple[float, ...]
    sigma: tuple[float, ...]
    unit: str

    def to_record(self) -> dict:
        return {
            "name": self.name,
            "dof": self.dof,
            "statistic": float(self.statistic),
            "threshold": float(self.threshold),
            "p_value": float(self.p_value),
            "kept": bool(self.kept),
            "estimate": [float(v) for v in self.estimate],
            "sigma": [float(v) for v in self.sigma],
            "unit": self.unit,
        }


@dataclass(frozen=True, slots=True, kw_only=True)
class ArrayCentre:
    """The array's centre from one survey, in the form :func:`oceanloc.field.repeatability.survey_spread`
    takes (``position_enu_m``, ``sigma_enu_m``, ``epoch_s``)."""

    position_enu_m: FloatArray
    covariance_m2: FloatArray
    epoch_s: float

    @property
    def sigma_enu_m(self) -> FloatArray:
        return np.sqrt(np.diag(self.covariance_m2))


@dataclass(frozen=True, slots=True, kw_only=True)
class GnssaArrayResult:
    """Localization of an array from one survey (:func:`localize_gnssa_array`).

    Attributes
    ----------
    name : str
    solution : str
        ``independent`` or ``common_shift``.
    acoustic_model : str
        The travel-time model used (``straight``, ``harmonic``, ``ray``).
    transponder_ids : tuple of str
    positions_enu_m : (J, 3) float
        Transponder positions, ENU about the survey origin, metres.
    covariance_m2 : (3J, 3J) float
        Reported covariance of the stacked positions (formal + positive part of jackknife - formal + GNSS
        common mode).
    covariance_formal_m2 : (3J, 3J) float
    covariance_jackknife_m2 : (3J, 3J) float or None
    covariance_gnss_m2 : (3J, 3J) float
    positions_geodetic : (J, 3) float or None
        Latitude, longitude (deg), ellipsoidal height (m).
    shift_enu_m : (3,) float or None
        The common shift (``common_shift`` solution), metres.
    shift_covariance_m2 : (3, 3) float or None
    centre : ArrayCentre
        Mean of the positions and its covariance.
    epoch_s : float
        Mean transmit time of the used pings.
    reference_speed_mps : float
        ``c_ref``.
    knot_times_s, sound_speed_knots_mps, sound_speed_knot_sigma_mps : (K,) float
        Estimated sound speed scale ``c(t)`` at its knots and its 1-sigma (empty when fixed).
    sound_speed_mps : float
        Mean of ``c(t)`` over the used replies.
    speed_correction_ppm : float
        ``1e6 (mean c / c_ref - 1)``: the estimated correction to the profile as a whole.
    gradient_per_km, gradient_sigma_per_km : (2,) float
        Horizontal slowness gradient (east, north) and 1-sigma (zeros when not estimated).
    lever_arm_body_m : (3,) float
        Lever arm used (estimated when calibrating), forward, starboard, down, metres.
    lever_arm_covariance_m2 : (3, 3) float
        Its posterior covariance (the prior's when not estimated).
    lever_arm_estimated : bool
    lever_arm_prior_sigma_m : (3,) float
        The lever arm's prior 1-sigma (zeros when it is known exactly): compared with the posterior, it
        says how much the survey's geometry determined it (:attr:`lever_arm_determined`).
    reply_ping, reply_transponder : (m,) int
        Copied from the survey, to read the per-reply arrays.
    residual_m : (m,) float
        ``c0 (TWTT - tau - model)`` for every reply, two-way path metres (``c0 = c_ref``).
    residual_s : (m,) float
        The same in seconds of travel time.
    sigma_m : (m,) float
        Per-reply 1-sigma of that residual (marginal), metres.
    used : (m,) bool
    exclusions : tuple of ReplyExclusion
    iterations : tuple of ArrayIteration
    sigma_path_m, beta_m, residual_rms_m : float
    converged : bool
    time_origin_unix_s : float
        Unix time of the survey's time 0 (for :attr:`epoch_s` as UTC).
    status : str
        ``ok`` or what went wrong.
    model_tests : tuple of ModelTest
        The tests of the model selection (:func:`select_model`; empty when it is off): which of the
        gradient, the speed's variation in time and its constant scale were kept, with their estimates.
    """

    name: str
    solution: str
    acoustic_model: str
    transponder_ids: tuple[str, ...]
    positions_enu_m: FloatArray
    covariance_m2: FloatArray
    covariance_formal_m2: FloatArray
    covariance_jackknife_m2: FloatArray | None
    covariance_gnss_m2: FloatArray
    positions_geodetic: FloatArray | None
    shift_enu_m: FloatArray | None
    shift_covariance_m2: FloatArray | None
    centre: ArrayCentre
    epoch_s: float
    reference_speed_mps: float
    knot_times_s: FloatArray
    sound_speed_knots_mps: FloatArray
    sound_speed_knot_sigma_mps: FloatArray
    sound_speed_mps: float
    speed_correction_ppm: float
    gradient_per_km: FloatArray
    gradient_sigma_per_km: FloatArray
    lever_arm_body_m: FloatArray
    lever_arm_covariance_m2: FloatArray
    lever_arm_estimated: bool
    lever_arm_prior_sigma_m: FloatArray
    reply_ping: IntArray
    reply_transponder: IntArray
    residual_m: FloatArray
    residual_s: FloatArray
    sigma_m: FloatArray
    used: BoolArray
    exclusions: tuple[ReplyExclusion, ...]
    iterations: tuple[ArrayIteration, ...]
    sigma_path_m: float
    beta_m: float
    residual_rms_m: float
    converged: bool
    time_origin_unix_s: float
    status: str = "ok"
    model_tests: tuple[ModelTest, ...] = ()

    @property
    def sigma_enu_m(self) -> FloatArray:
        """1-sigma of each transponder's (E, N, U), ``(J, 3)`` metres."""
        return np.sqrt(np.diag(self.covariance_m2)).reshape(-1, 3)

    @property
    def lever_arm_determined(self) -> BoolArray:
        """Per lever-arm component: calibrated, and its posterior sigma under half its prior sigma (the
        survey's geometry, not the prior, determined it)."""
        post = np.sqrt(np.diag(self.lever_arm_covariance_m2))
        return self.lever_arm_estimated & (post < 0.5 * self.lever_arm_prior_sigma_m)

    def speed_scale(self, t_s: FloatArray | float) -> FloatArray:
        """The estimated correction to the profile at times ``t_s``: ``c(t) / c_ref``, by which every speed
        of the given profile is to be multiplied (1 when the speed was fixed)."""
        t = np.asarray(t_s, dtype=float)
        if self.knot_times_s.size == 0:
            return np.ones_like(t)
        if self.knot_times_s.size == 1:
            return np.full_like(t, self.sound_speed_knots_mps[0] / self.reference_speed_mps)
        return np.interp(t, self.knot_times_s, self.sound_speed_knots_mps) / self.reference_speed_mps

    def position_covariance_m2(self, j: int) -> FloatArray:
        """The (3, 3) covariance of transponder ``j``."""
        return self.covariance_m2[3 * j : 3 * j + 3, 3 * j : 3 * j + 3]

    def to_record(self) -> dict:
        """Plain JSON-ready data: per transponder the position (ENU and geodetic) and 1-sigma, the shift,
        the centre, the sound-speed correction, the lever arm, the noise and the exclusions."""
        sig = self.sigma_enu_m
        transponders = []
        for j, tid in enumerate(self.transponder_ids):
            e, n, u = (float(v) for v in self.positions_enu_m[j])
            entry = {
                "id": tid,
                "e_m": e,
                "n_m": n,
                "u_m": u,
                "sigma_e_m": float(sig[j, 0]),
                "sigma_n_m": float(sig[j, 1]),
                "sigma_u_m": float(sig[j, 2]),
                "lat_deg": None,
                "lon_deg": None,
                "h_m": None,
                "replies_used": int(np.sum(self.used & (self.reply_transponder == j))),
            }
            if self.positions_geodetic is not None:
                lat, lon, h = (float(v) for v in self.positions_geodetic[j])
                entry.update(lat_deg=lat, lon_deg=lon, h_m=h)
            transponders.append(entry)
        centre_sig = self.centre.sigma_enu_m
        return {
            "file": self.name,
            "solution": self.solution,
            "acoustic_model": self.acoustic_model,
            "epoch_utc": gnssa_epoch_utc(self.epoch_s + self.time_origin_unix_s - GPS_EPOCH_2020_UNIX_S),
            "epoch_s": float(self.epoch_s),
            "transponders": transponders,
            "covariance_m2": self.covariance_m2.tolist(),
            "shift_enu_m": None if self.shift_enu_m is None else [float(v) for v in self.shift_enu_m],
            "shift_covariance_m2": None
            if self.shift_covariance_m2 is None
            else self.shift_covariance_m2.tolist(),
            "centre_enu_m": [float(v) for v in self.centre.position_enu_m],
            "centre_sigma_enu_m": [float(v) for v in centre_sig],
            "reference_speed_mps": float(self.reference_speed_mps),
            "sound_speed_mps": float(self.sound_speed_mps),
            "speed_correction_ppm": float(self.speed_correction_ppm),
            "knot_times_s": [float(v) for v in self.knot_times_s],
            "sound_speed_knots_mps": [float(v) for v in self.sound_speed_knots_mps],
            "sound_speed_knot_sigma_mps": [float(v) for v in self.sound_speed_knot_sigma_mps],
            "gradient_e_per_km": float(self.gradient_per_km[0]),
            "gradient_n_per_km": float(self.gradient_per_km[1]),
            "lever_arm_body_m": [float(v) for v in self.lever_arm_body_m],
            "lever_arm_sigma_m": [float(v) for v in np.sqrt(np.diag(self.lever_arm_covariance_m2))],
            "lever_arm_covariance_m2": self.lever_arm_covariance_m2.tolist(),
            "lever_arm_estimated": bool(self.lever_arm_estimated),
            "lever_arm_prior_sigma_m": [float(v) for v in self.lever_arm_prior_sigma_m],
            "lever_arm_determined": [bool(v) for v in self.lever_arm_determined],
            "replies_used": int(self.used.sum()),
            "replies_excluded": len(self.exclusions),
            "exclusions": [x.to_record() for x in self.exclusions],
            "iterations": [it.to_record() for it in self.iterations],
            "residual_rms_m": float(self.residual_rms_m),
            "sigma_path_m": float(self.sigma_path_m),
            "beta_m": float(self.beta_m),
            "converged": bool(self.converged),
            "status": self.status,
            "model_tests": [t.to_record() for t in self.model_tests],
        }


# --------------------------------------------------------------------------------------------------
# the measurement model


@dataclass(slots=True)
class _Acoustics:
    """Travel-time model state of one solve: per-reply slowness weights and frozen bending corrections."""

    model: str
    c_ref: float
    surface_m: float
    profile: SoundSpeedProfile | None
    fixed_slowness: FloatArray | None  # (J,) harmonic model
    delta_tx_s: FloatArray  # (m,)
    delta_rx_s: FloatArray  # (m,)
    tables: list[BendingTable | None] = field(default_factory=list)


@dataclass(slots=True)
class ArrayProblem:
    """The whitened least-squares model of one array survey (a :class:`NormalModel` of batch 1).

    State layout (see :attr:`layout`): positions (``3J``) or the shift (3), gradient (2), lever arm (3),
    knots (K). The first :attr:`first_knot` columns of the Jacobian are dense (every reply touches its
    transponder's position or the shift, the gradient and the lever arm); the knot columns are not: the
    hat basis puts each reply on two neighbouring knots, so a reply's knot row is two numbers at the
    columns ``knot_index, knot_index + 1``. The solver is therefore given the normal equations formed
    from that structure (:meth:`normal_equations`: a dense block by BLAS, the knot block and the cross
    terms summed by ``np.bincount`` over the knot indices) instead of the dense ``(n S, d)`` Jacobian,
    whose ``J^T J`` with ~170 knot columns cost most of a solve; :meth:`evaluate` still gives the dense
    whitened Jacobian, the reference the structured form is tested against.
    """

    survey: GnssaArraySurvey
    twtt_s: FloatArray  # (m,) turn-around removed
    knot_index: IntArray  # (m,) first of the two knots of each reply's hat pair
    knot_weight: FloatArray  # (m, 2) hat-basis weights of knots knot_index, knot_index + 1
    n_knots: int
    geometry: FloatArray | None  # (J, 3) for the common shift
    acoustics: _Acoustics
    n_pos: int
    gradient: bool
    lever: bool
    mask: BoolArray  # (m,)
    slots: IntArray  # (n, S) reply index or -1
    whiten: FloatArray  # (n, S, S) inverse Cholesky factors
    _cache: dict = field(default_factory=dict)

    def invalidate(self) -> None:
        """Forget the cached evaluations (after the mask, the whitening or the bending changed)."""
        for key in ("key", "model_key", "lin_key"):
            self._cache.pop(key, None)

    def fixed(self, key: str) -> FloatArray:
        """Arrays that do not change during the solve, computed once (rotations per reply, one-hot)."""
        if key not in self._cache:
            s = self.survey
            if key == "tx_rotation":
                self._cache[key] = s.transmit_rotation[s.reply_ping]
            elif key == "rows":
                self._cache[key] = np.arange(s.n_replies)[:, None]
            elif key == "cols":
                self._cache[key] = 3 * s.reply_transponder[:, None] + np.arange(3)[None, :]
            elif key == "valid":
                self._cache[key] = self.slots >= 0
            elif key == "slot_index":
                self._cache[key] = np.where(self.slots >= 0, self.slots, 0)
            elif key == "knot_cols":
                # (n, 2 S): the knot columns of each ping's slots (padding slots carry zero values)
                pair = self.knot_index[:, None] + np.array([0, min(1, self.n_knots - 1)])
                self._cache[key] = pair[self.fixed("slot_index")].reshape(self.slots.shape[0], -1)
        return self._cache[key]

    @property
    def batch_size(self) -> int:
        return 1

    @property
    def col_gradient(self) -> int:
        return self.n_pos

    @property
    def col_lever(self) -> int:
        return self.n_pos + 2 * int(self.gradient)

    @property
    def first_knot(self) -> int:
        return self.col_lever + 3 * int(self.lever)

    def positions(self, x: FloatArray) -> FloatArray:
        """Transponder positions ``(J, 3)`` of the state ``x (d,)``."""
        if self.geometry is not None:
            return self.geometry + x[:3]
        return x[: self.n_pos].reshape(-1, 3)

    def lever_arm(self, x: FloatArray) -> FloatArray:
        return x[self.col_lever : self.col_lever + 3] if self.lever else self.survey.lever_arm_body_m

    def speed(self, x: FloatArray) -> FloatArray:
        """The sound-speed scale ``c(t)`` of every reply, m/s: the hat basis on its two knots."""
        if self.n_knots == 0:
            return np.full(self.twtt_s.shape, self.acoustics.c_ref)
        knots = x[self.first_knot :]
        if self.n_knots == 1:
            return self.knot_weight[:, 0] * knots[0]
        k = self.knot_index
        return self.knot_weight[:, 0] * knots[k] + self.knot_weight[:, 1] * knots[k + 1]

    def model(self, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Modelled TWTT ``(m,)`` (turn-around removed) and its dense Jacobian ``(m, d)`` (the reference
        form; the solver uses :meth:`model_parts`)."""
        model, dense, dspeed = self.model_parts(x)
        jac = np.zeros((model.size, x.size))
        jac[:, : self.first_knot] = dense
        if self.n_knots:
            rows = np.arange(model.size)
            k0 = self.first_knot
            jac[rows, k0 + self.knot_index] += dspeed * self.knot_weight[:, 0]
            if self.n_knots > 1:
                jac[rows, k0 + self.knot_index + 1] += dspeed * self.knot_weight[:, 1]
        return model, jac

    def model_parts(self, x: FloatArray, jacobian: bool = True) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Modelled TWTT ``(m,)`` (turn-around removed) and, when ``jacobian``, its derivatives: by the
        dense columns ``(m, first_knot)`` and by the speed scale of the reply ``(m,)`` (times the hat
        weights, the knot columns). Without ``jacobian`` the derivatives are empty: the cost of a trial
        step needs the model only, which is a third of the work."""
        s = self.survey
        ac = self.acoustics
        m = self.twtt_s.size
        k0 = self.first_knot
        j_of = s.reply_transponder
        pos = self.positions(x)[j_of]  # (m, 3)
        a, b = self.legs(x)
        jac_p = np.zeros((m, 3))
        jac_l = np.zeros((m, 3))
        time = np.zeros(m)
        for leg, rot, delta in (
            (a, self.fixed("tx_rotation"), ac.delta_tx_s),
            (b, s.receive_rotation, ac.delta_rx_s),
        ):
            diff = leg - pos
            length = np.sqrt(np.sum(diff * diff, axis=1))
            if ac.model == "straight":
                h = np.full(m, 1.0 / ac.c_ref)
            elif ac.model == "harmonic":
                assert ac.fixed_slowness is not None
                h = ac.fixed_slowness[j_of]
            else:
                assert ac.profile is not None
                za = ac.surface_m - leg[:, 2]
                zb = ac.surface_m - pos[:, 2]
                h = ac.profile.harmonic_slowness_spm(za, zb)
            time += length * h + delta
            if not jacobian:
                continue
            unit = diff / np.maximum(length, 1e-9)[:, None]  # d L / d leg = unit = - d L / d p
            d_p = -unit * h[:, None]
            d_leg = unit * h[:, None]
            if ac.model == "ray":
                dz = np.where(np.abs(zb - za) < 1e-6, 1e-6, zb - za)
                dh_dzb = (1.0 / ac.profile.speed_at_mps(np.nextafter(zb, -np.inf)) - h) / dz
                dh_dza = (h - 1.0 / ac.profile.speed_at_mps(za)) / dz
                d_p[:, 2] -= length * dh_dzb  # z_b = surface - U_p
                d_leg[:, 2] -= length * dh_dza
            jac_p += d_p
            if self.lever:
                jac_l += np.matmul(d_leg[:, None, :], rot)[:, 0, :]
        path = ac.c_ref * time
        jac_path = np.zeros((m, k0)) if jacobian else np.zeros((m, 0))
        jac_p *= ac.c_ref
        if self.lever and jacobian:
            jac_path[:, self.col_lever : self.col_lever + 3] = ac.c_ref * jac_l
        if self.gradient:
            g = 1e-3 * x[self.col_gradient : self.col_gradient + 2]
            factor = gradient_path_m2(pos, a) + gradient_path_m2(pos, b)
            path = path + factor @ g
            if jacobian:
                jac_path[:, self.col_gradient : self.col_gradient + 2] = 1e-3 * factor
                for leg, rot in ((a, self.fixed("tx_rotation")), (b, s.receive_rotation)):
                    gj = gradient_path_jacobian(pos, leg)
                    d_grad = g[0] * gj[:, 0, :] + g[1] * gj[:, 1, :]  # d/d transponder = -d/d leg
                    jac_p += d_grad
                    if self.lever:
                        cl = self.col_lever
                        jac_path[:, cl : cl + 3] -= np.matmul(d_grad[:, None, :], rot)[:, 0, :]
        c = self.speed(x)
        model = path / c
        if not jacobian:
            return model, jac_path, np.zeros(0)
        self._scatter_position(jac_path, jac_p)
        jac_path /= c[:, None]
        return model, jac_path, -path / (c * c)

    def _scatter_position(self, jac: FloatArray, d_p: FloatArray) -> None:
        """Put the per-reply position derivative ``(m, 3)`` in the state columns of its transponder."""
        if self.geometry is not None:
            jac[:, :3] = d_p
            return
        jac[self.fixed("rows"), self.fixed("cols")] = d_p

    def legs(self, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Transducer positions at transmit (per reply) and at receive, ``(m, 3)`` each."""
        if not self.lever:
            if "legs" not in self._cache:
                s = self.survey
                self._cache["legs"] = (s.transmit_enu_m()[s.reply_ping], s.receive_enu_m())
            return self._cache["legs"]
        s = self.survey
        lever = self.lever_arm(x)
        return s.transmit_enu_m(lever)[s.reply_ping], s.receive_enu_m(lever)

    def model_value(self, x: FloatArray) -> FloatArray:
        """The modelled TWTT ``(m,)`` at ``x``, the last one cached (the solver's accepted trial is the
        next linearization point and the outer loop's residual point)."""
        key = x.tobytes()
        if self._cache.get("model_key") != key:
            self._cache.update(model_key=key, model=self.model_parts(x, jacobian=False)[0])
        return self._cache["model"]

    def residual_m(self, x: FloatArray) -> FloatArray:
        """``c_ref (TWTT - tau - model)`` of every reply, metres."""
        return self.acoustics.c_ref * (self.twtt_s - self.model_value(x))

    def _whitened_residual(self, model: FloatArray) -> FloatArray:
        """Whitened residuals ``(n, S)`` of the used replies (zero rows for the others and padding)."""
        c0 = self.acoustics.c_ref
        r = np.where(self.mask, c0 * (self.twtt_s - model), 0.0)
        r_pad = np.where(self.fixed("valid"), r[self.fixed("slot_index")], 0.0)
        return np.matmul(self.whiten, r_pad[..., None])[..., 0]

    def residuals(self, x: FloatArray, rows: IntArray) -> FloatArray:
        """Whitened residuals ``(1, n S)`` without the Jacobian (the cost of a trial step)."""
        return self._whitened_residual(self.model_value(x[0])).reshape(1, -1)

    def linearize(self, x: FloatArray) -> _Linearization:
        """The whitened residuals and Jacobian at ``x (d,)`` in structured form (cached: the solver asks
        for the normal equations at the accepted point, then for the covariance at the same one)."""
        key = x.tobytes()
        if self._cache.get("lin_key") == key:
            return self._cache["lin"]
        model, dense, dspeed = self.model_parts(x)
        self._cache.update(model_key=key, model=model)
        c0 = self.acoustics.c_ref
        weight = np.where(self.mask, c0, 0.0)
        dense *= weight[:, None]
        valid, idx = self.fixed("valid"), self.fixed("slot_index")
        d_pad = dense[idx]
        d_pad *= valid[..., None]
        n, width = self.slots.shape
        if self.n_knots:
            k_raw = (dspeed[:, None] * self.knot_weight) * weight[:, None]  # (m, 2)
            k_pad = k_raw[idx] * valid[..., None]  # (n, S, 2)
            # whitened row s of ping n: sum over slots t of W[s, t] (slot t's two knot values)
            k_w = (self.whiten[..., None] * k_pad[:, None, :, :]).reshape(n, width, 2 * width)
        else:
            k_w = np.zeros((n, width, 0))
        lin = _Linearization(
            residual=self._whitened_residual(model),
            dense=np.matmul(self.whiten, d_pad),
            knot_value=k_w,
            knot_col=self.fixed("knot_cols") if self.n_knots else np.zeros((n, 0), dtype=np.int64),
            n_knots=self.n_knots,
        )
        self._cache.update(lin_key=key, lin=lin)
        return lin

    def normal_equations(self, x: FloatArray, rows: IntArray) -> NormalEquations:
        """``J^T J``, ``J^T r`` and the blind rows at ``x (1, d)`` from the structured Jacobian."""
        lin = self.linearize(x[0])
        normal, grad = lin.normal(np.zeros(lin.residual.shape[0], dtype=np.int64), 1)
        return NormalEquations(
            residual=lin.residual.reshape(1, -1), gradient=grad, normal=normal, blind=lin.blind()[None]
        )

    def evaluate(self, x: FloatArray, rows: IntArray) -> tuple[FloatArray, FloatArray]:
        """Whitened residuals ``(1, n S)`` and dense Jacobian ``(1, n S, d)`` (the reference form of
        :meth:`normal_equations`; the solver does not use it)."""
        lin = self.linearize(x[0])
        return lin.residual.reshape(1, -1), lin.dense_jacobian()[None]


@dataclass(frozen=True, slots=True, kw_only=True)
class _Linearization:
    """Whitened residuals and Jacobian of an :class:`ArrayProblem` at one state, per ping ``n`` and slot
    ``s``: ``J[(n, s)] = [dense[n, s], knots]`` with the knot part ``knot_value[n, s, a]`` at the columns
    ``first_knot + knot_col[n, a]`` (``a`` over the ping's slots times their two hat knots; repeated
    columns add up)."""

    residual: FloatArray  # (n, S)
    dense: FloatArray  # (n, S, k0)
    knot_value: FloatArray  # (n, S, 2 S)
    knot_col: IntArray  # (n, 2 S)
    n_knots: int

    def dense_jacobian(self) -> FloatArray:
        """The whitened Jacobian as a dense ``(n S, k0 + K)`` matrix."""
        n, width, k0 = self.dense.shape
        jac = np.zeros((n, width, k0 + self.n_knots))
        jac[..., :k0] = self.dense
        cols = np.broadcast_to(k0 + self.knot_col[:, None, :], self.knot_value.shape)
        ping = np.broadcast_to(np.arange(n)[:, None, None], cols.shape)
        slot = np.broadcast_to(np.arange(width)[None, :, None], cols.shape)
        np.add.at(jac, (ping, slot, cols), self.knot_value)
        return jac.reshape(n * width, -1)

    def blind(self) -> BoolArray:
        """Rows ``(n S,)`` with a zero Jacobian but a nonzero residual."""
        zero = np.all(self.dense == 0.0, axis=-1) & np.all(self.knot_value == 0.0, axis=-1)
        return (zero & (self.residual != 0.0)).reshape(-1)

    def normal(self, group: IntArray, n_groups: int) -> tuple[FloatArray, FloatArray]:
        """``J^T J`` ``(G, d, d)`` and ``J^T r`` ``(G, d)`` of the rows of each group of pings (``group
        (n,)`` in ``0 .. n_groups - 1``; one group: the whole survey; the jackknife's time blocks).

        Blockwise: the dense columns by BLAS; the knot-knot block and the dense-knot cross terms are the
        per-ping products of the few knot entries, summed into their columns by ``np.bincount`` (each
        ping's rows touch at most ``2 S`` knot columns, so this is linear in the pings instead of in
        pings times knots)."""
        k0 = self.dense.shape[2]
        kk = self.n_knots
        d = k0 + kk
        normal = np.zeros((n_groups, d, d))
        grad = np.zeros((n_groups, d))
        for g in range(n_groups):
            sel = slice(None) if n_groups == 1 else group == g
            dg = self.dense[sel].reshape(-1, k0)
            normal[g, :k0, :k0] = dg.T @ dg
            grad[g, :k0] = dg.T @ self.residual[sel].reshape(-1)
        if kk == 0:
            return normal, grad
        v, cols = self.knot_value, self.knot_col
        base = (group * kk)[:, None] + cols  # (n, 2S): group and knot column
        size = n_groups * kk
        cross = np.matmul(np.swapaxes(v, 1, 2), self.dense)  # (n, 2S, k0)
        flat = (base[..., None] * k0 + np.arange(k0)).reshape(-1)
        kd = np.bincount(flat, weights=cross.reshape(-1), minlength=size * k0).reshape(n_groups, kk, k0)
        prod = np.matmul(np.swapaxes(v, 1, 2), v)  # (n, 2S, 2S)
        pair = ((base[:, :, None] * kk) + cols[:, None, :]).reshape(-1)
        block = np.bincount(pair, weights=prod.reshape(-1), minlength=size * kk).reshape(n_groups, kk, kk)
        normal[:, k0:, :k0] = kd
        normal[:, :k0, k0:] = np.swapaxes(kd, 1, 2)
        normal[:, k0:, k0:] = 0.5 * (block + np.swapaxes(block, 1, 2))
        g_k = np.einsum("nsa,ns->na", v, self.residual)
        grad[:, k0:] = np.bincount(base.reshape(-1), weights=g_k.reshape(-1), minlength=size).reshape(
            n_groups, kk
        )
        return normal, grad


def _slots(ping: IntArray, n: int) -> IntArray:
    """``(n, S)`` table of the replies of each ping (``-1`` padding), ``S`` the most replies of a ping."""
    order = np.argsort(ping, kind="stable")
    counts = np.bincount(ping, minlength=n)
    width = max(int(counts.max()), 1)
    start = np.concatenate([[0], np.cumsum(counts)[:-1]])
    rank = np.arange(ping.size) - start[ping[order]]
    table = np.full((n, width), -1, dtype=np.int64)
    table[ping[order], rank] = order
    return table


def _whitening(problem: ArrayProblem, x: FloatArray, var_extra: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Inverse Cholesky factors of each ping's reply covariance (see the module docstring) and the
    marginal GNSS variance of each reply, m^2."""
    s = problem.survey
    pos = problem.positions(x)[s.reply_transponder]
    lever = problem.lever_arm(x)
    a = s.transmit_enu_m(lever)[s.reply_ping]
    b = s.receive_enu_m(lever)
    u_tx = (a - pos) / np.linalg.norm(a - pos, axis=1, keepdims=True)
    u_rx = (b - pos) / np.linalg.norm(b - pos, axis=1, keepdims=True)
    c_tx = s.transmit_antenna_cov_m2[s.reply_ping]
    var_tx = np.einsum("mi,mij,mj->m", u_tx, c_tx, u_tx)
    var_rx = np.einsum("mi,mij,mj->m", u_rx, s.receive_antenna_cov_m2, u_rx)
    slots = problem.slots
    valid = (slots >= 0) & problem.mask[np.where(slots >= 0, slots, 0)]
    idx = np.where(valid, slots, 0)
    v = np.where(valid[..., None], u_tx[idx], 0.0)  # (n, S, 3)
    cov = np.einsum("nsi,nij,ntj->nst", v, s.transmit_antenna_cov_m2, v)
    diag = np.where(valid, var_rx[idx] + var_extra[idx], 1.0)
    cov = cov + diag[..., None] * np.eye(slots.shape[1])
    chol = np.linalg.cholesky(cov)
    return np.linalg.inv(chol), var_tx + var_rx


def _tan_incidence(problem: ArrayProblem, x: FloatArray) -> FloatArray:
    s = problem.survey
    pos = problem.positions(x)[s.reply_transponder]
    a = s.transmit_enu_m(problem.lever_arm(x))[s.reply_ping]
    return np.hypot(a[:, 0] - pos[:, 0], a[:, 1] - pos[:, 1]) / np.maximum(a[:, 2] - pos[:, 2], 1e-3)


def _refresh_bending(problem: ArrayProblem, x: FloatArray, force: bool = False) -> None:
    """Rebuild a transponder's bending table when its depth moved by more than 0.5 m or its legs left the
    table's distances or transducer depths, and re-evaluate the frozen bending corrections at ``x``."""
    ac = problem.acoustics
    if ac.model != "ray" or ac.profile is None:
        return
    s = problem.survey
    pos = problem.positions(x)
    lever = problem.lever_arm(x)
    tx = s.transmit_enu_m(lever)
    rx = s.receive_enu_m(lever)
    za_all = ac.surface_m - np.concatenate([tx[:, 2], rx[:, 2]])
    top = (float(za_all.min()), float(za_all.max()))
    j_of = s.reply_transponder
    for j in range(pos.shape[0]):
        zb = ac.surface_m - pos[j, 2]
        table = ac.tables[j]
        sel = j_of == j
        if not sel.any():
            continue
        legs = np.concatenate([tx[s.reply_ping[sel]], rx[sel]])
        reach = float(np.max(np.hypot(legs[:, 0] - pos[j, 0], legs[:, 1] - pos[j, 1])))
        stale = table is None or abs(table.bottom_m - zb) > 0.5 or reach > table.horizontal_m[-1]
        if force or stale or top[0] < table.top_m[0] - 0.01 or top[1] > table.top_m[-1] + 0.01:
            ac.tables[j] = bending_table(ac.profile, zb, top, 1.2 * reach + 10.0)
    problem.invalidate()
    for leg, out in ((tx[s.reply_ping], ac.delta_tx_s), (rx, ac.delta_rx_s)):
        for j in range(pos.shape[0]):
            sel = j_of == j
            table = ac.tables[j]
            if not sel.any() or table is None:
                continue
            horiz = np.hypot(leg[sel, 0] - pos[j, 0], leg[sel, 1] - pos[j, 1])
            out[sel] = table.correction_s(ac.surface_m - leg[sel, 2], horiz)


# --------------------------------------------------------------------------------------------------
# the solve


def localize_gnssa_array(
    survey: GnssaArraySurvey,
    options: GnssaArrayOptions | None = None,
    *,
    profile: SoundSpeedProfile | None = None,
    geometry: ArrayGeometry | None = None,
) -> GnssaArrayResult:
    """Localize a transponder array from one GNSS-A survey (see the module docstring).

    Parameters
    ----------
    survey : GnssaArraySurvey
    options : GnssaArrayOptions, optional
        Defaults: oceanloc's (sound speed, gradient, noise estimated, ray tracing with a profile).
    profile : SoundSpeedProfile, optional
        The survey's sound-speed profile (needed by the ``harmonic`` and ``ray`` models).
    geometry : ArrayGeometry, optional
        The array's geometry from a prior campaign (needed by the ``common_shift`` solution; also the
        starting positions of ``independent`` when the survey has no approximate positions).

    Returns
    -------
    GnssaArrayResult

    Raises
    ------
    ConfigError
        Settings that do not fit the survey (no profile for the ``ray`` model, no geometry for the shift).
    DataError
        A survey that cannot be solved reliably (too many gross errors, too few replies).
    """
    opts = options or GnssaArrayOptions()
    setup = _setup(survey, opts, profile, geometry)
    problem, prior = setup.problem, setup.prior
    m = survey.n_replies
    used = setup.candidates.copy()
    n_candidates = int(used.sum())
    max_out = int(opts.max_outlier_fraction * n_candidates)
    sigma_path, beta = opts.sigma_path_m, 0.0
    x = prior.mean[0].copy()
    map_opts = MapOptions(delta_min_m=1e-7, max_iterations=100, surface_z_m=None)
    exclusions: list[ReplyExclusion] = []
    iterations: list[ArrayIteration] = []
    result = None
    resid = np.zeros(m)
    sigma = np.ones(m)
    for rnd in range(opts.max_rounds):
        # three noise re-estimations on the first round, one per round after it
        for _ in range(3 if opts.estimate_noise and rnd == 0 else 1):
            x_before = x.copy()
            _refresh_bending(problem, x, force=rnd == 0 and not iterations)
            tan_inc = _tan_incidence(problem, x)
            extra = sigma_path**2 + (beta * tan_inc) ** 2
            problem.mask = used
            problem.whiten, gnss_var = _whitening(problem, x, extra)
            problem.invalidate()
            result = solve_map(problem, prior, map_opts, initial=x[None, :])
            x = result.estimate[0]
            resid = problem.residual_m(x)
            if opts.estimate_noise:
                sigma_path, beta = _variance_components(
                    resid[used], gnss_var[used], tan_inc[used], opts.range_dependent_weights
                )
            change = float(np.max(np.abs(problem.positions(x) - problem.positions(x_before))))
            iterations.append(
                ArrayIteration(
                    round=rnd,
                    replies_used=int(used.sum()),
                    sigma_path_m=float(sigma_path),
                    beta_m=float(beta),
                    cost=float(result.cost[0]),
                    map_iterations=int(result.iterations[0]),
                    position_change_m=change,
                    excluded=0,
                )
            )
        tan_inc = _tan_incidence(problem, x)
        sigma = np.sqrt(gnss_var + sigma_path**2 + (beta * tan_inc) ** 2)
        remove = _outliers(opts, resid, sigma, used, max_out - (n_candidates - int(used.sum())))
        if remove.size == 0:
            break
        for o in remove:
            exclusions.append(_exclusion(survey, int(o), resid, sigma, opts))
        used = used.copy()
        used[remove] = False
        iterations[-1] = dataclasses.replace(iterations[-1], excluded=int(remove.size))
    assert result is not None

    def final_solve(setup: _Setup, x: FloatArray, sigma_path: float, beta: float) -> tuple:
        """Bending corrections at ``x``, one solve; the residuals and their sigmas."""
        problem = setup.problem
        _refresh_bending(problem, x)
        problem.whiten, gnss_var = _whitening(
            problem, x, sigma_path**2 + (beta * _tan_incidence(problem, x)) ** 2
        )
        problem.invalidate()
        result = solve_map(problem, setup.prior, map_opts, initial=x[None, :])
        x = result.estimate[0]
        resid = problem.residual_m(x)
        sigma = np.sqrt(gnss_var + sigma_path**2 + (beta * _tan_incidence(problem, x)) ** 2)
        return result, x, resid, sigma, gnss_var

    result, x, resid, sigma, gnss_var = final_solve(setup, x, sigma_path, beta)
    tests: tuple[ModelTest, ...] = ()
    if opts.select_model:

        def refit(smaller: _Setup, x0: FloatArray) -> tuple[MapResult, FloatArray]:
            nonlocal sigma_path, beta, resid, sigma
            out = final_solve(smaller, x0, sigma_path, beta)
            if opts.estimate_noise:  # the noise of the smaller model, then its solve
                sigma_path, beta = _variance_components(
                    out[2][used],
                    out[4][used],
                    _tan_incidence(smaller.problem, out[1])[used],
                    opts.range_dependent_weights,
                )
                out = final_solve(smaller, out[1], sigma_path, beta)
            resid, sigma = out[2], out[3]
            return out[0], out[1]

        setup, x, result, tests = select_model(setup, x, result, opts, refit)
        problem = setup.problem
    left = used & (np.abs(resid) > opts.gross_error_m)
    if left.any() and opts.prescreen:
        worst = int(np.argmax(np.where(left, np.abs(resid), 0.0)))
        raise DataError(
            f"{survey.path or survey.name}: {int(left.sum())} used replies still have |residual| > "
            f"{opts.gross_error_m:g} m (reply {worst}: {resid[worst]:+.1f} m): the survey cannot be solved "
            "reliably; check its travel times, turn-around delays and transponder order"
        )
    if opts.gnss_common_mode is None:
        serial = serial_correlation_test(survey, resid, sigma, used, opts.serial_lags, opts.selection_alpha)
        tests = (*tests, serial)
        opts = dataclasses.replace(opts, gnss_common_mode=serial.kept)
    out = _result(
        survey, opts, setup, result, x, used, resid, sigma, sigma_path, beta, exclusions, iterations
    )
    return dataclasses.replace(out, model_tests=tests)


def select_model(
    setup: _Setup,
    x: FloatArray,
    result: MapResult,
    opts: GnssaArrayOptions,
    refit: Callable[[_Setup, FloatArray], tuple[MapResult, FloatArray]],
) -> tuple[_Setup, FloatArray, MapResult, tuple[ModelTest, ...]]:
    """Drop the sound-speed and gradient parameters a survey does not support (nested models compared by
    their likelihood ratio against Schwarz's criterion, BIC, or a chi-square level).

    Why: each parameter group costs precision whether or not the ocean needs it. On a short drift-free
    survey the horizontal gradient, nearly collinear with the horizontal shift when the platform circles
    the array, multiplies the horizontal scatter (seeded GNATSS oracle surveys of 300 pings: 14 and 22 mm
    RMS east and north with it, 3 and 2 mm without), and the speed's knots and scale trade with depth.
    A drifting or stratified ocean leaves a large, unmistakable misfit when they are removed, so the
    test keeps them there. Tested in order, on the fit of the bigger model:

    1. ``gradient`` (2 parameters: ``g = 0``) and ``sound_speed_variation`` (``K - 1``: all knots equal),
       each from the full model;
    2. ``sound_speed_scale`` (1: the constant speed equal to ``c_ref``, the profile as given), on the
       model refitted without what step 1 dropped, only when the speed is one constant and the profile's
       depth zero is given (``surface_height_m``; GNATSS's configuration gives it as the geoid). A
       defaulted sea surface is off by the antenna's height above the water, an error nearly collinear
       with the depth that no test can see but the scale absorbs, so then the scale stays.

    The statistic of a linear constraint ``D x = d`` is ``(D x - d)^T (D P D^T)^{-1} (D x - d)``, ``P``
    the posterior covariance: for the linearized (Gauss-Newton) model this is exactly the increase of
    the MAP cost ``-2 log p`` when the constraint is imposed (the likelihood-ratio statistic in its Wald
    form). When the parameters are truly absent it is chi-square with ``dof`` degrees of freedom, or
    stochastically smaller (the prior shrinks the estimate). The bigger model is kept when the statistic
    exceeds ``dof ln n`` (``n`` used replies; ``selection_criterion="bic"``, the default): the Schwarz
    approximation of the two models' evidence ratio, consistent as ``n`` grows, and a higher bar than a
    1 % chi-square test (``"lr"``: 9.2 for the gradient against 13.6 at 900 replies). The higher bar is
    chosen because the gradient and the knots are weakly identified against the position: a false
    detection costs centimetres (on one of 12 drift-free oracle surveys a 1 % test kept a spurious
    gradient, 1e-5 per km, and moved the centre by 3.7 cm), while a real drift or gradient
    that matters at the centimetre level gives statistics in the hundreds (about 9000 for the oracle's
    drift; 14 to 680 on the La Jolla surveys). Each drop is followed by ``refit(smaller_setup, x)`` (the
    noise re-estimated, one solve; the outlier decisions of the full model are kept).

    Returns
    -------
    setup, x, result, tests
        The selected model, its estimate and solve, and the tests (:class:`ModelTest`) in order.
    """
    n_used = int(setup.problem.mask.sum())

    def threshold(dof: int) -> float:
        if opts.selection_criterion == "bic":
            return dof * float(np.log(max(n_used, 2)))
        return float(_chi2().ppf(1.0 - opts.selection_alpha, dof))

    problem = setup.problem
    cov = result.covariance[0]
    c_ref = problem.acoustics.c_ref
    tests: list[ModelTest] = []
    keep_gradient = problem.gradient
    speed = "knots" if problem.n_knots > 1 else ("constant" if problem.n_knots == 1 else "fixed")
    if problem.gradient:
        cols = np.arange(problem.col_gradient, problem.col_gradient + 2)
        t = _lr_test("gradient", np.eye(2), x[cols], cov[np.ix_(cols, cols)], threshold, "per_km")
        tests.append(dataclasses.replace(t, sigma=tuple(np.sqrt(np.diag(cov)[cols]))))
        keep_gradient = t.kept
    k0 = problem.first_knot
    if problem.n_knots > 1:
        knots = x[k0:]
        diff = np.diff(np.eye(problem.n_knots), axis=0)  # (K - 1, K): consecutive differences
        t = _lr_test("sound_speed_variation", diff, knots, cov[k0:, k0:], threshold, "mps")
        span = float(knots.max() - knots.min())
        tests.append(
            dataclasses.replace(t, estimate=(span,), sigma=(float(np.sqrt(np.mean(np.diag(cov)[k0:]))),))
        )
        if not t.kept:
            speed = "constant"
    if keep_gradient != problem.gradient or (problem.n_knots > 1 and speed == "constant"):
        setup, x = _reduced(setup, x, keep_gradient, speed, opts.sigma_sound_speed_mps)
        result, x = refit(setup, x)
    problem = setup.problem
    if problem.n_knots == 1 and opts.surface_height_m is not None:
        k0 = problem.first_knot
        cov = result.covariance[0]
        t = _lr_test("sound_speed_scale", np.eye(1), x[k0:] - c_ref, cov[k0:, k0:], threshold, "ppm")
        tests.append(
            dataclasses.replace(
                t, estimate=(1e6 * (x[k0] / c_ref - 1.0),), sigma=(1e6 * float(np.sqrt(cov[k0, k0])) / c_ref,)
            )
        )
        if not t.kept:
            setup, x = _reduced(setup, x, keep_gradient, "fixed", opts.sigma_sound_speed_mps)
            result, x = refit(setup, x)
    return setup, x, result, tuple(tests)


def serial_correlation_test(
    survey: GnssaArraySurvey,
    residual_m: FloatArray,
    sigma_m: FloatArray,
    used: BoolArray,
    lags: int = 10,
    alpha: float = 0.01,
) -> ModelTest:
    """Ljung-Box portmanteau test (Ljung and Box 1978) of the normalized residuals ``r / sigma`` of each
    transponder in time order: ``Q = sum_j n_j (n_j + 2) sum_{k=1..L} rho_jk^2 / (n_j - k)`` against the
    chi-square quantile ``1 - alpha`` with ``L`` degrees of freedom per transponder (those with more than
    ``_SERIAL_MIN_REPLIES`` used replies). ``kept`` (the residuals are serially correlated, or too few
    replies to tell) decides the GNSS common-mode
    term: GNSS errors correlated over minutes to hours, as real kinematic solutions are, leave
    correlated residuals and do not average out over the survey; white ones do, and the formal covariance
    already holds them."""
    q, dof = 0.0, 0
    for j in range(survey.n_transponders):
        sel = np.flatnonzero(used & (survey.reply_transponder == j))
        n = sel.size
        if n < max(_SERIAL_MIN_REPLIES, 4 * lags):
            continue
        order = sel[np.argsort(survey.t_transmit_s[survey.reply_ping[sel]], kind="stable")]
        z = residual_m[order] / sigma_m[order]
        z = z - z.mean()
        denom = float(z @ z)
        if denom <= 0.0:
            continue
        k = np.arange(1, lags + 1)
        rho = np.array([z[:-lag] @ z[lag:] for lag in k]) / denom
        q += float(n * (n + 2) * np.sum(rho**2 / (n - k)))
        dof += lags
    if dof == 0:  # too few replies to tell: keep the conservative term
        return ModelTest(
            name="gnss_serial_correlation", dof=0, statistic=float("nan"), threshold=float("nan"),
            p_value=float("nan"), kept=True, estimate=(), sigma=(), unit="",
        )  # fmt: skip
    threshold = float(_chi2().ppf(1.0 - alpha, dof))
    return ModelTest(
        name="gnss_serial_correlation",
        dof=dof,
        statistic=q,
        threshold=threshold,
        p_value=float(_chi2().sf(q, dof)),
        kept=q > threshold,
        estimate=(),
        sigma=(),
        unit="",
    )


def _chi2() -> Any:
    """``scipy.stats.chi2``, imported when first needed (the command line starts without scipy)."""
    from scipy import stats

    return stats.chi2


def _lr_test(
    name: str,
    constraint: FloatArray,
    value: FloatArray,
    cov: FloatArray,
    threshold: Callable[[int], float],
    unit: str,
) -> ModelTest:
    """The statistic ``(D v)^T (D C D^T)^{-1} (D v)`` of the constraint ``D v = 0`` against
    ``threshold(dof)`` (see :func:`select_model`)."""
    dv = constraint @ value
    dof = int(constraint.shape[0])
    stat = float(dv @ np.linalg.solve(constraint @ cov @ constraint.T, dv))
    limit = float(threshold(dof))
    return ModelTest(
        name=name,
        dof=dof,
        statistic=stat,
        threshold=limit,
        p_value=float(_chi2().sf(stat, dof)),
        kept=stat > limit,
        estimate=tuple(float(v) for v in value),
        sigma=(),
        unit=unit,
    )


def _reduced(
    setup: _Setup, x: FloatArray, gradient: bool, speed: str, sigma_speed_mps: float
) -> tuple[_Setup, FloatArray]:
    """The nested model without the gradient (``gradient`` False) and with the speed ``knots`` as they
    are, one ``constant`` (at the mean speed of the used replies, prior ``N(c_ref, sigma_speed^2)``) or
    ``fixed`` at ``c_ref``; the state ``x`` mapped onto it."""
    p = setup.problem
    cols = list(range(p.n_pos))
    if p.gradient and gradient:
        cols += [p.col_gradient, p.col_gradient + 1]
    if p.lever:
        cols += list(range(p.col_lever, p.col_lever + 3))
    k0 = p.first_knot
    if speed == "knots":
        cols += list(range(k0, k0 + p.n_knots))
    idx = np.asarray(cols)
    mean, cov = setup.prior.mean[0][idx], setup.prior.cov[np.ix_(idx, idx)]
    x_new = x[idx]
    m = p.twtt_s.size
    knot_index, knot_weight, n_knots, knots_s = p.knot_index, p.knot_weight, p.n_knots, setup.knots_s
    if speed == "constant":
        c_mean = float(np.mean(p.speed(x)[p.mask]))
        x_new = np.append(x_new, c_mean)
        mean = np.append(mean, p.acoustics.c_ref)
        cov = np.pad(cov, ((0, 1), (0, 1)))
        cov[-1, -1] = sigma_speed_mps**2
        knot_index, knot_weight = np.zeros(m, dtype=np.int64), np.stack([np.ones(m), np.zeros(m)], axis=1)
        n_knots, knots_s = 1, setup.knots_s[:1]
    elif speed == "fixed":
        knot_index, knot_weight = np.zeros(m, dtype=np.int64), np.zeros((m, 2))
        n_knots, knots_s = 0, np.zeros(0)
    problem = dataclasses.replace(
        p,
        gradient=p.gradient and gradient,
        knot_index=knot_index,
        knot_weight=knot_weight,
        n_knots=n_knots,
        _cache={},
    )
    prior = GaussianPrior(mean=mean[None, :], cov=cov)
    return dataclasses.replace(setup, problem=problem, prior=prior, knots_s=knots_s), x_new


def _outliers(
    opts: GnssaArrayOptions, resid: FloatArray, sigma: FloatArray, used: BoolArray, room: int
) -> IntArray:
    """Replies to exclude this round (largest first), at most ``room``."""
    if room <= 0:
        return np.zeros(0, dtype=np.int64)
    if opts.outlier_rule == "residual":
        score = np.where(used, np.abs(resid), 0.0)
        bad = np.flatnonzero(score > opts.residual_limit_m)
        per_round = bad.size
    else:
        score = np.where(used, np.abs(resid) / sigma, 0.0)
        bad = np.flatnonzero(score > opts.outlier_threshold)
        per_round = 1 + int(used.sum()) // 1000
    order = bad[np.argsort(-score[bad], kind="stable")]
    return order[: min(per_round, room)]


def _exclusion(
    survey: GnssaArraySurvey, o: int, resid: FloatArray, sigma: FloatArray, opts: GnssaArrayOptions
) -> ReplyExclusion:
    r = float(resid[o])
    if opts.outlier_rule == "residual":
        reason = f"outlier: |residual| {abs(r):.3f} m > limit {opts.residual_limit_m:g} m"
    else:
        kind = "gross error" if abs(r) > opts.gross_error_m else "outlier"
        reason = (
            f"{kind}: |residual| {abs(r):.3f} m = {abs(r) / sigma[o]:.1f} sigma"
            f" > {opts.outlier_threshold:g} sigma"
        )
    ping = int(survey.reply_ping[o])
    return ReplyExclusion(
        reply=o,
        ping=ping,
        transponder=survey.transponder_ids[int(survey.reply_transponder[o])],
        line=int(survey.line[o]),  # type: ignore[index]
        time_s=float(survey.t_transmit_s[ping]),
        reason=reason,
        residual_m=r,
    )


@dataclass(slots=True)
class _Setup:
    problem: ArrayProblem
    prior: GaussianPrior
    candidates: BoolArray
    knots_s: FloatArray
    exclusions: list[ReplyExclusion]
    lever_in_state: bool


def _setup(
    survey: GnssaArraySurvey,
    opts: GnssaArrayOptions,
    profile: SoundSpeedProfile | None,
    geometry: ArrayGeometry | None,
) -> _Setup:
    s = survey
    n_t = s.n_transponders
    model = opts.acoustic_model
    if model == "auto":
        model = "ray" if profile is not None else "straight"
    if model in ("ray",) and profile is None:
        raise ConfigError("the ray acoustic model needs a sound-speed profile")
    if model == "harmonic" and profile is None and opts.transponder_speeds_mps is None:
        raise ConfigError("the harmonic acoustic model needs a sound-speed profile or transponder_speeds_mps")
    if opts.solution == "common_shift" and geometry is None:
        raise ConfigError("the common_shift solution needs the array geometry of a prior campaign")
    if geometry is not None and geometry.positions_enu_m.shape != (n_t, 3):
        raise ConfigError(f"the array geometry must give ({n_t}, 3) positions")
    if opts.transponder_speeds_mps is not None and len(opts.transponder_speeds_mps) != n_t:
        raise ConfigError(
            f"transponder_speeds_mps needs {n_t} values, got {len(opts.transponder_speeds_mps)}"
        )
    twtt = s.twtt_s - s.turnaround_s[s.reply_transponder]
    if np.any(twtt <= 0.0):
        i = int(np.argmax(twtt <= 0.0))
        raise DataError(f"{s.path or s.name}: reply {i}: the turn-around delay exceeds the travel time")
    tx = s.transmit_enu_m()
    rx = s.receive_enu_m()
    surface = float(np.mean(tx[:, 2])) if opts.surface_height_m is None else float(opts.surface_height_m)
    counts = s.replies_per_transponder
    if np.any(counts == 0):
        missing = ", ".join(s.transponder_ids[j] for j in np.flatnonzero(counts == 0))
        raise DataError(f"{s.path or s.name}: no reply from transponder(s) {missing}")
    # first speed guess, robust first fit per transponder
    c_guess = opts.sound_speed_mps or (
        float(profile.harmonic_mean_mps(0.0, float(np.median(0.5 * 1500.0 * twtt))))
        if profile is not None
        else 1500.0
    )
    gross = np.zeros(s.n_replies, dtype=bool)
    fits = np.zeros((n_t, 3))
    exclusions: list[ReplyExclusion] = []
    for j in range(n_t):
        sel = np.flatnonzero(s.reply_transponder == j)
        a, b, t = tx[s.reply_ping[sel]], rx[sel], twtt[sel]
        if sel.size >= 8:
            # the robust fit on at most _ROBUST_FIT_REPLIES replies spread over the survey; residuals of all
            sub = np.arange(0, sel.size, max(1, sel.size // _ROBUST_FIT_REPLIES))
            fit = robust_first_fit(a[sub], b[sub], t[sub], c_guess, surface)
            fits[j] = fit.position_enu_m
            if opts.prescreen:
                p_fit = fit.position_enu_m
                resid_all = (
                    c_guess * t - np.linalg.norm(a - p_fit, axis=1) - np.linalg.norm(b - p_fit, axis=1)
                )
                r = resid_all - np.median(fit.residual_m)
                thr = max(opts.prescreen_sigmas * fit.sigma_m, opts.gross_error_m)
                bad = np.abs(r) > thr
                if bad.sum() > opts.max_gross_fraction * sel.size:
                    raise DataError(
                        f"{s.path or s.name}: {int(bad.sum())} of {sel.size} replies of transponder "
                        f"{s.transponder_ids[j]} have travel times no single position explains "
                        f"(|residual| > {thr:.2f} m at a robust first fit), more than the "
                        f"{100.0 * opts.max_gross_fraction:.0f} % allowed: check the travel times, their "
                        "units, the turn-around delays and the transponder order"
                    )
                gross[sel[bad]] = True
                for k in np.flatnonzero(bad):
                    o = int(sel[k])
                    exclusions.append(
                        ReplyExclusion(
                            reply=o,
                            ping=int(s.reply_ping[o]),
                            transponder=s.transponder_ids[j],
                            line=int(s.line[o]),  # type: ignore[index]
                            time_s=float(s.t_transmit_s[s.reply_ping[o]]),
                            reason=f"gross error (pre-screen): |residual| {abs(r[k]):.1f} m at the robust "
                            f"first fit > {thr:.2f} m",
                            residual_m=float(r[k]),
                        )
                    )
        else:
            i = int(np.argmin(t))
            fits[j] = a[i] - np.array([0.0, 0.0, 0.5 * c_guess * t[i]])
    if s.approx_positions_enu_m is not None:
        start = s.approx_positions_enu_m.copy()
    elif geometry is not None and opts.solution == "independent":
        start = geometry.positions_enu_m.copy()
    else:
        start = fits
    # reference speed and fixed per-transponder slowness
    depths = surface - start[:, 2]
    if opts.sound_speed_mps is not None:
        c_ref = float(opts.sound_speed_mps)
    elif profile is not None:
        c_ref = float(profile.harmonic_mean_mps(0.0, float(np.mean(depths))))
    else:
        c_ref = 1500.0
    fixed = None
    if model == "harmonic":
        if opts.transponder_speeds_mps is not None:
            fixed = 1.0 / np.asarray(opts.transponder_speeds_mps, dtype=float)
        else:
            assert profile is not None
            fixed = profile.harmonic_slowness_spm(np.zeros(n_t), depths)
    acoustics = _Acoustics(
        model=model,
        c_ref=c_ref,
        surface_m=surface,
        profile=profile,
        fixed_slowness=fixed,
        delta_tx_s=np.zeros(s.n_replies),
        delta_rx_s=np.zeros(s.n_replies),
        tables=[None] * n_t,
    )
    # knots on the replies' mid-times
    t_mid = 0.5 * (s.t_transmit_s[s.reply_ping] + s.t_receive_s)
    knots = _knots(t_mid, opts, s.n_pings)
    knot_index, knot_weight = hat_pairs(hat_basis(t_mid, knots))
    lever_in_state = opts.estimate_lever_arm or bool(np.any(s.lever_arm_cov_m2 != 0.0))
    shift = opts.solution == "common_shift"
    n_pos = 3 if shift else 3 * n_t
    problem = ArrayProblem(
        survey=s,
        twtt_s=twtt,
        knot_index=knot_index,
        knot_weight=knot_weight,
        n_knots=knots.size,
        geometry=geometry.positions_enu_m if shift and geometry is not None else None,
        acoustics=acoustics,
        n_pos=n_pos,
        gradient=opts.estimate_gradient,
        lever=lever_in_state,
        mask=~gross,
        slots=_slots(s.reply_ping, s.n_pings),
        whiten=np.zeros(0),
    )
    k0 = problem.first_knot
    dim = k0 + knots.size
    mean = np.zeros(dim)
    var = np.zeros(dim)
    if shift:
        assert geometry is not None
        mean[:3] = np.median(fits - geometry.positions_enu_m, axis=0)
    else:
        mean[:n_pos] = start.reshape(-1)
    var[:n_pos] = opts.sigma_position_prior_m**2
    cov = np.zeros((dim, dim))
    if opts.estimate_gradient:
        var[problem.col_gradient : problem.col_gradient + 2] = opts.sigma_gradient_per_km**2
    cov[np.diag_indices(k0)] = var[:k0]
    if lever_in_state:
        cl = problem.col_lever
        mean[cl : cl + 3] = s.lever_arm_body_m
        lever_cov = s.lever_arm_cov_m2
        if opts.estimate_lever_arm and not np.any(lever_cov != 0.0):
            lever_cov = opts.sigma_lever_arm_m**2 * np.eye(3)
        cov[cl : cl + 3, cl : cl + 3] = lever_cov
    if knots.size:
        mean[k0:] = c_ref
        lag = np.abs(knots[:, None] - knots[None, :])
        cov[k0:, k0:] = opts.sigma_sound_speed_mps**2 * np.exp(-lag / opts.sound_speed_correlation_s)
    return _Setup(
        problem=problem,
        prior=GaussianPrior(mean=mean[None, :], cov=cov),
        candidates=~gross,
        knots_s=knots,
        exclusions=exclusions,
        lever_in_state=lever_in_state,
    )


def _knots(t_s: FloatArray, opts: GnssaArrayOptions, n_pings: int) -> FloatArray:
    """Sound-speed knot times: at most ``knot_spacing_s`` apart, at least ``min_pings_per_knot`` pings
    per segment on average."""
    if not opts.estimate_sound_speed:
        return np.zeros(0)
    t0, t1 = float(t_s.min()), float(t_s.max())
    if opts.knot_spacing_s is None or t1 <= t0:
        return np.array([t0])
    spacing = max(opts.knot_spacing_s, (t1 - t0) * opts.min_pings_per_knot / max(n_pings, 1))
    n_seg = max(1, round((t1 - t0) / spacing))
    return np.linspace(t0, t1, n_seg + 1)


def hat_pairs(basis: FloatArray) -> tuple[IntArray, FloatArray]:
    """The two nonzero columns of each row of a hat basis ``(m, K)``: the first index ``(m,)`` and the
    weights ``(m, 2)`` at it and the next column, read from the basis itself (so ``speed`` equals the dense
    product). A hat basis row is nonzero on at most two neighbouring knots; with one knot the second
    weight is 0 (and its column repeats the first)."""
    m, kk = basis.shape
    if kk == 0:
        return np.zeros(m, dtype=np.int64), np.zeros((m, 2))
    if kk == 1:
        return np.zeros(m, dtype=np.int64), np.stack([basis[:, 0], np.zeros(m)], axis=1)
    first = np.clip(np.argmax(basis != 0.0, axis=1), 0, kk - 2)
    rows = np.arange(m)
    weight = np.stack([basis[rows, first], basis[rows, first + 1]], axis=1)
    if not np.allclose(weight.sum(axis=1), basis.sum(axis=1), rtol=0.0, atol=1e-12):
        raise ValueError("not a hat basis: a row has nonzeros beyond two neighbouring knots")
    return first, weight


def _linearized_jackknife(
    problem: ArrayProblem, prior: GaussianPrior, x: FloatArray, blocks: int, cols: slice
) -> FloatArray | None:
    """Delete-one-block jackknife of the state columns ``cols`` over contiguous time blocks of pings,
    each block's estimate one Gauss-Newton step from the solution (normal-matrix downdate). The blocks'
    normal equations come from one structured pass (:meth:`_Linearization.normal`) and the downdated
    systems are solved in one batched call."""
    s = problem.survey
    used_pings = np.unique(s.reply_ping[problem.mask])
    if blocks < 2 or used_pings.size < 4 * blocks:
        return None
    lin = problem.linearize(x)
    order = used_pings[np.argsort(s.t_transmit_s[used_pings], kind="stable")]
    block_of = np.full(s.n_pings, blocks)  # pings without a used reply: an extra block, all zero rows
    block_of[order] = np.arange(order.size) * blocks // order.size
    normal, grad = lin.normal(block_of, blocks + 1)
    info = np.linalg.inv(prior.cov)
    a_full = normal.sum(axis=0) + info
    reps = np.linalg.solve(a_full[None] - normal[:blocks], -grad[:blocks, :, None])[..., 0]
    dev = reps[:, cols]
    dev = dev - dev.mean(axis=0)
    return (blocks - 1) / blocks * dev.T @ dev


def _result(
    survey: GnssaArraySurvey,
    opts: GnssaArrayOptions,
    setup: _Setup,
    result: object,
    x: FloatArray,
    used: BoolArray,
    resid: FloatArray,
    sigma: FloatArray,
    sigma_path: float,
    beta: float,
    exclusions: list[ReplyExclusion],
    iterations: list[ArrayIteration],
) -> GnssaArrayResult:
    problem = setup.problem
    n_t = survey.n_transponders
    cov_state = result.covariance[0]  # type: ignore[attr-defined]
    npos = problem.n_pos
    formal_pos = cov_state[:npos, :npos]
    jk = _linearized_jackknife(problem, setup.prior, x, opts.jackknife_blocks, slice(0, npos))
    baseline = formal_pos
    if problem.lever and not opts.estimate_lever_arm:
        # the lever arm's prior error is common to every block, so the jackknife cannot see it: compare
        # the jackknife with the formal covariance given the lever arm (Schur complement), then add the
        # excess to the full formal covariance, which holds the lever arm's part
        cl = slice(problem.col_lever, problem.col_lever + 3)
        p_pl = cov_state[:npos, cl]
        baseline = formal_pos - p_pl @ np.linalg.solve(cov_state[cl, cl], p_pl.T)
    cov_pos = formal_pos if jk is None else formal_pos + _positive_part(jk - baseline)
    # survey-wide GNSS error: the mean antenna covariance of the used pings, common to every transponder
    ping_used = np.unique(survey.reply_ping[used])
    c_gnss = 0.5 * (
        np.mean(survey.transmit_antenna_cov_m2[ping_used], axis=0)
        + np.mean(survey.receive_antenna_cov_m2[used], axis=0)
    )
    if not opts.gnss_common_mode:
        c_gnss = np.zeros((3, 3))
    if problem.geometry is not None:
        shift_cov = cov_pos + c_gnss
        stack = np.tile(np.eye(3), (n_t, 1))  # (3J, 3)
        cov = stack @ shift_cov @ stack.T
        formal = stack @ formal_pos @ stack.T
        jk_full = None if jk is None else stack @ jk @ stack.T
        gnss_full = stack @ c_gnss @ stack.T
        shift = x[:3].copy()
    else:
        gnss_full = np.tile(c_gnss, (n_t, n_t))
        cov = cov_pos + gnss_full
        formal = formal_pos
        jk_full = jk
        shift = None
        shift_cov = None
    positions = problem.positions(x)
    avg = np.tile(np.eye(3), (1, n_t)) / n_t  # (3, 3J)
    centre = ArrayCentre(position_enu_m=positions.mean(axis=0), covariance_m2=avg @ cov @ avg.T, epoch_s=0.0)
    epoch = float(np.mean(survey.t_transmit_s[np.unique(survey.reply_ping[used])]))
    centre = dataclasses.replace(centre, epoch_s=epoch)
    k0 = problem.first_knot
    knots = x[k0:].copy()
    knot_sig = np.sqrt(np.diag(cov_state)[k0:])
    speed = problem.speed(x)
    c_ref = problem.acoustics.c_ref
    grad = x[problem.col_gradient : problem.col_gradient + 2].copy() if problem.gradient else np.zeros(2)
    grad_sig = (
        np.sqrt(np.diag(cov_state)[problem.col_gradient : problem.col_gradient + 2])
        if problem.gradient
        else np.zeros(2)
    )
    if problem.lever:
        cl = problem.col_lever
        lever = x[cl : cl + 3].copy()
        lever_cov = cov_state[cl : cl + 3, cl : cl + 3].copy()
        lever_prior = np.sqrt(np.diag(setup.prior.cov[cl : cl + 3, cl : cl + 3]))
    else:
        lever, lever_cov = survey.lever_arm_body_m.copy(), survey.lever_arm_cov_m2.copy()
        lever_prior = np.sqrt(np.diag(lever_cov))
    geodetic = None if survey.origin is None else enu_to_geodetic(positions, survey.origin)
    all_exclusions = tuple(setup.exclusions) + tuple(exclusions)
    mean_speed = float(np.mean(speed[used]))
    return GnssaArrayResult(
        name=survey.name,
        solution=opts.solution,
        acoustic_model=problem.acoustics.model,
        transponder_ids=survey.transponder_ids,
        positions_enu_m=positions,
        covariance_m2=cov,
        covariance_formal_m2=formal,
        covariance_jackknife_m2=jk_full,
        covariance_gnss_m2=gnss_full,
        positions_geodetic=geodetic,
        shift_enu_m=shift,
        shift_covariance_m2=shift_cov,
        centre=centre,
        epoch_s=epoch,
        reference_speed_mps=c_ref,
        knot_times_s=setup.knots_s,
        sound_speed_knots_mps=knots,
        sound_speed_knot_sigma_mps=knot_sig,
        sound_speed_mps=mean_speed,
        speed_correction_ppm=1e6 * (mean_speed / c_ref - 1.0),
        gradient_per_km=grad,
        gradient_sigma_per_km=grad_sig,
        lever_arm_body_m=lever,
        lever_arm_covariance_m2=lever_cov,
        lever_arm_estimated=bool(opts.estimate_lever_arm),
        lever_arm_prior_sigma_m=lever_prior,
        reply_ping=survey.reply_ping,
        reply_transponder=survey.reply_transponder,
        residual_m=resid,
        residual_s=resid / c_ref,
        sigma_m=sigma,
        used=used,
        exclusions=all_exclusions,
        iterations=tuple(iterations),
        sigma_path_m=float(sigma_path),
        beta_m=float(beta),
        residual_rms_m=float(np.sqrt(np.mean(resid[used] ** 2))),
        converged=bool(result.converged[0]),  # type: ignore[attr-defined]
        time_origin_unix_s=float(survey.time_origin_unix_s),
        status="ok" if bool(result.converged[0]) else str(result.message[0]),  # type: ignore[attr-defined]
    )
