"""Robust MAP localization of a seafloor transponder from GNSS-Acoustic two-way travel times.

Model (per ping ``i``, transmit position ``a_i``, receive position ``b_i``, both from GNSS)::

    TWTT_i = (|p_T - a_i| + |p_T - b_i|) / c(t_i) + tau + noise

with the transponder ``p_T = (E, N, U)`` and the sound speed as unknowns of one MAP problem solved by
:func:`oceanloc.estimation.map_gauss_newton.solve_map` (Garcia et al. 2019, eqs. 10-22, on a different
measurement model). The sound speed is a harmonic-mean speed along the path, either one constant or
piecewise linear in time (knots every ``knot_spacing_s``): sea water warms and mixes over a survey of
two hours, and on the La Jolla surveys one constant speed leaves residuals that drift by +-10 cm with
time. Knot values have a Gaussian prior centred on the given (published) speed with standard deviation
``sigma_sound_speed_mps`` and exponential correlation ``sound_speed_correlation_s`` between knots.

Noise (journal eqs. 46-52 generalized): the GNSS sigmas of both legs projected on their lines of sight
(known, per ping), plus a path term ``sigma_path`` (timing noise, unmodelled propagation) and, for far
pings, a range-dependent term ``beta * tan(incidence)``; ``sigma_path`` and ``beta`` are estimated from
the residuals by maximum likelihood (variance components), so the formal covariance matches the
scatter of the residuals instead of trusting a guessed timing sigma.

Far pings: a straight ray at constant speed is wrong by an amount that grows with the incidence angle
(ray bending through the sound-speed profile), so the range-dependent term down-weights far pings by
what the data say their extra scatter is; an elevation cut (``max_tan_incidence``) is available too.

Gross errors first: a ping file can hold travel times that fit no position at all (a wrong column, a
missed turn-around, a quarter of the pings at an absurd value). Least squares follows them by kilometres,
and the one-at-a-time rule below, capped at ``max_outlier_fraction``, cannot remove them all. So a robust
first fit (:func:`robust_first_fit`: position only, the given sound speed, Tukey-biweight iteratively
reweighted MAP from three starting points, the one with the smallest MAD of residuals kept) screens the
pings: those whose residual departs from the median by more than ``max(prescreen_sigmas * 1.4826 MAD,
gross_error_m)`` are excluded as gross errors before the real solve. If more than
``max_gross_fraction`` of the pings are gross, or a used ping still has a residual above
``gross_error_m`` at the end, the survey cannot be solved reliably and a :class:`DataError` says so.

Outliers: the authors' rule (Xie et al. 2023): the ping with the largest normalized residual is removed
if it exceeds ``outlier_threshold`` (3), one at a time, re-solving and re-estimating the noise after each
removal. Every exclusion is listed with its reason.

Uncertainty: residuals of neighbouring pings are correlated (the sound speed field changes slowly), so
the formal covariance is optimistic. A delete-one-block jackknife over ``jackknife_blocks`` contiguous
time blocks (one batched solve) measures the estimate's sensitivity to whole stretches of the survey;
the reported covariance is the formal one plus the positive part of (jackknife - formal).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from oceanloc._typing import BoolArray, FloatArray, IntArray
from oceanloc.errors import ConfigError, DataError
from oceanloc.estimation.map_gauss_newton import GaussianPrior, MapOptions, solve_map
from oceanloc.geo.enu import enu_to_geodetic
from oceanloc.io.gnssa import GPS_EPOCH_2020_UNIX_S, GnssaSurvey
from oceanloc.models.acoustics import (
    gradient_path_jacobian,
    gradient_path_m2,
    refraction_shortening_jacobian,
    refraction_shortening_m,
)
from oceanloc.models.measurements import (
    range_jacobian,
    two_way_range_jacobian,
    two_way_range_m,
)


@dataclass(frozen=True, slots=True, kw_only=True)
class GnssaOptions:
    """Settings of :func:`localize_gnssa`.

    Attributes
    ----------
    sound_speed_mps : float
        Prior (or fixed) harmonic-mean sound speed, m/s (1500: nominal sea water; give the survey's).
    estimate_sound_speed : bool
        Make the sound speed an unknown with a prior; False fixes it.
    sigma_sound_speed_mps : float
        Prior standard deviation of each sound-speed knot, m/s.
    knot_spacing_s : float or None
        Spacing of the piecewise-linear sound-speed knots in time; None for one constant speed.
    min_pings_per_knot : int
        Knots are spread further apart if a segment would hold fewer pings than this.
    sound_speed_correlation_s : float
        Correlation time of the knot prior (exponential), seconds.
    outlier_threshold : float
        Normalized-residual threshold of the one-at-a-time outlier rule.
    max_outlier_fraction : float
        At most this fraction of the pings is excluded as outliers.
    gross_error_m : float
        Exclusions with a residual larger than this are labelled gross errors (same rule, clearer label);
        also the smallest residual the pre-screen excludes, and the largest a used ping may keep.
    prescreen : bool
        Screen gross errors with a robust first fit before the solve (see the module docstring).
    prescreen_sigmas : float
        Pre-screen threshold in robust (MAD) standard deviations of the first fit's residuals.
    max_gross_fraction : float
        Largest fraction of the pings the pre-screen may exclude; beyond it the survey is refused.
    range_dependent_weights : bool
        Estimate the far-ping term ``beta * tan(incidence)`` of the noise.
    max_tan_incidence : float or None
        Elevation cut: exclude pings whose horizontal offset exceeds this multiple of the depth.
    sigma_position_prior_m : float
        Standard deviation of the (weak) position prior around the initial guess, metres.
    turnaround_s : float
        Turn-around delay still in the TWTT (0 for files that removed it), seconds.
    jackknife_blocks : int
        Number of contiguous time blocks for the jackknife covariance (0 disables it).
    estimate_gradient : bool
        Estimate a horizontal gradient of slowness ``(g_E, g_N)``, relative change per kilometre
        (:func:`~oceanloc.models.acoustics.gradient_path_m2`).
    sigma_gradient_per_km : float
        Prior standard deviation of each gradient component around zero, per kilometre (1e-3: about
        1.5 m/s of depth-averaged sound speed per kilometre).
    estimate_refraction : bool
        Estimate the refraction coefficient ``kappa`` of the straight-ray correction
        ``L (1 - kappa tan^2 theta)`` per leg (:func:`~oceanloc.models.acoustics.refraction_shortening_m`).
    sigma_refraction_ppm : float
        Prior standard deviation of ``kappa`` around zero, parts per million.
    gnss_common_mode : bool
        Add the survey-wide GNSS error (the mean per-ping GNSS covariance) to the reported covariance.
    """

    sound_speed_mps: float = 1500.0
    estimate_sound_speed: bool = True
    sigma_sound_speed_mps: float = 3.0
    knot_spacing_s: float | None = 900.0
    min_pings_per_knot: int = 40
    sound_speed_correlation_s: float = 1800.0
    outlier_threshold: float = 3.0
    max_outlier_fraction: float = 0.2
    gross_error_m: float = 5.0
    prescreen: bool = True
    prescreen_sigmas: float = 8.0
    max_gross_fraction: float = 0.4
    range_dependent_weights: bool = True
    max_tan_incidence: float | None = None
    sigma_position_prior_m: float = 1000.0
    turnaround_s: float = 0.0
    jackknife_blocks: int = 10
    estimate_gradient: bool = True
    sigma_gradient_per_km: float = 1e-3
    estimate_refraction: bool = False
    sigma_refraction_ppm: float = 30.0
    gnss_common_mode: bool = True

    def __post_init__(self) -> None:
        if not (1300.0 <= self.sound_speed_mps <= 1700.0):
            raise ConfigError(f"sound speed {self.sound_speed_mps} m/s is outside [1300, 1700]")
        if self.sigma_sound_speed_mps <= 0.0:
            raise ConfigError("sigma_sound_speed_mps must be positive")
        if self.knot_spacing_s is not None and self.knot_spacing_s <= 0.0:
            raise ConfigError("knot_spacing_s must be positive (or None for a constant sound speed)")
        if self.outlier_threshold <= 1.0:
            raise ConfigError(f"outlier_threshold must exceed 1, got {self.outlier_threshold}")
        if not 0.0 <= self.max_outlier_fraction < 0.5:
            raise ConfigError("max_outlier_fraction must be in [0, 0.5)")
        if not 0.0 <= self.max_gross_fraction < 0.5:
            raise ConfigError(
                "max_gross_fraction must be in [0, 0.5): a majority of gross errors cannot be told apart"
            )
        if not (self.gross_error_m > 0.0 and np.isfinite(self.gross_error_m)):
            raise ConfigError(f"gross_error_m must be a positive number of metres, got {self.gross_error_m}")
        if not self.prescreen_sigmas > 1.0:
            raise ConfigError(f"prescreen_sigmas must exceed 1, got {self.prescreen_sigmas}")
        if self.max_tan_incidence is not None and self.max_tan_incidence <= 0.0:
            raise ConfigError("max_tan_incidence must be positive")
        if self.jackknife_blocks == 1 or self.jackknife_blocks < 0:
            raise ConfigError("jackknife_blocks must be 0 (off) or at least 2")
        if self.sigma_refraction_ppm <= 0.0:
            raise ConfigError("sigma_refraction_ppm must be positive")
        if self.sigma_gradient_per_km <= 0.0:
            raise ConfigError("sigma_gradient_per_km must be positive")


@dataclass(frozen=True, slots=True, kw_only=True)
class Exclusion:
    """One excluded ping and why."""

    index: int
    line: int
    time_s: float
    reason: str
    residual_m: float

    def __str__(self) -> str:
        return f"line {self.line} (t={self.time_s:.1f} s): {self.reason}"


@dataclass(frozen=True, slots=True, kw_only=True)
class GnssaResult:
    """Localization of one survey.

    Attributes
    ----------
    name : str
        Survey name.
    position_enu_m : (3,) float
        Transponder (E, N, U) in the file's frame, metres.
    covariance_m2 : (3, 3) float
        Reported covariance: formal plus the positive part of (jackknife - formal).
    covariance_formal_m2 : (3, 3) float
        MAP covariance (eq. 22) with the estimated noise.
    covariance_jackknife_m2 : (3, 3) float or None
        Delete-one-block jackknife covariance.
    position_geodetic : (3,) float or None
        Latitude (deg), longitude (deg), ellipsoidal height (m) if the file has an origin.
    epoch_s : float
        Epoch of the position: the mean transmit time of the used pings, in the file's time base
        (seconds after 2020-01-01 UTC for the La Jolla format).
    knot_times_s : (K,) float
        Times of the sound-speed knots (empty if the sound speed is fixed).
    sound_speed_knots_mps : (K,) float
        Estimated sound speed at the knots.
    sound_speed_mps : float
        Mean sound speed over the used pings.
    used : (n,) bool
        Pings used in the final solution.
    exclusions : tuple of Exclusion
        Every excluded ping, in the order it was excluded.
    residual_m : (n,) float
        ``c(t) TWTT - (|p - a| + |p - b|)`` for every ping at the estimate, metres (two-way path).
    sigma_m : (n,) float
        Per-ping standard deviation of that residual, metres.
    residual_rms_m : float
        RMS of the used residuals, metres.
    sigma_path_m : float
        Estimated path noise (timing and unmodelled propagation), metres of two-way path.
    beta_m : float
        Estimated far-ping noise per unit tan(incidence), metres.
    gradient_per_km : (2,) float
        Estimated horizontal slowness gradient (east, north), relative change per kilometre (zeros when
        not estimated).
    refraction_ppm : float
        Estimated refraction coefficient ``kappa`` (0 when not estimated), parts per million.
    covariance_gnss_m2 : (3, 3) float
        The survey-wide GNSS part of :attr:`covariance_m2` (zeros when not added).
    converged : bool
    """

    name: str
    position_enu_m: FloatArray
    covariance_m2: FloatArray
    covariance_formal_m2: FloatArray
    covariance_jackknife_m2: FloatArray | None
    position_geodetic: FloatArray | None
    epoch_s: float
    knot_times_s: FloatArray
    sound_speed_knots_mps: FloatArray
    sound_speed_mps: float
    used: BoolArray
    exclusions: tuple[Exclusion, ...]
    residual_m: FloatArray
    sigma_m: FloatArray
    residual_rms_m: float
    sigma_path_m: float
    beta_m: float
    gradient_per_km: FloatArray
    refraction_ppm: float
    covariance_gnss_m2: FloatArray
    converged: bool

    @property
    def sigma_enu_m(self) -> FloatArray:
        """1-sigma of (E, N, U) from :attr:`covariance_m2`, metres."""
        return np.sqrt(np.diag(self.covariance_m2))

    @property
    def pings_used(self) -> int:
        return int(self.used.sum())

    def to_record(self) -> dict:
        """Plain JSON-ready data: position and 1-sigma (E, N, U order as named), epoch, acoustic model."""
        e, n, u = (float(v) for v in self.position_enu_m)
        se, sn, su = (float(v) for v in self.sigma_enu_m)
        record = {
            "file": self.name,
            "epoch_utc": gnssa_epoch_utc(self.epoch_s),
            "e_m": e,
            "n_m": n,
            "u_m": u,
            "sigma_e_m": se,
            "sigma_n_m": sn,
            "sigma_u_m": su,
            "lat_deg": None,
            "lon_deg": None,
            "h_m": None,
            "sound_speed_mps": float(self.sound_speed_mps),
            "pings_used": self.pings_used,
            "pings_excluded": len(self.exclusions),
            "residual_rms_m": float(self.residual_rms_m),
            "gradient_e_per_km": float(self.gradient_per_km[0]),
            "gradient_n_per_km": float(self.gradient_per_km[1]),
            "refraction_ppm": float(self.refraction_ppm),
            "sigma_path_m": float(self.sigma_path_m),
            "beta_m": float(self.beta_m),
            "converged": bool(self.converged),
        }
        if self.position_geodetic is not None:
            lat, lon, h = (float(v) for v in self.position_geodetic)
            record.update(lat_deg=lat, lon_deg=lon, h_m=h)
        return record


@dataclass(frozen=True, slots=True)
class GnssaProblem:
    """A batch of GNSS-A MAP problems sharing the pings, differing in which pings they use.

    State ``x = (E, N, U, [g_E, g_N], [kappa], c_1, ..., c_K)``: the transponder, optionally the
    horizontal slowness gradient (per kilometre, :func:`~oceanloc.models.acoustics.gradient_path_m2`) and
    the refraction coefficient (ppm, :func:`~oceanloc.models.acoustics.refraction_shortening_m`), then the
    sound-speed knots; with ``K = 0`` the sound speed is fixed at ``fixed_speed``. Residuals are in
    travel time, whitened by ``sigma_m / c0`` with the nominal speed ``c0`` (a constant weight, so the
    cost is an ordinary weighted least-squares cost in travel time).

    Attributes
    ----------
    transmit_m, receive_m : (n, 3) float
    twtt_s : (n,) float
        Travel times with the turn-around delay removed.
    basis : (n, K) float
        Sound-speed interpolation weights of each ping (rows sum to 1).
    sigma_m : (n,) float
        Path-length standard deviations, metres.
    mask : (B, n) bool
    fixed_speed : float
        The nominal (prior) speed: the fixed speed when ``K = 0`` and the whitening speed ``c0``.
    gradient : bool
        The state holds the horizontal slowness gradient.
    refraction : bool
        The state holds the refraction coefficient.
    """

    transmit_m: FloatArray
    receive_m: FloatArray
    twtt_s: FloatArray
    basis: FloatArray
    sigma_m: FloatArray
    mask: BoolArray
    fixed_speed: float
    gradient: bool = False
    refraction: bool = False

    @property
    def batch_size(self) -> int:
        return int(self.mask.shape[0])

    @property
    def first_knot(self) -> int:
        """Index of the first sound-speed knot in the state."""
        return 3 + 2 * int(self.gradient) + int(self.refraction)

    def speed(self, x: FloatArray) -> FloatArray:
        """Sound speed at each ping, ``(b, n)``."""
        if self.basis.shape[1] == 0:
            return np.full((x.shape[0], self.twtt_s.shape[0]), self.fixed_speed)
        return x[:, self.first_knot :] @ self.basis.T

    def path(self, x: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Modelled two-way acoustic path at the states ``x``.

        Returns
        -------
        path : (b, n) float
            Equivalent path length (straight legs, corrected for gradient and refraction), metres.
        d_target : (b, n, 3) float
            Its Jacobian on the transponder position.
        d_nuisance : (b, n, q) float
            Its Jacobian on the gradient and refraction parameters (``q`` = 0 to 3).
        """
        target = x[:, None, :3]
        legs = (self.transmit_m, self.receive_m)
        path = two_way_range_m(target, *legs)
        d_target = two_way_range_jacobian(target, *legs)
        nuisance = []
        col = 3
        if self.gradient:
            g = 1e-3 * x[:, None, col : col + 2]
            factor = sum(gradient_path_m2(target, leg) for leg in legs)
            jac = sum(gradient_path_jacobian(target, leg) for leg in legs)
            path = path + np.sum(g * factor, axis=-1)
            d_target = d_target + np.einsum("bnk,bnkj->bnj", g, jac)
            nuisance.append(1e-3 * factor)
            col += 2
        if self.refraction:
            kappa = 1e-6 * x[:, col, None]
            short = sum(refraction_shortening_m(target, leg) for leg in legs)
            jac = sum(refraction_shortening_jacobian(target, leg) for leg in legs)
            path = path - kappa * short
            d_target = d_target - kappa[..., None] * jac
            nuisance.append(-1e-6 * short[..., None])
        d_nuisance = np.concatenate(nuisance, axis=-1) if nuisance else np.zeros((*path.shape, 0))
        return path, d_target, d_nuisance

    def evaluate(self, x: FloatArray, rows: IntArray) -> tuple[FloatArray, FloatArray]:
        path, d_target, d_nuisance = self.path(x)
        c = self.speed(x)
        weight = np.where(self.mask[rows], self.fixed_speed / self.sigma_m, 0.0)
        resid = (self.twtt_s - path / c) * weight
        k0 = self.first_knot
        jac = np.empty((x.shape[0], self.twtt_s.shape[0], x.shape[1]))
        jac[..., :3] = d_target / c[..., None]
        jac[..., 3:k0] = d_nuisance / c[..., None]
        if x.shape[1] > k0:
            jac[..., k0:] = (-path / (c * c))[..., None] * self.basis
        return resid, jac * weight[..., None]

    def with_mask(self, mask: BoolArray, sigma_m: FloatArray | None = None) -> GnssaProblem:
        """The same problem with other ping masks ``(B, n)`` (and optionally other sigmas)."""
        return dataclasses.replace(self, mask=mask, sigma_m=self.sigma_m if sigma_m is None else sigma_m)


def sound_speed_knots(t_s: FloatArray, options: GnssaOptions) -> FloatArray:
    """Knot times of the piecewise-linear sound speed: at least ``min_pings_per_knot`` pings per
    segment on average and at most ``knot_spacing_s`` apart (one knot: a constant speed)."""
    if not options.estimate_sound_speed:
        return np.zeros(0)
    t0, t1 = float(t_s.min()), float(t_s.max())
    if options.knot_spacing_s is None or t1 <= t0:
        return np.array([t0])
    spacing = max(options.knot_spacing_s, (t1 - t0) * options.min_pings_per_knot / t_s.size)
    n_seg = max(1, round((t1 - t0) / spacing))
    return np.linspace(t0, t1, n_seg + 1)


def hat_basis(t_s: FloatArray, knots_s: FloatArray) -> FloatArray:
    """Piecewise-linear interpolation weights ``(n, K)`` of times on knots (constant for one knot)."""
    if knots_s.size == 0:
        return np.zeros((t_s.size, 0))
    if knots_s.size == 1:
        return np.ones((t_s.size, 1))
    eye = np.eye(knots_s.size)
    return np.stack([np.interp(t_s, knots_s, eye[k]) for k in range(knots_s.size)], axis=1)


def localize_gnssa(survey: GnssaSurvey, options: GnssaOptions) -> GnssaResult:
    """Robust MAP position of the transponder of one survey (see the module docstring).

    Five steps, each a function returning a small frozen result: :func:`gross_prescreen` (gross travel
    times found by a robust first fit), :func:`gnssa_setup` (the MAP problem and its prior),
    :func:`elevation_cut` (far pings dropped before solving), :func:`robust_solve` (MAP, noise components
    and the one-at-a-time outlier rule) and :func:`gnssa_covariance` (formal, jackknife and GNSS
    common-mode parts).

    Parameters
    ----------
    survey : GnssaSurvey
    options : GnssaOptions

    Returns
    -------
    GnssaResult
    """
    screen = gross_prescreen(survey, options)
    setup = gnssa_setup(survey, options, screen.gross)
    cut = elevation_cut(survey, options, setup.initial_m, screen.gross)
    if cut.candidates.sum() < setup.dim + 2:
        raise DataError(
            f"{survey.path}: {int(cut.candidates.sum())} usable pings, need at least {setup.dim + 2}"
        )
    sol = robust_solve(survey, options, setup, cut)
    cov = gnssa_covariance(survey, options, setup, sol)
    x, used, k0 = sol.x, sol.used, setup.first_knot
    problem = setup.template.with_mask(used[None, :], sol.sigma_m)
    resid = _path_residual(problem, x)[0]
    gross_exclusions = screen.exclusions(survey, resid)
    n_excluded = len(gross_exclusions) + len(cut.exclusions) + len(sol.exclusions)
    _refuse_gross_left(survey, options, used, resid, n_excluded)
    speed = problem.speed(x)[0]
    geodetic = None if survey.origin is None else enu_to_geodetic(x[0, :3], survey.origin)
    return GnssaResult(
        name=survey.name,
        position_enu_m=x[0, :3].copy(),
        covariance_m2=cov.total_m2,
        covariance_formal_m2=cov.formal_m2,
        covariance_jackknife_m2=cov.jackknife_m2,
        position_geodetic=geodetic,
        epoch_s=float(np.mean(survey.t_transmit_s[used])),
        knot_times_s=setup.knots_s,
        sound_speed_knots_mps=x[0, k0:].copy(),
        gradient_per_km=x[0, 3:5].copy() if options.estimate_gradient else np.zeros(2),
        refraction_ppm=float(x[0, k0 - 1]) if options.estimate_refraction else 0.0,
        covariance_gnss_m2=cov.gnss_m2,
        sound_speed_mps=float(np.mean(speed[used])),
        used=used,
        exclusions=gross_exclusions + cut.exclusions + sol.exclusions,
        residual_m=resid,
        sigma_m=sol.sigma_m,
        residual_rms_m=float(np.sqrt(np.mean(resid[used] ** 2))),
        sigma_path_m=float(sol.sigma_path_m),
        beta_m=float(sol.beta_m),
        converged=sol.converged,
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class GnssaSetup:
    """The MAP problem of one survey before any ping is dropped (:func:`gnssa_setup`).

    Attributes
    ----------
    template : GnssaProblem
        Every ping, unit sigmas (masks and sigmas are set per solve).
    knots_s : (K,) float
        Sound-speed knot times (empty: one constant speed).
    t_mid_s : (n,) float
        Mid-times of the pings (transmit and receive averaged), seconds.
    initial_m : (3,) float
        Starting position: below the ping with the shortest travel time, metres.
    prior : GaussianPrior
        Position, gradient, refraction and knot prior.
    map_options : MapOptions
    """

    template: GnssaProblem
    knots_s: FloatArray
    t_mid_s: FloatArray
    initial_m: FloatArray
    prior: GaussianPrior
    map_options: MapOptions

    @property
    def first_knot(self) -> int:
        return self.template.first_knot

    @property
    def dim(self) -> int:
        return self.first_knot + int(self.knots_s.size)


def gnssa_setup(survey: GnssaSurvey, options: GnssaOptions, gross: BoolArray | None = None) -> GnssaSetup:
    """The survey's MAP problem and prior: knots, hat basis, initial guess, prior covariance (position,
    gradient, refraction, exponentially correlated knots) and the surface constraint; the initial guess
    leaves out the ``gross`` pings."""
    n = survey.n_pings
    tx, rx = survey.transmit_enu_m, survey.receive_enu_m
    twtt = survey.twtt_s - options.turnaround_s
    if np.any(twtt <= 0.0):
        raise DataError(f"{survey.path}: turnaround {options.turnaround_s} s exceeds some travel times")
    t_mid = 0.5 * (survey.t_transmit_s + survey.t_receive_s)
    knots = sound_speed_knots(t_mid, options)
    basis = hat_basis(t_mid, knots)
    n_knots = knots.size
    template = GnssaProblem(
        tx,
        rx,
        twtt,
        basis,
        np.ones(n),
        np.ones((1, n), dtype=bool),
        options.sound_speed_mps,
        gradient=options.estimate_gradient,
        refraction=options.estimate_refraction,
    )
    k0 = template.first_knot
    dim = k0 + n_knots
    keep = np.ones(n, dtype=bool) if gross is None else ~gross
    x0 = _initial_guess(tx[keep], twtt[keep], options.sound_speed_mps)
    prior_mean = np.concatenate([x0, np.zeros(k0 - 3), np.full(n_knots, options.sound_speed_mps)])[None, :]
    prior_var = [options.sigma_position_prior_m**2] * 3
    if options.estimate_gradient:
        prior_var += [options.sigma_gradient_per_km**2] * 2
    if options.estimate_refraction:
        prior_var += [options.sigma_refraction_ppm**2]
    prior_cov = np.zeros((dim, dim))
    prior_cov[:k0, :k0] = np.diag(prior_var)
    if n_knots:
        lag = np.abs(knots[:, None] - knots[None, :])
        prior_cov[k0:, k0:] = options.sigma_sound_speed_mps**2 * np.exp(
            -lag / options.sound_speed_correlation_s
        )
    surface = float(np.min(np.concatenate([tx[:, 2], rx[:, 2]])))
    return GnssaSetup(
        template=template,
        knots_s=knots,
        t_mid_s=t_mid,
        initial_m=x0,
        prior=GaussianPrior(mean=prior_mean, cov=prior_cov),
        map_options=MapOptions(delta_min_m=1e-7, max_iterations=100, surface_z_m=surface),
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class PingSelection:
    """Pings kept for solving (:func:`elevation_cut`): ``candidates (n,)`` and the far pings dropped."""

    candidates: BoolArray
    exclusions: tuple[Exclusion, ...]


def elevation_cut(
    survey: GnssaSurvey, options: GnssaOptions, initial_m: FloatArray, excluded: BoolArray | None = None
) -> PingSelection:
    """Drop pings farther than ``max_tan_incidence`` depths horizontally from ``initial_m`` (none when the
    cut is off), among the pings not already ``excluded`` (the gross errors of :func:`gross_prescreen`)."""
    tx = survey.transmit_enu_m
    candidates = np.ones(survey.n_pings, dtype=bool) if excluded is None else ~excluded
    exclusions: list[Exclusion] = []
    if options.max_tan_incidence is not None:
        depth = np.maximum(tx[:, 2] - initial_m[2], 1.0)
        tan_inc = np.hypot(tx[:, 0] - initial_m[0], tx[:, 1] - initial_m[1]) / depth
        for i in np.flatnonzero(candidates & (tan_inc > options.max_tan_incidence)):
            candidates[i] = False
            exclusions.append(
                Exclusion(
                    index=int(i),
                    line=int(survey.line[i]),
                    time_s=float(survey.t_transmit_s[i]),
                    reason=f"far ping: tan(incidence) {tan_inc[i]:.2f} > {options.max_tan_incidence}",
                    residual_m=float("nan"),
                )
            )
    return PingSelection(candidates=candidates, exclusions=tuple(exclusions))


@dataclass(frozen=True, slots=True, kw_only=True)
class RobustSolution:
    """The MAP solution after the outlier rule (:func:`robust_solve`).

    Attributes
    ----------
    x : (1, dim) float
        Unknowns: position, gradient, refraction, sound-speed knots.
    covariance : (1, dim, dim) float
        MAP covariance at the last solve.
    used : (n,) bool
    sigma_m : (n,) float
        Per-ping path sigma with the estimated noise components, metres.
    sigma_path_m, beta_m : float
        Estimated path noise and far-ping noise per unit tan(incidence), metres.
    exclusions : tuple of Exclusion
        Outliers, in the order they were removed.
    converged : bool
    """

    x: FloatArray
    covariance: FloatArray
    used: BoolArray
    sigma_m: FloatArray
    sigma_path_m: float
    beta_m: float
    exclusions: tuple[Exclusion, ...]
    converged: bool


def robust_solve(
    survey: GnssaSurvey, options: GnssaOptions, setup: GnssaSetup, selection: PingSelection
) -> RobustSolution:
    """MAP with the noise components re-estimated (three rounds per solve), removing the ping with the
    largest normalized residual while it exceeds ``outlier_threshold`` (Xie et al. 2023), at most
    ``max_outlier_fraction`` of the candidates."""
    template, prior, map_opts = setup.template, setup.prior, setup.map_options
    candidates = selection.candidates
    sigma_path, beta = 0.05, 0.0
    used = candidates.copy()
    x = prior.mean.copy()
    max_out = int(options.max_outlier_fraction * candidates.sum())
    n_out = 0
    exclusions: list[Exclusion] = []
    while True:
        gnss_var, tan_inc = _gnss_variance(x[0, :3], survey)
        result = None
        for _ in range(3):
            sigma = np.sqrt(gnss_var + sigma_path**2 + (beta * tan_inc) ** 2)
            problem = template.with_mask(used[None, :], sigma)
            result = solve_map(problem, prior, map_opts, initial=x)
            x = result.estimate
            resid = _path_residual(problem, x)[0]
            sigma_path, beta = _variance_components(
                resid[used], gnss_var[used], tan_inc[used], options.range_dependent_weights
            )
        assert result is not None
        sigma = np.sqrt(gnss_var + sigma_path**2 + (beta * tan_inc) ** 2)
        normalized = np.where(used, np.abs(resid) / sigma, 0.0)
        worst = int(np.argmax(normalized))
        if normalized[worst] <= options.outlier_threshold or n_out >= max_out:
            break
        used[worst] = False
        n_out += 1
        exclusions.append(
            Exclusion(
                index=worst,
                line=int(survey.line[worst]),
                time_s=float(survey.t_transmit_s[worst]),
                reason=("gross error" if abs(resid[worst]) > options.gross_error_m else "outlier")
                + f": |residual| {abs(resid[worst]):.3f} m = {normalized[worst]:.1f} sigma"
                f" > {options.outlier_threshold:g} sigma",
                residual_m=float(resid[worst]),
            )
        )
    return RobustSolution(
        x=x,
        covariance=result.covariance,
        used=used,
        sigma_m=sigma,
        sigma_path_m=float(sigma_path),
        beta_m=float(beta),
        exclusions=tuple(exclusions),
        converged=bool(result.converged[0]),
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class RobustFit:
    """Result of :func:`robust_first_fit`.

    Attributes
    ----------
    position_enu_m : (3,) float
        Transponder position, metres.
    residual_m : (n,) float
        ``c TWTT - path`` of every ping at that position, metres (two-way path).
    sigma_m : float
        Robust standard deviation of the residuals, ``1.4826 * MAD``, metres.
    """

    position_enu_m: FloatArray
    residual_m: FloatArray
    sigma_m: float


_TUKEY_C = 4.685
"""Tukey biweight tuning constant (95 % efficiency at the normal)."""


def robust_first_fit(
    transmit_m: FloatArray,
    receive_m: FloatArray,
    twtt_s: FloatArray,
    speed_mps: float,
    surface_z_m: float,
    iterations: int = 12,
) -> RobustFit:
    """A transponder position that a minority of gross travel times cannot move.

    Position only, straight rays at the given sound speed; Tukey-biweight iteratively reweighted MAP
    (weights ``(1 - u^2)^2`` for ``|u| = |r - median r| / (4.685 * 1.4826 MAD) < 1``, else 0; the scale
    floored at 1 cm) from three starting points: below the ping with the shortest travel time, below
    the ping at the 10th percentile of travel time, and below the median surface position at the median
    travel time's depth. The start whose fit has the smallest MAD is returned. Its breakdown point is
    that of the median: it holds while fewer than half of the pings are gross.
    """
    n = twtt_s.size
    problem = GnssaProblem(
        transmit_m, receive_m, twtt_s, np.zeros((n, 0)), np.ones(n), np.ones((1, n), dtype=bool), speed_mps
    )
    opts = MapOptions(delta_min_m=1e-4, max_iterations=50, surface_z_m=surface_z_m)
    best: RobustFit | None = None
    for start in _robust_starts(transmit_m, twtt_s, speed_mps):
        x = start[None, :]
        prior = GaussianPrior(mean=x.copy(), cov=1e6 * np.eye(3))  # 1 km: only keeps the solve defined
        for _ in range(iterations):
            r = _path_residual(problem, x)[0]
            med = np.median(r)
            scale = max(1.4826 * float(np.median(np.abs(r - med))), 0.01)
            u = (r - med) / (_TUKEY_C * scale)
            w = np.where(np.abs(u) < 1.0, (1.0 - u * u) ** 2, 0.0)
            keep = w > 1e-6
            if keep.sum() < 4:
                break
            sigma = scale / np.sqrt(np.where(keep, w, 1.0))
            x = solve_map(problem.with_mask(keep[None, :], sigma), prior, opts, initial=x).estimate
        r = _path_residual(problem, x)[0]
        fit = RobustFit(
            position_enu_m=x[0].copy(),
            residual_m=r,
            sigma_m=1.4826 * float(np.median(np.abs(r - np.median(r)))),
        )
        if np.all(np.isfinite(fit.position_enu_m)) and (best is None or fit.sigma_m < best.sigma_m):
            best = fit
    if best is None:
        raise DataError("no robust first fit: every start gave a NaN position")
    return best


def _robust_starts(tx: FloatArray, twtt: FloatArray, speed: float) -> list[FloatArray]:
    """Starting points of :func:`robust_first_fit` (see there)."""
    order = np.argsort(twtt, kind="stable")
    starts = [
        _initial_guess(tx, twtt, speed),
        _initial_guess(tx[order[twtt.size // 10 :]], twtt[order[twtt.size // 10 :]], speed),
    ]
    e, nn = np.median(tx[:, 0]), np.median(tx[:, 1])
    offset = float(np.median(np.hypot(tx[:, 0] - e, tx[:, 1] - nn)))
    leg = 0.5 * speed * float(np.median(twtt))
    depth = np.sqrt(max(leg * leg - offset * offset, (0.1 * leg) ** 2))
    starts.append(np.array([e, nn, float(np.median(tx[:, 2])) - depth]))
    return starts


@dataclass(frozen=True, slots=True, kw_only=True)
class Prescreen:
    """Gross travel-time errors found before the solve (:func:`gross_prescreen`).

    Attributes
    ----------
    gross : (n,) bool
        Pings excluded as gross errors.
    fit_residual_m : (n,) float
        Each ping's residual at the robust first fit less their median, metres (zeros when off).
    threshold_m : float
        ``max(prescreen_sigmas * 1.4826 MAD, gross_error_m)``; ``inf`` when the pre-screen is off.
    """

    gross: BoolArray
    fit_residual_m: FloatArray
    threshold_m: float

    def exclusions(self, survey: GnssaSurvey, residual_m: FloatArray) -> tuple[Exclusion, ...]:
        """The gross pings as exclusions, with their residual at the final solution."""
        return tuple(
            Exclusion(
                index=int(i),
                line=int(survey.line[i]),
                time_s=float(survey.t_transmit_s[i]),
                reason=f"gross error (pre-screen): |residual| {abs(self.fit_residual_m[i]):.1f} m at the "
                f"robust first fit > {self.threshold_m:.2f} m",
                residual_m=float(residual_m[i]),
            )
            for i in np.flatnonzero(self.gross)
        )


def gross_prescreen(survey: GnssaSurvey, options: GnssaOptions) -> Prescreen:
    """Screen gross travel times with :func:`robust_first_fit` (see the module docstring); refuse a survey
    with more than ``max_gross_fraction`` of them."""
    n = survey.n_pings
    tx, rx = survey.transmit_enu_m, survey.receive_enu_m
    twtt = survey.twtt_s - options.turnaround_s
    if not options.prescreen or n < 8 or np.any(twtt <= 0.0):
        return Prescreen(gross=np.zeros(n, dtype=bool), fit_residual_m=np.zeros(n), threshold_m=np.inf)
    surface = float(np.min(np.concatenate([tx[:, 2], rx[:, 2]])))
    fit = robust_first_fit(tx, rx, twtt, options.sound_speed_mps, surface)
    fit_resid = fit.residual_m - np.median(fit.residual_m)
    threshold = max(options.prescreen_sigmas * fit.sigma_m, options.gross_error_m)
    gross = np.abs(fit_resid) > threshold
    if gross.sum() > options.max_gross_fraction * n:
        raise DataError(
            f"{survey.path}: {int(gross.sum())} of {n} pings ({100.0 * gross.mean():.0f} %) have travel "
            f"times no single transponder position explains (|residual| > {threshold:.2f} m at a robust "
            f"first fit), more than the {100.0 * options.max_gross_fraction:.0f} % allowed "
            "(max_gross_fraction): the survey cannot be solved reliably; check the travel-time column, "
            "its units and the turn-around delay"
        )
    return Prescreen(gross=gross, fit_residual_m=fit_resid, threshold_m=float(threshold))


def _refuse_gross_left(
    survey: GnssaSurvey, options: GnssaOptions, used: BoolArray, residual_m: FloatArray, n_excluded: int
) -> None:
    """A used ping with a residual above ``gross_error_m`` at the end means no reliable solution."""
    left = used & (np.abs(residual_m) > options.gross_error_m)
    if left.any():
        worst = int(np.argmax(np.where(left, np.abs(residual_m), 0.0)))
        raise DataError(
            f"{survey.path}: after excluding {n_excluded} pings, {int(left.sum())} used "
            f"pings still have |residual| > {options.gross_error_m:g} m (line {int(survey.line[worst])}: "
            f"{residual_m[worst]:+.1f} m): the survey cannot be solved reliably; check its travel times"
        )


@dataclass(frozen=True, slots=True, kw_only=True)
class GnssaCovariance:
    """The reported position covariance and its parts (:func:`gnssa_covariance`), (3, 3) m^2 each."""

    formal_m2: FloatArray
    jackknife_m2: FloatArray | None
    gnss_m2: FloatArray
    total_m2: FloatArray


def gnssa_covariance(
    survey: GnssaSurvey, options: GnssaOptions, setup: GnssaSetup, solution: RobustSolution
) -> GnssaCovariance:
    """Formal MAP covariance plus the positive part of (jackknife - formal), plus the survey-wide GNSS
    error when ``gnss_common_mode``."""
    used = solution.used
    problem = setup.template.with_mask(used[None, :], solution.sigma_m)
    cov_formal = solution.covariance[0, :3, :3]
    cov_jk = _jackknife(
        problem, setup.prior, setup.map_options, solution.x, setup.t_mid_s, used, options.jackknife_blocks
    )
    cov = cov_formal if cov_jk is None else cov_formal + _positive_part(cov_jk - cov_formal)
    cov_gnss = _gnss_common_mode(survey, used) if options.gnss_common_mode else np.zeros((3, 3))
    return GnssaCovariance(
        formal_m2=cov_formal, jackknife_m2=cov_jk, gnss_m2=cov_gnss, total_m2=cov + cov_gnss
    )


def _initial_guess(tx: FloatArray, twtt: FloatArray, speed: float) -> FloatArray:
    """Below the ping with the shortest travel time, at half its two-way path."""
    i = int(np.argmin(twtt))
    return np.array([tx[i, 0], tx[i, 1], tx[i, 2] - 0.5 * speed * twtt[i]])


def _gnss_variance(target: FloatArray, survey: GnssaSurvey) -> tuple[FloatArray, FloatArray]:
    """GNSS variance projected on both legs (eqs. 46-52) and tan(incidence) of each ping."""
    u_tx = range_jacobian(target, survey.transmit_enu_m)
    u_rx = range_jacobian(target, survey.receive_enu_m)
    var = np.sum((u_tx * survey.sigma_transmit_enu_m) ** 2, axis=-1)
    var += np.sum((u_rx * survey.sigma_receive_enu_m) ** 2, axis=-1)
    horiz = np.hypot(survey.transmit_enu_m[:, 0] - target[0], survey.transmit_enu_m[:, 1] - target[1])
    depth = np.maximum(survey.transmit_enu_m[:, 2] - target[2], 1e-3)
    return var, horiz / depth


def _path_residual(problem: GnssaProblem, x: FloatArray) -> FloatArray:
    """``c(t) TWTT - path`` in metres, ``(b, n)``."""
    return problem.speed(x) * problem.twtt_s - problem.path(x)[0]


def _variance_components(
    resid: FloatArray, gnss_var: FloatArray, tan_inc: FloatArray, with_beta: bool
) -> tuple[float, float]:
    """Maximum-likelihood ``sigma_path`` and ``beta`` of ``var_i = g_i + s^2 + beta^2 tan_i^2``."""
    e2 = resid * resid
    t2 = tan_inc * tan_inc

    def nll(q: FloatArray) -> float:
        var = gnss_var + np.exp(2.0 * q[0]) + (np.exp(2.0 * q[1]) * t2 if with_beta else 0.0)
        return float(np.sum(np.log(var) + e2 / var))

    start = np.log([max(np.sqrt(np.mean(e2)), 1e-3), 1e-2])
    from scipy.optimize import minimize

    q = minimize(nll, start, method="Nelder-Mead", options={"xatol": 1e-3, "fatol": 1e-6}).x
    return float(max(np.exp(q[0]), 1e-4)), float(np.exp(q[1])) if with_beta else 0.0


def _jackknife(
    problem: GnssaProblem,
    prior: GaussianPrior,
    map_opts: MapOptions,
    x: FloatArray,
    t_s: FloatArray,
    used: BoolArray,
    blocks: int,
) -> FloatArray | None:
    """Delete-one-block jackknife covariance of the position over contiguous time blocks."""
    idx = np.flatnonzero(used)
    if blocks < 2 or idx.size < 4 * blocks:
        return None
    order = idx[np.argsort(t_s[idx], kind="stable")]
    block_of = np.empty(problem.twtt_s.size, dtype=np.int64)
    block_of[order] = np.arange(order.size) * blocks // order.size
    masks = np.stack([used & (block_of != g) for g in range(blocks)])
    batch = problem.with_mask(masks)
    rep_prior = GaussianPrior(mean=np.repeat(prior.mean, blocks, axis=0), cov=prior.cov)
    reps = solve_map(batch, rep_prior, map_opts, initial=np.repeat(x, blocks, axis=0)).estimate[:, :3]
    dev = reps - reps.mean(axis=0)
    return (blocks - 1) / blocks * dev.T @ dev


def _gnss_common_mode(survey: GnssaSurvey, used: BoolArray) -> FloatArray:
    """Covariance of the survey-wide GNSS error: the mean per-ping GNSS variance of the used pings.

    Kinematic GNSS errors (troposphere, orbits and clocks, multipath, antenna phase centre) are
    correlated over hours, longer than a survey, so their common part shifts the whole surface track and
    the transponder with it, one for one, and no number of pings averages it down. The full per-ping
    variance is the limit of full correlation.
    """
    var = 0.5 * (survey.sigma_transmit_enu_m[used] ** 2 + survey.sigma_receive_enu_m[used] ** 2)
    return np.diag(np.mean(var, axis=0))


def _positive_part(matrix: FloatArray) -> FloatArray:
    """The positive semi-definite part of a symmetric matrix."""
    w, v = np.linalg.eigh(0.5 * (matrix + matrix.T))
    return (v * np.maximum(w, 0.0)) @ v.T


def gnssa_epoch_utc(epoch_s: float) -> str:
    """A GNSS-A epoch (seconds after 2020-01-01 UTC, the files' time base) as ISO 8601 UTC."""
    import datetime as dt

    stamp = dt.datetime.fromtimestamp(GPS_EPOCH_2020_UNIX_S + float(epoch_s), tz=dt.UTC)
    return stamp.isoformat(timespec="seconds")
