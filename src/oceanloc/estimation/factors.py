"""MAP problems built from factors over named parameter blocks, stacked into the system ``solve_map`` solves.

GTSAM's lesson (``NonlinearFactorGraph``, ``Values``, an optimizer, ``Marginals``), written small and
batched for Monte Carlo:

* :class:`ParameterBlock` and :class:`ParameterLayout` - the named unknowns (a beacon's position, the
  head's misalignment, the lever arm, the sound-speed scale, the turn-around delay, a range bias) and
  where each sits in the stacked state vector ``x (B, d)`` (GTSAM's keys and ``Values``).
* **Factors** - one measurement kind each, with a whitened residual ``(z - h(x)) / sigma`` and its
  whitened Jacobian ``(dh/dx) / sigma`` on the blocks it names (:class:`Factor`):
  :class:`RangeFactor` (a range, from known sensor positions or from an antenna, an attitude and a lever
  arm, with optional scale, delay and bias), :class:`DirectionFactor` (USBL azimuth and elevation,
  2x2 whitened per ping), :class:`DepthFactor` (a measured beacon depth) and :class:`PriorFactor`.
* :class:`FactorGraph` - the stacking step. Its :meth:`~FactorGraph.evaluate` concatenates every
  factor's rows into the whitened residual ``(b, N)`` and the dense Jacobian ``(b, N, d)``: it *is* a
  :class:`~oceanloc.estimation.map_gauss_newton.WhitenedModel`, the one interface between this layer
  and :func:`~oceanloc.estimation.map_gauss_newton.solve_map` (which owns the iteration, step control
  and covariance). The prior factors become the solver's
  :class:`~oceanloc.estimation.map_gauss_newton.GaussianPrior` (:meth:`FactorGraph.prior`): every block
  needs one, so the information is always invertible.
* :class:`HeldModel` - the same system with some components held at fixed values (the parameters a
  track cannot see, :mod:`oceanloc.estimation.usbl_calibration`).

The contract with ``solve_map`` is therefore: ``batch_size``, ``evaluate(x (b, d), rows (b,)) ->
(residual (b, N), jacobian (b, N, d))`` with masked measurements as zero rows, and ``residuals(x, rows)``
for a cost alone. Nothing here depends on how ``solve_map`` iterates.

The transponder survey's range problem (:class:`~oceanloc.estimation.map_gauss_newton.RangeProblem`)
is one :class:`RangeFactor` on one block, and gives the same numbers bit for bit as before the factors.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

import numpy as np

from oceanloc._typing import ArrayLike, BoolArray, FloatArray, IntArray
from oceanloc.errors import ConfigError
from oceanloc.models.measurements import range_jacobian, range_m
from oceanloc.models.usbl import (
    DEFAULT_SOUND_SPEED_MPS,
    direction_residual_rad,
    usbl_direction_jacobian,
    usbl_direction_rad,
    usbl_range_jacobian,
    usbl_range_m,
    vessel_rotation,
)

if TYPE_CHECKING:
    from oceanloc.estimation.map_gauss_newton import GaussianPrior


@dataclass(frozen=True, slots=True)
class ParameterBlock:
    """A named group of unknowns: ``name`` (``beacon 1``, ``misalignment``), one label and unit per
    component (``("east", "north", "up")``, ``("m", "m", "m")``)."""

    name: str
    labels: tuple[str, ...]
    units: tuple[str, ...]

    def __post_init__(self) -> None:
        if not self.name or not self.labels or len(self.labels) != len(self.units):
            raise ConfigError(f"parameter block {self.name!r} needs one unit per label")

    @property
    def size(self) -> int:
        return len(self.labels)


@dataclass(frozen=True, slots=True)
class ParameterLayout:
    """Where each block sits in the state vector: blocks in order, contiguous."""

    blocks: tuple[ParameterBlock, ...]
    offsets: dict[str, int] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        names = [b.name for b in self.blocks]
        if len(set(names)) != len(names):
            raise ConfigError(f"parameter block names must be unique, got {names}")
        offsets, at = {}, 0
        for b in self.blocks:
            offsets[b.name] = at
            at += b.size
        object.__setattr__(self, "offsets", offsets)

    @property
    def dim(self) -> int:
        return sum(b.size for b in self.blocks)

    def block(self, name: str) -> ParameterBlock:
        for b in self.blocks:
            if b.name == name:
                return b
        raise ConfigError(f"no parameter block {name!r} (blocks: {', '.join(self.names)})")

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(b.name for b in self.blocks)

    def index(self, name: str) -> slice:
        """The block's slice of the state vector."""
        block = self.block(name)
        start = self.offsets[name]
        return slice(start, start + block.size)

    def split(self, x: FloatArray) -> dict[str, FloatArray]:
        """``x (..., d)`` as a mapping of block name to ``(..., size)`` views (GTSAM's ``Values``)."""
        return {b.name: x[..., self.index(b.name)] for b in self.blocks}

    def component_names(self) -> tuple[str, ...]:
        """``"block label"`` for every component, in state order (``"misalignment roll"``; a one-component
        block labelled with its own name is just its name, ``"scale"``)."""
        return tuple(b.name if lab == b.name else f"{b.name} {lab}" for b in self.blocks for lab in b.labels)

    def component_units(self) -> tuple[str, ...]:
        return tuple(u for b in self.blocks for u in b.units)


