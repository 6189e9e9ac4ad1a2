"""USBL calibration: the beacon positions, the head's misalignment, its lever arm, the sound-speed scale,
the beacon's turn-around delay (and optionally a range bias) from the survey's own pings, by MAP.

The problem is built from factors (:mod:`oceanloc.estimation.factors`) over named blocks: per beacon a
:class:`~oceanloc.estimation.factors.RangeFactor` (eq. (2) of :mod:`oceanloc.models.usbl`) and a
:class:`~oceanloc.estimation.factors.DirectionFactor` (eq. (1)), optional
:class:`~oceanloc.estimation.factors.DepthFactor` s, and a prior on every block; the stacked system is
solved by :func:`~oceanloc.estimation.map_gauss_newton.solve_map`.

**Noise.** Each ping's range has the USBL's range noise plus the GNSS antenna error projected on the
line of sight; its azimuth and elevation have the head's angle noise (isotropic on the sphere: the
azimuth's standard deviation is ``sigma_angle / cos(el)``, reading the measured elevation, floored at
``min_cos_elevation``) plus the GNSS and vessel-attitude errors carried through the model's Jacobians,
as one 2x2 covariance per ping (azimuth and elevation are correlated through the attitude). The
projection is made at the starting point and again at the first solution (the folded noise depends on
the geometry, not on small changes of the estimate).

**Steps** (:func:`calibrate_usbl`, batched over ``B`` independent problems for Monte Carlo):

1. start from the fixes themselves (each beacon at the median of where the fixes put it with the
   prior's calibration) unless a start is given, and solve the full MAP;
2. re-fold the noise at that solution; decide which calibration parameters the pings cannot see
   (:func:`~oceanloc.estimation.observability.held_parameters`): they are held at their prior and named;
3. solve again with them held; the covariance includes their prior uncertainty
   (:func:`~oceanloc.estimation.observability.consider_covariance`);
4. check the linearization over the confidence ellipsoid (trusted or not), and keep the residuals.

Units: metres, radians and seconds inside; :class:`UsblCalibration` converts for people.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from oceanloc._typing import ArrayLike, BoolArray, FloatArray, IntArray, StrArray
from oceanloc.errors import ConfigError
from oceanloc.estimation.factors import (
    DepthFactor,
    DirectionFactor,
    FactorGraph,
    HeldModel,
    ParameterBlock,
    ParameterLayout,
    PriorFactor,
    RangeFactor,
)
from oceanloc.estimation.map_gauss_newton import GaussianPrior, MapOptions, solve_map
from oceanloc.estimation.observability import (
    DEFAULT_OBSERVABILITY_RATIO,
    consider_covariance,
    graph_linearization_check,
    held_parameters,
)
from oceanloc.models.usbl import (
    DEFAULT_SOUND_SPEED_MPS,
    apparent_beacon_enu_m,
    direction_residual_rad,
    usbl_direction_jacobian,
    usbl_range_jacobian,
)
from oceanloc.units import DEG

CALIBRATION_BLOCKS: tuple[str, ...] = ("misalignment", "lever_arm", "scale", "delay", "bias")
"""The calibration blocks, in state order after the beacons."""


def beacon_block(beacon_id: int) -> str:
    """The block name of a beacon's position (``"beacon 1"``)."""
    return f"beacon {int(beacon_id)}"


@dataclass(frozen=True, slots=True, kw_only=True)
class UsblNoise:
    """Measurement noise of a USBL calibration survey (1 sigma). Defaults: a SeaTrac-class head on a small
    vessel with an RTK GNSS and an attitude sensor (range 0.1 m, angles 0.5 deg, attitude 0.05 deg, GNSS
    2 cm horizontally and 5 cm vertically).

    Attributes
    ----------
    sigma_range_m : float
    sigma_angle_rad : float
        The head's direction noise (elevation; the azimuth's is this over ``cos el``).
    sigma_roll_pitch_rad, sigma_heading_rad : float
        Vessel attitude noise.
    sigma_horizontal_m, sigma_vertical_m : float
        GNSS antenna position noise per axis.
    min_cos_elevation : float
        Floor of ``cos el`` in the azimuth's noise (a beacon straight below has no azimuth).
    """

    sigma_range_m: float = 0.1
    sigma_angle_rad: float = 0.5 * DEG
    sigma_roll_pitch_rad: float = 0.05 * DEG
    sigma_heading_rad: float = 0.05 * DEG
    sigma_horizontal_m: float = 0.02
    sigma_vertical_m: float = 0.05
    min_cos_elevation: float = 0.02

    def __post_init__(self) -> None:
        if not (self.sigma_range_m > 0 and self.sigma_angle_rad > 0):
            raise ConfigError("the range and angle sigmas must be positive")
        for name in ("sigma_roll_pitch_rad", "sigma_heading_rad", "sigma_horizontal_m", "sigma_vertical_m"):
            if not getattr(self, name) >= 0.0:
                raise ConfigError(f"{name} must not be negative, got {getattr(self, name)}")
        if not 0.0 < self.min_cos_elevation <= 1.0:
            raise ConfigError(f"min_cos_elevation must be in (0, 1], got {self.min_cos_elevation}")

    def to_record(self) -> dict:
        return {
            "sigma_range_m": self.sigma_range_m,
            "sigma_angle_deg": self.sigma_angle_rad / DEG,
            "sigma_roll_pitch_deg": self.sigma_roll_pitch_rad / DEG,
            "sigma_heading_deg": self.sigma_heading_rad / DEG,
            "sigma_horizontal_m": self.sigma_horizontal_m,
            "sigma_vertical_m": self.sigma_vertical_m,
        }