@dataclass(frozen=True, slots=True, kw_only=True)
class Linearized:
    """A factor's whitened residual ``(b, rows)`` and its whitened Jacobian on each of its keys,
    ``(b, rows, size)``, in the order of the factor's ``keys``."""

    residual: FloatArray
    jacobians: tuple[FloatArray, ...]


class Factor(Protocol):
    """One measurement kind over named blocks (``keys``): ``rows`` whitened residual rows per problem of a
    batch of ``batch_size``; ``linearize(values, rows)`` at the block values (``name -> (b, size)``) of
    the problems ``rows``; ``residual(values, rows)`` the residual alone."""

    @property
    def keys(self) -> tuple[str, ...]: ...

    @property
    def rows(self) -> int: ...

    @property
    def batch_size(self) -> int: ...

    def linearize(self, values: Mapping[str, FloatArray], rows: IntArray) -> Linearized: ...

    def residual(self, values: Mapping[str, FloatArray], rows: IntArray) -> FloatArray: ...


def _batch_array(value: ArrayLike, shape: tuple[int, ...], name: str) -> FloatArray:
    arr = np.asarray(value, dtype=float)
    try:
        return np.broadcast_to(arr, shape)
    except ValueError:
        raise ConfigError(f"{name} has shape {arr.shape}, expected {shape}") from None