@dataclass(frozen=True, slots=True, kw_only=True)
class UsblPings:
    """The pings of ``B`` calibration problems (Monte Carlo runs; ``B = 1`` for a recorded survey).

    Attributes
    ----------
    beacon : (n,) int
        Beacon id of each ping (the same sequence for every problem).
    antenna_enu_m : (B, n, 3) float
        Vessel reference (GNSS antenna) positions at the pings, ENU metres.
    attitude_rad : (B, n, 3) float
        Vessel roll, pitch and heading (clockwise from north), radians.
    range_m : (B, n) float
        Ranges, NaN where a ping has none.
    direction_rad : (B, n, 2) float
        Azimuth and elevation in the head's frame, NaN where a ping has none.
    t_s : (n,) float
        Ping times, seconds (for the reports; any origin).
    """

    beacon: IntArray
    antenna_enu_m: FloatArray
    attitude_rad: FloatArray
    range_m: FloatArray
    direction_rad: FloatArray
    t_s: FloatArray

    @classmethod
    def build(
        cls,
        beacon: ArrayLike,
        antenna_enu_m: ArrayLike,
        attitude_rad: ArrayLike,
        range_m: ArrayLike,
        direction_rad: ArrayLike,
        t_s: ArrayLike | None = None,
    ) -> UsblPings:
        """Validate and broadcast: arrays without the batch axis are one problem."""
        ids = np.asarray(beacon, dtype=np.int64).ravel()
        n = ids.size
        if n == 0:
            raise ConfigError("a calibration needs at least one ping")
        ant = np.asarray(antenna_enu_m, dtype=float)
        ant = ant[None] if ant.ndim == 2 else ant
        batch = ant.shape[0]

        def shaped(a: ArrayLike, tail: tuple[int, ...], name: str) -> FloatArray:
            arr = np.asarray(a, dtype=float)
            if arr.shape == (n, *tail):
                arr = arr[None]
            try:
                return np.ascontiguousarray(np.broadcast_to(arr, (batch, n, *tail)))
            except ValueError:
                raise ConfigError(f"{name} has shape {arr.shape}, expected {(batch, n, *tail)}") from None

        ant = shaped(ant, (3,), "antenna_enu_m")
        att = shaped(attitude_rad, (3,), "attitude_rad")
        rng = shaped(range_m, (), "range_m")
        dirs = shaped(direction_rad, (2,), "direction_rad")
        if not (np.all(np.isfinite(ant)) and np.all(np.isfinite(att))):
            raise ConfigError("antenna positions and attitudes must be finite at every ping")
        times = np.arange(n, dtype=float) if t_s is None else np.asarray(t_s, dtype=float).ravel()
        if times.shape != (n,):
            raise ConfigError(f"t_s has {times.size} times for {n} pings")
        return cls(
            beacon=ids, antenna_enu_m=ant, attitude_rad=att, range_m=rng, direction_rad=dirs, t_s=times
        )

    @property
    def batch(self) -> int:
        return int(self.antenna_enu_m.shape[0])

    @property
    def n(self) -> int:
        return int(self.beacon.size)

    @property
    def beacon_ids(self) -> IntArray:
        return np.unique(self.beacon)

    def head(self, count: int) -> UsblPings:
        """The first ``count`` pings (a survey as it stood after them)."""
        return UsblPings(
            beacon=self.beacon[:count],
            antenna_enu_m=self.antenna_enu_m[:, :count],
            attitude_rad=self.attitude_rad[:, :count],
            range_m=self.range_m[:, :count],
            direction_rad=self.direction_rad[:, :count],
            t_s=self.t_s[:count],
        )

    def take(self, rows: IntArray) -> UsblPings:
        """The problems ``rows`` of the batch."""
        return UsblPings(
            beacon=self.beacon,
            antenna_enu_m=self.antenna_enu_m[rows],
            attitude_rad=self.attitude_rad[rows],
            range_m=self.range_m[rows],
            direction_rad=self.direction_rad[rows],
            t_s=self.t_s,
        )


@dataclass(frozen=True, slots=True, kw_only=True)
class CalibrationPrior:
    """What is known before the calibration: a mean and a standard deviation per parameter.

    Attributes
    ----------
    beacon_ids : (M,) int
    beacon_enu_m : (M, 3) or (B, M, 3) float
        Beacon positions as dropped or last surveyed, ENU metres.
    beacon_sigma_m : (M, 3) float
    misalignment_rad, misalignment_sigma_rad : (3,) float
        Head roll, pitch, heading in the vessel frame (as installed) and their uncertainty.
    lever_arm_m, lever_arm_sigma_m : (3,) float
        Transducer from antenna in the vessel frame (forward, starboard, down), as measured.
    scale, scale_sigma : float
        Sound-speed scale ``c_0 / c``.
    delay_s, delay_sigma_s : float
        Uncompensated turn-around delay.
    bias_m, bias_sigma_m : float
        Constant range bias (estimated only when the options ask for it).
    """

    beacon_ids: IntArray
    beacon_enu_m: FloatArray
    beacon_sigma_m: FloatArray
    misalignment_rad: FloatArray = field(default_factory=lambda: np.zeros(3))
    misalignment_sigma_rad: FloatArray = field(default_factory=lambda: np.array([3.0, 3.0, 10.0]) * DEG)
    lever_arm_m: FloatArray = field(default_factory=lambda: np.zeros(3))
    lever_arm_sigma_m: FloatArray = field(default_factory=lambda: np.full(3, 0.1))
    scale: float = 1.0
    scale_sigma: float = 0.01
    delay_s: float = 0.0
    delay_sigma_s: float = 1e-3
    bias_m: float = 0.0
    bias_sigma_m: float = 0.5

    def __post_init__(self) -> None:
        ids = np.asarray(self.beacon_ids, dtype=np.int64).ravel()
        object.__setattr__(self, "beacon_ids", ids)
        for name, shape in (
            ("misalignment_rad", (3,)),
            ("misalignment_sigma_rad", (3,)),
            ("lever_arm_m", (3,)),
            ("lever_arm_sigma_m", (3,)),
            ("beacon_sigma_m", (ids.size, 3)),
        ):
            arr = np.asarray(getattr(self, name), dtype=float)
            try:
                arr = np.broadcast_to(arr, shape).copy()
            except ValueError:
                raise ConfigError(f"prior {name} has shape {arr.shape}, expected {shape}") from None
            object.__setattr__(self, name, arr)
        mean = np.asarray(self.beacon_enu_m, dtype=float)
        if mean.shape[-2:] != (ids.size, 3):
            raise ConfigError(f"prior beacon_enu_m has shape {mean.shape}, expected (..., {ids.size}, 3)")
        object.__setattr__(self, "beacon_enu_m", mean)
        sigmas = [self.misalignment_sigma_rad, self.lever_arm_sigma_m, self.beacon_sigma_m]
        sigmas += [np.array([self.scale_sigma, self.delay_sigma_s, self.bias_sigma_m])]
        if not all(np.all(np.isfinite(s) & (s > 0.0)) for s in sigmas):
            raise ConfigError("every prior standard deviation must be positive and finite")
        if not np.all(np.isfinite(mean)):
            raise ConfigError("prior beacon positions must be finite")


@dataclass(frozen=True, slots=True, kw_only=True)
class CalibrationOptions:
    """Settings of :func:`calibrate_usbl`.

    Attributes
    ----------
    sound_speed_mps : float
        The sound speed the USBL was configured with (``c_0``: the scale is relative to it).
    estimate_delay : bool
        Estimate the turn-around delay (else it is fixed at its prior).
    estimate_bias : bool
        Estimate a constant range bias too (it is indistinguishable from the delay: one of them is held).
    observability_ratio : float
        Data/prior information ratio below which a parameter is held at its prior.
    confidence : float
        Of the linearization check's ellipsoid.
    max_iterations : int
    depths : tuple of (beacon id, depth m, sigma m)
        Measured beacon depths (its pressure sensor, an echo sounder), below the surface at ENU up 0.
    """

    sound_speed_mps: float = DEFAULT_SOUND_SPEED_MPS
    estimate_delay: bool = True
    estimate_bias: bool = False
    observability_ratio: float = DEFAULT_OBSERVABILITY_RATIO
    confidence: float = 0.95
    max_iterations: int = 100
    depths: tuple[tuple[int, float, float], ...] = ()

    def __post_init__(self) -> None:
        if not 1300.0 <= self.sound_speed_mps <= 1700.0:
            raise ConfigError(f"sound speed {self.sound_speed_mps} m/s is outside [1300, 1700]")
        if not self.observability_ratio > 0:
            raise ConfigError(f"observability_ratio must be positive, got {self.observability_ratio}")
        if not 0.0 < self.confidence < 1.0:
            raise ConfigError(f"confidence must be in (0, 1), got {self.confidence}")
        if self.max_iterations < 1:
            raise ConfigError(f"max_iterations must be at least 1, got {self.max_iterations}")
        for _, depth, sigma in self.depths:
            if not (np.isfinite(depth) and sigma > 0):
                raise ConfigError(
                    f"a beacon depth needs a finite value and a positive sigma, got {depth}, {sigma}"
                )