@dataclass(frozen=True, slots=True, kw_only=True)
class RangeFactor:
    """Ranges from a sensor to one target block (journal eq. 3-4, and eq. (2) of :mod:`oceanloc.models.usbl`).

    Two kinds of sensor:

    * **known positions** (``sensor_m``, the transponder survey): ``h = |p - s|``, Jacobian the unit line
      of sight (journal eq. 8);
    * **an antenna with an attitude and a lever-arm block** (``antenna_enu_m``, ``attitude_rad``,
      ``lever_arm`` key; the USBL calibration): ``h = s |p - p_A - R l| + c_0 tau / 2 + b`` with the
      optional ``scale``, ``delay`` and ``bias`` blocks (absent: 1, 0, 0).

    Attributes
    ----------
    target : str
        Key of the target's position block (3 components, ENU metres).
    ranges_m : (B, n) float
    sigma_m : (B, n) float
        Range standard deviations, metres (the USBL calibration folds GNSS noise into them).
    mask : (B, n) bool
        Measurements used.
    sensor_m : (B, n, 3) float or None
        Known sensor positions.
    antenna_enu_m, attitude_rad : (B, n, 3) float or None
        Antenna positions and vessel roll, pitch, heading, when the sensor is a lever arm away.
    lever_arm, scale, delay, bias : str or None
        Keys of the calibration blocks (3, 1, 1 and 1 components).
    sound_speed_mps : float
        ``c_0`` of the delay term.
    """

    target: str
    ranges_m: FloatArray
    sigma_m: FloatArray
    mask: BoolArray
    sensor_m: FloatArray | None = None
    antenna_enu_m: FloatArray | None = None
    attitude_rad: FloatArray | None = None
    lever_arm: str | None = None
    scale: str | None = None
    delay: str | None = None
    bias: str | None = None
    sound_speed_mps: float = DEFAULT_SOUND_SPEED_MPS
    rotation: FloatArray | None = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        if (self.sensor_m is None) == (self.lever_arm is None):
            raise ConfigError("a range factor needs either known sensor positions or a lever-arm block")
        if self.lever_arm is not None:
            if self.antenna_enu_m is None or self.attitude_rad is None:
                raise ConfigError("a range factor with a lever arm needs antenna positions and attitudes")
            if self.rotation is None:
                object.__setattr__(self, "rotation", vessel_rotation(self.attitude_rad))

    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(k for k in (self.target, self.lever_arm, self.scale, self.delay, self.bias) if k)

    @property
    def rows(self) -> int:
        return int(self.ranges_m.shape[-1])

    @property
    def batch_size(self) -> int:
        return int(self.ranges_m.shape[0])

    def _weight(self, rows: IntArray) -> FloatArray:
        return np.where(self.mask[rows], 1.0 / self.sigma_m[rows], 0.0)

    def linearize(self, values: Mapping[str, FloatArray], rows: IntArray) -> Linearized:
        weight = self._weight(rows)
        target = values[self.target][:, None, :]
        if self.sensor_m is not None:
            sensors = self.sensor_m[rows]
            resid = (self.ranges_m[rows] - range_m(target, sensors)) * weight
            return Linearized(
                residual=resid, jacobians=(range_jacobian(target, sensors) * weight[..., None],)
            )
        assert self.antenna_enu_m is not None and self.attitude_rad is not None and self.lever_arm is not None
        cal = self._calibration(values)
        assert self.rotation is not None
        jac = usbl_range_jacobian(
            target,
            self.antenna_enu_m[rows],
            self.attitude_rad[rows],
            values[self.lever_arm][:, None, :],
            cal[0],
            cal[1],
            cal[2],
            self.sound_speed_mps,
            pose=False,
            rotation=self.rotation[rows],
        )
        resid = (self.ranges_m[rows] - jac.range_m) * weight
        w3 = weight[..., None]
        blocks = [jac.beacon * w3, jac.lever_arm * w3]
        for key, part in ((self.scale, jac.scale), (self.delay, jac.delay), (self.bias, jac.bias)):
            if key:
                blocks.append((part * weight)[..., None])
        return Linearized(residual=resid, jacobians=tuple(blocks))

    def _calibration(self, values: Mapping[str, FloatArray]) -> tuple[FloatArray, FloatArray, FloatArray]:
        def term(key: str | None, default: float) -> FloatArray:
            return values[key][:, :1] if key else np.array(default)

        return term(self.scale, 1.0), term(self.delay, 0.0), term(self.bias, 0.0)

    def residual(self, values: Mapping[str, FloatArray], rows: IntArray) -> FloatArray:
        target = values[self.target][:, None, :]
        if self.sensor_m is not None:
            return (self.ranges_m[rows] - range_m(target, self.sensor_m[rows])) * self._weight(rows)
        assert self.antenna_enu_m is not None and self.attitude_rad is not None and self.lever_arm is not None
        cal = self._calibration(values)
        assert self.rotation is not None
        model = usbl_range_m(
            target,
            self.antenna_enu_m[rows],
            self.attitude_rad[rows],
            values[self.lever_arm][:, None, :],
            cal[0],
            cal[1],
            cal[2],
            self.sound_speed_mps,
            rotation=self.rotation[rows],
        )
        return (self.ranges_m[rows] - model) * self._weight(rows)


@dataclass(frozen=True, slots=True, kw_only=True)
class DirectionFactor:
    """USBL azimuth and elevation in the head's frame (eq. (1) of :mod:`oceanloc.models.usbl`).

    Two rows per ping, azimuth then elevation, whitened by ``sqrt_information`` (``W`` with ``W^T W`` the
    inverse of the ping's 2x2 angle covariance, which may fold GNSS and attitude noise in); the azimuth
    residual is wrapped on the circle.

    Attributes
    ----------
    beacon, misalignment : str
        Keys of the beacon position (3) and the head misalignment (3, radians).
    lever_arm : str or None
        Key of the lever arm (3); None: ``lever_arm_m`` fixed.
    measured_rad : (B, n, 2) float
    antenna_enu_m, attitude_rad : (B, n, 3) float
    sqrt_information : (B, n, 2, 2) float
        Zero for pings not used.
    lever_arm_m : (3,) float
        The fixed lever arm when ``lever_arm`` is None.
    """

    beacon: str
    misalignment: str
    measured_rad: FloatArray
    antenna_enu_m: FloatArray
    attitude_rad: FloatArray
    sqrt_information: FloatArray
    lever_arm: str | None = None
    lever_arm_m: FloatArray = field(default_factory=lambda: np.zeros(3))
    rotation: FloatArray | None = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.rotation is None:
            object.__setattr__(self, "rotation", vessel_rotation(self.attitude_rad))

    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(k for k in (self.beacon, self.misalignment, self.lever_arm) if k)

    @property
    def rows(self) -> int:
        return 2 * int(self.measured_rad.shape[-2])

    @property
    def batch_size(self) -> int:
        return int(self.measured_rad.shape[0])

    def _lever(self, values: Mapping[str, FloatArray]) -> FloatArray:
        return values[self.lever_arm][:, None, :] if self.lever_arm else np.asarray(self.lever_arm_m)

    def linearize(self, values: Mapping[str, FloatArray], rows: IntArray) -> Linearized:
        w = self.sqrt_information[rows]
        jac = usbl_direction_jacobian(
            values[self.beacon][:, None, :],
            self.antenna_enu_m[rows],
            self.attitude_rad[rows],
            self._lever(values),
            values[self.misalignment][:, None, :],
            pose=False,
            rotation=self.rotation[rows],  # type: ignore[index]
        )
        resid = (w @ direction_residual_rad(self.measured_rad[rows], jac.angles)[..., None])[..., 0]
        b = resid.shape[0]
        blocks = [jac.beacon, jac.misalignment] + ([jac.lever_arm] if self.lever_arm else [])
        return Linearized(
            residual=resid.reshape(b, -1),
            jacobians=tuple((w @ part).reshape(b, -1, 3) for part in blocks),
        )

    def residual(self, values: Mapping[str, FloatArray], rows: IntArray) -> FloatArray:
        angles = usbl_direction_rad(
            values[self.beacon][:, None, :],
            self.antenna_enu_m[rows],
            self.attitude_rad[rows],
            self._lever(values),
            values[self.misalignment][:, None, :],
            rotation=self.rotation[rows],  # type: ignore[index]
        )
        resid = (
            self.sqrt_information[rows] @ direction_residual_rad(self.measured_rad[rows], angles)[..., None]
        )
        return resid[..., 0].reshape(resid.shape[0], -1)


@dataclass(frozen=True, slots=True, kw_only=True)
class DepthFactor:
    """Measured depths of a beacon (its pressure sensor, an echo sounder): ``h = surface_up_m - U``.

    Attributes
    ----------
    beacon : str
    depth_m : (B, n) float
        Depths below the surface, metres.
    sigma_m : (B, n) float
    surface_up_m : float
        The sea surface's height in the ENU frame, metres.
    """

    beacon: str
    depth_m: FloatArray
    sigma_m: FloatArray
    surface_up_m: float = 0.0

    @property
    def keys(self) -> tuple[str, ...]:
        return (self.beacon,)

    @property
    def rows(self) -> int:
        return int(self.depth_m.shape[-1])

    @property
    def batch_size(self) -> int:
        return int(self.depth_m.shape[0])

    def linearize(self, values: Mapping[str, FloatArray], rows: IntArray) -> Linearized:
        inv = 1.0 / self.sigma_m[rows]
        resid = self.residual(values, rows)
        jac = np.zeros((*resid.shape, 3))
        jac[..., 2] = -inv
        return Linearized(residual=resid, jacobians=(jac,))

    def residual(self, values: Mapping[str, FloatArray], rows: IntArray) -> FloatArray:
        up = values[self.beacon][:, None, 2]
        return (self.depth_m[rows] - (self.surface_up_m - up)) / self.sigma_m[rows]


@dataclass(frozen=True, slots=True, kw_only=True)
class PriorFactor:
    """A Gaussian prior ``N(mean, cov)`` on one block: ``mean (B, size)``, ``cov (B, size, size)`` or
    ``(size, size)`` shared by the batch."""

    key: str
    mean: FloatArray
    cov: FloatArray

    @property
    def keys(self) -> tuple[str, ...]:
        return (self.key,)