def calibration_layout(beacon_ids: ArrayLike, options: CalibrationOptions) -> ParameterLayout:
    """The state: each beacon's position, then the misalignment, lever arm, scale, delay and bias blocks
    (delay and bias only where the options estimate them)."""
    blocks = [ParameterBlock(beacon_block(b), ("east", "north", "up"), ("m", "m", "m")) for b in beacon_ids]
    blocks += [
        ParameterBlock("misalignment", ("roll", "pitch", "heading"), ("rad", "rad", "rad")),
        ParameterBlock("lever_arm", ("forward", "starboard", "down"), ("m", "m", "m")),
        ParameterBlock("scale", ("scale",), ("1",)),
    ]
    if options.estimate_delay:
        blocks.append(ParameterBlock("delay", ("delay",), ("s",)))
    if options.estimate_bias:
        blocks.append(ParameterBlock("bias", ("bias",), ("m",)))
    return ParameterLayout(tuple(blocks))


def _prior_factors(layout: ParameterLayout, prior: CalibrationPrior, batch: int) -> list[PriorFactor]:
    beacon_mean = np.broadcast_to(prior.beacon_enu_m, (batch, prior.beacon_ids.size, 3))
    out = [
        PriorFactor(key=beacon_block(b), mean=beacon_mean[:, i], cov=np.diag(prior.beacon_sigma_m[i] ** 2))
        for i, b in enumerate(prior.beacon_ids)
    ]
    out += [
        PriorFactor(
            key="misalignment", mean=prior.misalignment_rad, cov=np.diag(prior.misalignment_sigma_rad**2)
        ),
        PriorFactor(key="lever_arm", mean=prior.lever_arm_m, cov=np.diag(prior.lever_arm_sigma_m**2)),
        PriorFactor(key="scale", mean=np.array([prior.scale]), cov=np.array([[prior.scale_sigma**2]])),
    ]
    if "delay" in layout.names:
        out.append(
            PriorFactor(key="delay", mean=np.array([prior.delay_s]), cov=np.array([[prior.delay_sigma_s**2]]))
        )
    if "bias" in layout.names:
        out.append(
            PriorFactor(key="bias", mean=np.array([prior.bias_m]), cov=np.array([[prior.bias_sigma_m**2]]))
        )
    return [
        PriorFactor(key=p.key, mean=np.broadcast_to(p.mean, (batch, p.mean.shape[-1])), cov=p.cov)
        for p in out
    ]


@dataclass(frozen=True, slots=True, kw_only=True)
class _Values:
    """Calibration values per ping, for folding noise and for the apparent positions."""

    beacon: FloatArray  # (B, n, 3)
    misalignment: FloatArray  # (B, 1, 3)
    lever: FloatArray  # (B, 1, 3)
    scale: FloatArray  # (B, 1)
    delay: FloatArray  # (B, 1)
    bias: FloatArray  # (B, 1)