class FactorGraph:
    """Factors and priors over a :class:`ParameterLayout`, stacked into one whitened system.

    Parameters
    ----------
    layout : ParameterLayout
    factors : sequence of Factor
        Measurement factors; every key must be a block of ``layout``.
    priors : sequence of PriorFactor
        Exactly one per block.

    The graph is a :class:`~oceanloc.estimation.map_gauss_newton.WhitenedModel`: ``evaluate(x, rows)``
    returns the residuals of all factors side by side ``(b, N)``, in the order given, and the dense
    Jacobian ``(b, N, d)`` with each factor's blocks in their columns.
    """

    def __init__(
        self, layout: ParameterLayout, factors: Sequence[Factor], priors: Sequence[PriorFactor]
    ) -> None:
        self.layout = layout
        self.factors = tuple(factors)
        self.priors = tuple(priors)
        batches = {f.batch_size for f in self.factors} | {np.atleast_2d(p.mean).shape[0] for p in self.priors}
        if len(batches) > 1:
            raise ConfigError(f"factors and priors disagree on the batch size: {sorted(batches)}")
        for f in self.factors:
            for k in f.keys:
                layout.block(k)
        covered = [p.key for p in self.priors]
        missing = [n for n in layout.names if n not in covered]
        if missing or len(set(covered)) != len(covered):
            raise ConfigError(f"every block needs exactly one prior; missing {missing}, given {covered}")
        self._batch = batches.pop() if batches else 1
        self.row_offsets = np.cumsum([0] + [f.rows for f in self.factors])
        self._columns = [[layout.index(k) for k in f.keys] for f in self.factors]

    @property
    def batch_size(self) -> int:
        return self._batch

    @property
    def rows(self) -> int:
        return int(self.row_offsets[-1])

    def evaluate(self, x: FloatArray, rows: IntArray) -> tuple[FloatArray, FloatArray]:
        """Whitened residuals ``(b, N)`` and Jacobian ``(b, N, d)`` at ``x (b, d)``: the stacking step."""
        values = self.layout.split(x)
        resid = np.empty((x.shape[0], self.rows))
        jac = np.zeros((x.shape[0], self.rows, self.layout.dim))
        for f, cols, lo, hi in zip(
            self.factors, self._columns, self.row_offsets[:-1], self.row_offsets[1:], strict=True
        ):
            lin = f.linearize(values, rows)
            resid[:, lo:hi] = lin.residual
            for col, part in zip(cols, lin.jacobians, strict=True):
                jac[:, lo:hi, col] = part
        return resid, jac

    def structure(self) -> BoolArray:
        """Which components each residual row depends on, ``(N, d)``: the factors' keys."""
        out = np.zeros((self.rows, self.layout.dim), dtype=bool)
        for cols, lo, hi in zip(self._columns, self.row_offsets[:-1], self.row_offsets[1:], strict=True):
            for col in cols:
                out[lo:hi, col] = True
        return out

    def residuals(self, x: FloatArray, rows: IntArray) -> FloatArray:
        """Whitened residuals alone ``(b, N)`` (a cost needs no Jacobian)."""
        values = self.layout.split(x)
        parts = [f.residual(values, rows) for f in self.factors]
        return np.concatenate(parts, axis=1) if parts else np.zeros((x.shape[0], 0))

    def factor_residuals(self, x: FloatArray, rows: IntArray) -> list[FloatArray]:
        """Each factor's whitened residuals ``(b, rows_f)``, in order."""
        values = self.layout.split(x)
        return [f.residual(values, rows) for f in self.factors]

    def prior_arrays(self) -> tuple[FloatArray, FloatArray]:
        """The block-diagonal prior over the whole state: mean ``(B, d)`` and covariance ``(B, d, d)``."""
        d, b = self.layout.dim, self._batch
        mean = np.zeros((b, d))
        cov = np.zeros((b, d, d))
        for p in self.priors:
            sl = self.layout.index(p.key)
            size = sl.stop - sl.start
            mean[:, sl] = _batch_array(p.mean, (b, size), f"prior mean of {p.key}")
            cov[:, sl, sl] = _batch_array(p.cov, (b, size, size), f"prior covariance of {p.key}")
        return mean, cov

    def prior(self) -> GaussianPrior:
        """The priors as the solver's :class:`~oceanloc.estimation.map_gauss_newton.GaussianPrior`."""
        from oceanloc.estimation.map_gauss_newton import GaussianPrior

        mean, cov = self.prior_arrays()
        return GaussianPrior(mean=mean, cov=cov)


class HeldModel:
    """A whitened model with the components ``held`` fixed at ``values`` (``(B, d)``; only the held
    entries are read): the free components alone are the unknowns, ``(b, d_free)``.

    ``held`` is one mask ``(d,)`` for the whole batch (problems with different masks are solved in
    groups). Rows that depend on held components only (a factor all of whose blocks are held) are left
    out: they are constants of the cost, and a solver would take them for measurements it cannot see.
    ``expand(x_free, rows)`` returns the full state.
    """

    def __init__(self, model: FactorGraph, held: BoolArray, values: FloatArray) -> None:
        self.model = model
        self.held = np.asarray(held, dtype=bool)
        self.free = np.flatnonzero(~self.held)
        self.values = np.asarray(values, dtype=float)
        self.kept = np.flatnonzero(model.structure()[:, self.free].any(axis=1))

    @property
    def batch_size(self) -> int:
        return self.model.batch_size

    def expand(self, x_free: FloatArray, rows: IntArray) -> FloatArray:
        x = self.values[rows].copy()
        x[:, self.free] = x_free
        return x

    def evaluate(self, x: FloatArray, rows: IntArray) -> tuple[FloatArray, FloatArray]:
        resid, jac = self.model.evaluate(self.expand(x, rows), rows)
        return resid[:, self.kept], jac[:, self.kept][:, :, self.free]

    def residuals(self, x: FloatArray, rows: IntArray) -> FloatArray:
        return self.model.residuals(self.expand(x, rows), rows)[:, self.kept]