def _values(layout: ParameterLayout, x: FloatArray, pings: UsblPings, prior: CalibrationPrior) -> _Values:
    v = layout.split(x)
    beacons = np.stack([v[beacon_block(b)] for b in prior.beacon_ids], axis=1)  # (B, M, 3)
    index = np.searchsorted(prior.beacon_ids, pings.beacon)
    batch = x.shape[0]

    def scalar(key: str, default: float) -> FloatArray:
        return v[key][:, :1] if key in v else np.full((batch, 1), default)

    return _Values(
        beacon=beacons[:, index],
        misalignment=v["misalignment"][:, None, :],
        lever=v["lever_arm"][:, None, :],
        scale=scalar("scale", prior.scale),
        delay=scalar("delay", prior.delay_s),
        bias=scalar("bias", prior.bias_m),
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class _FoldedNoise:
    sigma_range_m: FloatArray  # (B, n), inf where no range
    sqrt_information: FloatArray  # (B, n, 2, 2), 0 where no direction


def fold_noise(pings: UsblPings, values: _Values, noise: UsblNoise, sound_speed_mps: float) -> _FoldedNoise:
    """Each ping's range sigma and 2x2 angle whitening with the GNSS and attitude noise carried through
    the model's Jacobians at ``values`` (module docstring)."""
    g_var = np.array([noise.sigma_horizontal_m**2, noise.sigma_horizontal_m**2, noise.sigma_vertical_m**2])
    a_var = np.array(
        [noise.sigma_roll_pitch_rad**2, noise.sigma_roll_pitch_rad**2, noise.sigma_heading_rad**2]
    )
    rj = usbl_range_jacobian(
        values.beacon,
        pings.antenna_enu_m,
        pings.attitude_rad,
        values.lever,
        values.scale,
        values.delay,
        values.bias,
        sound_speed_mps,
    )
    var_r = noise.sigma_range_m**2 + np.sum(rj.antenna**2 * g_var, -1) + np.sum(rj.attitude**2 * a_var, -1)
    has_range = np.isfinite(pings.range_m)
    sigma_r = np.where(has_range, np.sqrt(var_r), np.inf)
    dj = usbl_direction_jacobian(
        values.beacon, pings.antenna_enu_m, pings.attitude_rad, values.lever, values.misalignment
    )
    el = np.where(np.isfinite(pings.direction_rad[..., 1]), pings.direction_rad[..., 1], dj.angles[..., 1])
    cos_el = np.maximum(np.cos(el), noise.min_cos_elevation)
    cov = np.zeros((*el.shape, 2, 2))
    cov[..., 0, 0] = (noise.sigma_angle_rad / cos_el) ** 2
    cov[..., 1, 1] = noise.sigma_angle_rad**2
    cov += np.einsum("...ik,k,...jk->...ij", dj.antenna, g_var, dj.antenna)
    cov += np.einsum("...ik,k,...jk->...ij", dj.attitude, a_var, dj.attitude)
    # W = L^-1 for the lower Cholesky factor L of the 2x2 covariance: W^T W = cov^-1.
    l00 = np.sqrt(cov[..., 0, 0])
    l10 = cov[..., 1, 0] / l00
    l11 = np.sqrt(np.maximum(cov[..., 1, 1] - l10 * l10, 1e-300))
    w = np.zeros_like(cov)
    w[..., 0, 0] = 1.0 / l00
    w[..., 1, 0] = -l10 / (l00 * l11)
    w[..., 1, 1] = 1.0 / l11
    has_dir = np.all(np.isfinite(pings.direction_rad), axis=-1)
    return _FoldedNoise(sigma_range_m=sigma_r, sqrt_information=w * has_dir[..., None, None])


def build_calibration_graph(
    pings: UsblPings,
    prior: CalibrationPrior,
    noise: UsblNoise,
    options: CalibrationOptions,
    linearize_at: FloatArray | None = None,
) -> FactorGraph:
    """The calibration's factor graph: per beacon a range and a direction factor over its pings, the
    depth factors, and a prior on every block; the noise folded at ``linearize_at`` (``(B, d)``; the
    prior mean by default)."""
    _check_beacons(pings, prior)
    layout = calibration_layout(prior.beacon_ids, options)
    priors = _prior_factors(layout, prior, pings.batch)
    graph0 = FactorGraph(layout, [], priors)
    x = graph0.prior_arrays()[0] if linearize_at is None else np.asarray(linearize_at, dtype=float)
    folded = fold_noise(pings, _values(layout, x, pings, prior), noise, options.sound_speed_mps)
    factors: list = []
    has_range = np.isfinite(pings.range_m)
    cal_keys = {k: (k if k in layout.names else None) for k in ("scale", "delay", "bias")}
    for b in prior.beacon_ids:
        sel = np.flatnonzero(pings.beacon == b)
        if sel.size == 0:
            continue
        key = beacon_block(b)
        factors.append(
            RangeFactor(
                target=key,
                ranges_m=np.where(has_range[:, sel], pings.range_m[:, sel], 0.0),
                sigma_m=np.where(has_range[:, sel], folded.sigma_range_m[:, sel], 1.0),
                mask=has_range[:, sel],
                antenna_enu_m=pings.antenna_enu_m[:, sel],
                attitude_rad=pings.attitude_rad[:, sel],
                lever_arm="lever_arm",
                scale=cal_keys["scale"],
                delay=cal_keys["delay"],
                bias=cal_keys["bias"],
                sound_speed_mps=options.sound_speed_mps,
            )
        )
        factors.append(
            DirectionFactor(
                beacon=key,
                misalignment="misalignment",
                lever_arm="lever_arm",
                measured_rad=np.nan_to_num(pings.direction_rad[:, sel]),
                antenna_enu_m=pings.antenna_enu_m[:, sel],
                attitude_rad=pings.attitude_rad[:, sel],
                sqrt_information=folded.sqrt_information[:, sel],
            )
        )
    for b, depth, sigma in options.depths:
        if int(b) not in prior.beacon_ids:
            raise ConfigError(f"a depth is given for beacon {b}, which has no prior position")
        shape = (pings.batch, 1)
        factors.append(
            DepthFactor(
                beacon=beacon_block(b),
                depth_m=np.full(shape, float(depth)),
                sigma_m=np.full(shape, float(sigma)),
            )
        )
    return FactorGraph(layout, factors, priors)


def _check_beacons(pings: UsblPings, prior: CalibrationPrior) -> None:
    missing = sorted(set(pings.beacon_ids.tolist()) - set(prior.beacon_ids.tolist()))
    if missing:
        raise ConfigError(f"pings to beacon(s) {missing} have no prior position")


def initial_guess(pings: UsblPings, prior: CalibrationPrior, options: CalibrationOptions) -> FloatArray:
    """A start ``(B, d)``: the prior, with each beacon at the median of where its fixes put it with the
    prior's calibration (the prior position where fewer than three fixes have both range and angles)."""
    _check_beacons(pings, prior)
    layout = calibration_layout(prior.beacon_ids, options)
    graph = FactorGraph(layout, [], _prior_factors(layout, prior, pings.batch))
    x = graph.prior_arrays()[0].copy()
    vals = _values(layout, x, pings, prior)
    app = apparent_beacon_enu_m(
        pings.range_m,
        pings.direction_rad,
        pings.antenna_enu_m,
        pings.attitude_rad,
        vals.lever,
        vals.misalignment,
        vals.scale,
        vals.delay,
        vals.bias,
        options.sound_speed_mps,
    )
    ok = np.all(np.isfinite(app), axis=-1)
    for b in prior.beacon_ids:
        sel = pings.beacon == b
        for row in range(pings.batch):
            use = ok[row] & sel
            if use.sum() >= 3:
                x[row, layout.index(beacon_block(b))] = np.median(app[row, use], axis=0)
    return x


@dataclass(frozen=True, slots=True, kw_only=True)
class UsblCalibration:
    """The result of :func:`calibrate_usbl` for ``B`` problems.

    Attributes
    ----------
    layout : ParameterLayout
    beacon_ids : (M,) int
    estimate : (B, d) float
        Held parameters at their prior mean. Units of :meth:`ParameterLayout.component_units`.
    covariance : (B, d, d) float
        Error covariance, held parameters' prior uncertainty carried into the others (consider).
    prior_mean : (B, d) float
    prior_cov : (B, d, d) float
    held : (B, d) bool
    notes : tuple of B tuples of str
        Why each held parameter is held (and what the track cannot determine).
    data_ratio : (B, d) float
        Eigenvalues of the data's information in prior units, ascending (the observability report).
    trusted : (B,) bool
        The linearization check passed (the covariance can be believed).
    check_statistic : (B,) float
        ``max |log ratio|`` of that check.
    status : (B,) str
        Of the final MAP solve (``converged``, ``max-iterations``, ...).
    message : (B,) str
    iterations : (B,) int
    range_residual_m : (B, n) float
        Measured less modelled range, NaN where no range.
    direction_residual_rad : (B, n, 2) float
        Azimuth (wrapped) and elevation residuals, NaN where no angles.
    normalized_residual : (B, n, 3) float
        The same whitened (range, then the two whitened angle rows).
    cost : (B,) float
        Final ``J_MAP``.
    """

    layout: ParameterLayout
    beacon_ids: IntArray
    estimate: FloatArray
    covariance: FloatArray
    prior_mean: FloatArray
    prior_cov: FloatArray
    held: BoolArray
    notes: tuple[tuple[str, ...], ...]
    data_ratio: FloatArray
    trusted: BoolArray
    check_statistic: FloatArray
    status: StrArray
    message: StrArray
    iterations: IntArray
    range_residual_m: FloatArray
    direction_residual_rad: FloatArray
    normalized_residual: FloatArray
    cost: FloatArray

    @property
    def sigma(self) -> FloatArray:
        """Standard deviations ``(B, d)``."""
        return np.sqrt(np.maximum(np.diagonal(self.covariance, axis1=-2, axis2=-1), 0.0))

    @property
    def correlation(self) -> FloatArray:
        """Correlation matrices ``(B, d, d)``."""
        s = self.sigma
        return self.covariance / np.maximum(s[..., :, None] * s[..., None, :], 1e-300)

    def block(self, name: str) -> FloatArray:
        """One block of the estimate, ``(B, size)``."""
        return self.estimate[:, self.layout.index(name)]

    def block_sigma(self, name: str) -> FloatArray:
        return self.sigma[:, self.layout.index(name)]

    def calibration_index(self) -> IntArray:
        """The components of the calibration blocks (not the beacons)."""
        return np.concatenate(
            [
                np.arange(self.layout.dim)[self.layout.index(n)]
                for n in CALIBRATION_BLOCKS
                if n in self.layout.names
            ]
        )

    def information(self) -> FloatArray:
        """Inverse of the covariance, ``(B, d, d)``."""
        return np.linalg.inv(self.covariance)

    def nees(self, truth: ArrayLike, index: ArrayLike | None = None) -> FloatArray:
        """``e^T P^-1 e`` of ``estimate - truth`` over the components ``index`` (all by default): chi-square
        with ``len(index)`` degrees of freedom for a consistent estimator."""
        idx = np.arange(self.layout.dim) if index is None else np.asarray(index, dtype=np.int64)
        e = (self.estimate - np.asarray(truth, dtype=float))[:, idx]
        cov = self.covariance[:, idx][:, :, idx]
        return np.einsum("bi,bi->b", e, np.linalg.solve(cov, e[..., None])[..., 0])

    def horizontal_covariance_m2(self, beacon_id: int) -> FloatArray:
        """The beacon's east-north covariance ``(B, 2, 2)``."""
        sl = self.layout.index(beacon_block(beacon_id))
        i = np.arange(self.layout.dim)[sl][:2]
        return self.covariance[:, i][:, :, i]


def calibrate_usbl(
    pings: UsblPings,
    prior: CalibrationPrior,
    noise: UsblNoise | None = None,
    options: CalibrationOptions | None = None,
    initial: ArrayLike | None = None,
) -> UsblCalibration:
    """Calibrate a USBL from its pings (module docstring), batched over ``pings.batch`` problems.

    Parameters
    ----------
    pings : UsblPings
    prior : CalibrationPrior
    noise : UsblNoise, optional
    options : CalibrationOptions, optional
    initial : (B, d) float, optional
        A start (the previous epoch's estimate in a sequential survey); by default :func:`initial_guess`.

    Raises
    ------
    ConfigError
        If a ping's beacon has no prior, or the prior or options are invalid.
    """
    noise = noise or UsblNoise()
    opts = options or CalibrationOptions()
    map_opts = MapOptions(delta_min_m=1e-9, max_iterations=opts.max_iterations, surface_z_m=None)
    x0 = initial_guess(pings, prior, opts) if initial is None else np.array(initial, dtype=float)
    graph = build_calibration_graph(pings, prior, noise, opts, linearize_at=x0)
    gprior = graph.prior()
    if x0.shape != gprior.mean.shape:
        raise ConfigError(f"initial has shape {x0.shape}, expected {gprior.mean.shape}")
    first = solve_map(graph, gprior, map_opts, initial=x0)
    graph = build_calibration_graph(pings, prior, noise, opts, linearize_at=first.estimate)
    layout = graph.layout
    all_rows = np.arange(pings.batch)
    _, jac = graph.evaluate(first.estimate, all_rows)
    holdable = np.zeros(layout.dim, dtype=bool)
    holdable[
        np.concatenate(
            [np.arange(layout.dim)[layout.index(n)] for n in layout.names if not n.startswith("beacon")]
        )
    ] = True
    decision = held_parameters(
        np.swapaxes(jac, 1, 2) @ jac, gprior.cov, layout.component_names(), holdable, opts.observability_ratio
    )
    estimate = first.estimate.copy()
    covariance = np.empty_like(gprior.cov)
    status = first.status.astype("<U14").copy()
    message = first.message.astype(object).copy()
    iterations = first.iterations.copy()
    cost = first.cost.copy()
    trusted = np.zeros(pings.batch, dtype=bool)
    statistic = np.zeros(pings.batch)
    masks, group = np.unique(decision.held, axis=0, return_inverse=True)
    for g, mask in enumerate(masks):
        rows = np.flatnonzero(group.ravel() == g)
        sub = _take_graph(graph, rows)
        values = np.where(mask, gprior.mean[rows], estimate[rows])
        free = np.flatnonzero(~mask)
        held_model = HeldModel(sub, mask, values)
        sub_prior = GaussianPrior(mean=gprior.mean[rows][:, free], cov=gprior.cov[rows][:, free][:, :, free])
        res = solve_map(held_model, sub_prior, map_opts, initial=values[:, free])
        full = held_model.expand(res.estimate, np.arange(rows.size))
        _, jac_g = sub.evaluate(full, np.arange(rows.size))
        cov_g, p_free = consider_covariance(jac_g, gprior.cov[rows], mask)
        check = graph_linearization_check(
            sub.residuals, full, free, p_free, gprior.mean[rows], gprior.cov[rows], confidence=opts.confidence
        )
        estimate[rows], covariance[rows] = full, cov_g
        status[rows], message[rows] = res.status, res.message
        iterations[rows] += res.iterations
        cost[rows] = res.cost
        trusted[rows], statistic[rows] = check.trusted, check.statistic
    data_ratio = _data_ratio(jac, gprior.cov)
    resid = _residuals(graph, pings, prior, layout, estimate, opts)
    return UsblCalibration(
        layout=layout,
        beacon_ids=prior.beacon_ids,
        estimate=estimate,
        covariance=covariance,
        prior_mean=gprior.mean,
        prior_cov=gprior.cov,
        held=decision.held,
        notes=decision.notes,
        data_ratio=data_ratio,
        trusted=trusted,
        check_statistic=statistic,
        status=status,
        message=message.astype(str),
        iterations=iterations,
        range_residual_m=resid[0],
        direction_residual_rad=resid[1],
        normalized_residual=resid[2],
        cost=cost,
    )


def _data_ratio(jac: FloatArray, prior_cov: FloatArray) -> FloatArray:
    from oceanloc.estimation.observability import observability

    return observability(np.swapaxes(jac, 1, 2) @ jac, prior_cov).ratio


class _RowsGraph:
    """A graph restricted to some problems of its batch (rows renumbered from 0)."""

    def __init__(self, graph: FactorGraph, rows: IntArray) -> None:
        self.graph, self.rows_map = graph, rows

    @property
    def batch_size(self) -> int:
        return int(self.rows_map.size)

    def evaluate(self, x: FloatArray, rows: IntArray) -> tuple[FloatArray, FloatArray]:
        return self.graph.evaluate(x, self.rows_map[rows])

    def residuals(self, x: FloatArray, rows: IntArray) -> FloatArray:
        return self.graph.residuals(x, self.rows_map[rows])

    def structure(self) -> BoolArray:
        return self.graph.structure()


def _take_graph(graph: FactorGraph, rows: IntArray):
    return (
        graph
        if rows.size == graph.batch_size and np.array_equal(rows, np.arange(rows.size))
        else _RowsGraph(graph, rows)
    )


def _residuals(
    graph: FactorGraph,
    pings: UsblPings,
    prior: CalibrationPrior,
    layout: ParameterLayout,
    x: FloatArray,
    opts: CalibrationOptions,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Per-ping range and angle residuals at ``x``, raw and whitened."""
    vals = _values(layout, x, pings, prior)
    rj = usbl_range_jacobian(
        vals.beacon,
        pings.antenna_enu_m,
        pings.attitude_rad,
        vals.lever,
        vals.scale,
        vals.delay,
        vals.bias,
        opts.sound_speed_mps,
    )
    dj = usbl_direction_jacobian(
        vals.beacon, pings.antenna_enu_m, pings.attitude_rad, vals.lever, vals.misalignment
    )
    r_res = pings.range_m - rj.range_m
    d_res = direction_residual_rad(pings.direction_rad, dj.angles)
    normalized = np.full((pings.batch, pings.n, 3), np.nan)
    parts = graph.factor_residuals(x, np.arange(pings.batch))
    k = 0
    for b in prior.beacon_ids:
        sel = np.flatnonzero(pings.beacon == b)
        if sel.size == 0:
            continue
        normalized[:, sel, 0] = parts[k]
        normalized[:, sel, 1:] = parts[k + 1].reshape(pings.batch, sel.size, 2)
        k += 2
    normalized[:, :, 0] = np.where(np.isfinite(pings.range_m), normalized[:, :, 0], np.nan)
    has_dir = np.all(np.isfinite(pings.direction_rad), axis=-1)
    normalized[:, :, 1:] = np.where(has_dir[..., None], normalized[:, :, 1:], np.nan)
    return r_res, d_res, normalized


def apparent_positions(
    pings: UsblPings,
    calibration: UsblCalibration,
    prior: CalibrationPrior,
    options: CalibrationOptions | None = None,
    *,
    calibrated: bool = True,
) -> FloatArray:
    """Where each fix puts its beacon, ``(B, n, 3)`` ENU metres, with the calibrated values (or, with
    ``calibrated=False``, the prior's: what the USBL showed before)."""
    opts = options or CalibrationOptions()
    x = calibration.estimate if calibrated else calibration.prior_mean
    vals = _values(calibration.layout, x, pings, prior)
    return apparent_beacon_enu_m(
        pings.range_m,
        pings.direction_rad,
        pings.antenna_enu_m,
        pings.attitude_rad,
        vals.lever,
        vals.misalignment,
        vals.scale,
        vals.delay,
        vals.bias,
        opts.sound_speed_mps,
    )
