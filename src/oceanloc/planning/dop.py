"""Horizontal dilution of precision (HDOP) for bearing, range and TDOA measurements.

Dillard (AquaQuad thesis), Chapter IV.A: ``HDOP = sqrt(trace((H^T R^-1 H)^-1))`` (eq. IV.9; eq. IV.6 is the
special case ``R = I``), where ``H`` holds the Jacobians of the measurements with respect to the target's
horizontal position. With ``sigma`` the measurement standard deviation (radians for bearings, metres for
ranges, seconds for TDOA), HDOP is the square root of the trace of the position Cramer-Rao bound of one
snapshot, in metres; with ``sigma = 1`` it is the thesis' unit-weight geometric factor.

Everything is batched: ``nodes_m (..., n, 2)`` and ``target_m (..., 2)`` broadcast, so a whole grid of
candidate node positions or a time series of flock geometries is one call. Singular geometries (all lines
of sight parallel, fewer independent measurements than two) give ``inf``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from oceanloc import _validate
from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.errors import ArgumentError, ConfigError
from oceanloc.estimation.bounds import hdop_from_jacobian
from oceanloc.models.measurements import (
    MEASUREMENT_KINDS,
    MeasurementKind,
    bearing_jacobian,
    horizontal_range_jacobian,
    sensor_pairs,
    tdoa_jacobian,
)

__all__ = [
    "MEASUREMENT_KINDS",
    "DopMap",
    "MeasurementKind",
    "PlacementResult",
    "hdop",
    "hdop_from_jacobian",
    "hdop_map",
    "hdop_unit",
    "optimize_placement",
    "position_jacobian",
]


def position_jacobian(
    nodes_m: ArrayLike,
    target_m: ArrayLike,
    kind: MeasurementKind,
    *,
    pairs: ArrayLike | None = None,
    sound_speed_mps: float = 1500.0,
) -> FloatArray:
    """Measurement Jacobian ``H`` with respect to the target's horizontal position.

    Parameters
    ----------
    nodes_m : (..., n, 2) float
        Sensor node positions, metres.
    target_m : (..., 2) float
        Target position, metres; broadcast against ``nodes_m``'s leading dimensions.
    kind : {"bearing", "range", "tdoa"}
        Measurement type: eqs. (II.3), (II.4), (II.7).
    pairs : (P, 2) int, optional
        TDOA sensor pairs; every pair ``i < j`` by default (the thesis' lab filter uses all three pairs of
        three nodes).
    sound_speed_mps : float
        Sound speed for TDOA.

    Returns
    -------
    (..., m, 2) float
        ``m = n`` for bearing and range, ``m = P`` for TDOA.
    """
    nodes = np.asarray(nodes_m, dtype=float)
    target = np.asarray(target_m, dtype=float)[..., :2]
    if kind == "bearing":
        return bearing_jacobian(target, nodes)
    if kind == "range":
        return horizontal_range_jacobian(target, nodes)
    if kind == "tdoa":
        p = sensor_pairs(nodes.shape[-2]) if pairs is None else pairs
        return tdoa_jacobian(target, nodes, p, sound_speed_mps)
    raise ValueError(f"measurement kind must be one of {', '.join(MEASUREMENT_KINDS)}; got {kind!r}")


def hdop(
    nodes_m: ArrayLike,
    target_m: ArrayLike,
    kind: MeasurementKind,
    sigma: ArrayLike = 1.0,
    *,
    pairs: ArrayLike | None = None,
    sound_speed_mps: float = 1500.0,
) -> FloatArray:
    """Horizontal dilution of precision of a flock of nodes observing a target, eqs. (IV.6)/(IV.9).

    Parameters
    ----------
    nodes_m : (..., n, 2) float
        Node positions, metres.
    target_m : (..., 2) float
        Target position, metres; broadcast against ``nodes_m``'s leading dimensions.
    kind : {"bearing", "range", "tdoa"}
        Measurement type.
    sigma : float or (..., m) float
        Measurement standard deviation: radians (bearing), metres (range) or seconds (TDOA). With
        ``sigma = 1`` the result is the thesis' geometric HDOP (eq. IV.6, in m/rad for bearings, dimensionless
        for ranges, m/s for TDOA); with the real sigma it is the snapshot position standard error in metres.
    pairs : (P, 2) int, optional
        TDOA pairs (default: all pairs).
    sound_speed_mps : float
        Sound speed ``c`` for TDOA.

    Returns
    -------
    (...) float
        HDOP; ``inf`` for singular geometries.

    Examples
    --------
    >>> import numpy as np
    >>> ring = 100.0 * np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
    >>> float(hdop(ring, np.zeros(2), "range"))  # four ranges at right angles: sqrt(2 / 2)
    1.0
    """
    nodes = _validate.float_array("nodes_m", nodes_m, last=(2,), min_ndim=2, max_abs=_validate.MAX_LENGTH_M)
    target = _validate.float_array("target_m", target_m, last=(2,), max_abs=_validate.MAX_LENGTH_M)
    _check_kind(kind)
    sig = np.asarray(sigma, dtype=float)
    if sig.size == 0 or not np.all(sig > 0.0):  # +inf is allowed: a node that is missing (module docstring)
        raise ArgumentError(f"sigma: must be positive (or +inf for a missing node), got {sig!r}")
    _validate.number("sound_speed_mps", sound_speed_mps, lo=1000.0, hi=2000.0, unit="m/s")
    n = nodes.shape[-2]
    rows = n * (n - 1) // 2 if kind == "tdoa" and pairs is None else n
    batch = float(np.prod(np.broadcast_shapes(nodes.shape[:-2], target.shape[:-1]), dtype=float))
    _validate.memory("nodes_m", batch * rows * 2 * 8 * _WORK_COPIES, what=f"HDOP of {batch:.0f} flocks")
    jac = position_jacobian(nodes, target, kind, pairs=pairs, sound_speed_mps=sound_speed_mps)
    try:
        np.broadcast_shapes(sig.shape, jac.shape[:-1])
    except ValueError:
        raise ArgumentError(
            f"sigma: shape {sig.shape} does not fit the {jac.shape[-2]} measurements"
        ) from None
    return hdop_from_jacobian(jac, sigma)


_WORK_COPIES = 8
"""Arrays of the Jacobian's size an HDOP evaluation holds at once (differences, Jacobian, products)."""


def _check_kind(kind: object) -> None:
    if kind not in ("bearing", "range", "tdoa"):
        raise ArgumentError(f"kind: {kind!r}; allowed: bearing, range, tdoa")


def hdop_unit(kind: str, sigma: float) -> str:
    """Unit of an HDOP value: ``m`` with a real sigma; with ``sigma = 1`` the geometric factor's unit
    (``m/rad`` for bearings, ``1`` for ranges, ``m/s`` for TDOA)."""
    if sigma != 1.0:
        return "m"
    return {"bearing": "m/rad", "range": "1", "tdoa": "m/s"}.get(kind, "1")


_CF_UNITS = {"m": "m", "m/rad": "m rad-1", "1": "1", "m/s": "m s-1"}


@dataclass(frozen=True, slots=True, kw_only=True)
class DopMap:
    """HDOP over a grid of positions of one moving node, the others fixed (thesis Figures 32 and 48).

    Attributes
    ----------
    x_m : (nx,) float
    y_m : (ny,) float
        Grid axes, metres.
    hdop : (ny, nx) float
        HDOP with the moving node at ``(x_m[j], y_m[i])``; ``inf`` where singular.
    fixed_nodes_m : (n - 1, 2) float
    target_m : (2,) float
    kind : str
    sigma : float
    """

    x_m: FloatArray
    y_m: FloatArray
    hdop: FloatArray
    fixed_nodes_m: FloatArray
    target_m: FloatArray
    kind: str
    sigma: float

    @property
    def hdop_unit(self) -> str:
        return hdop_unit(self.kind, self.sigma)

    def minimum(self) -> tuple[float, float, float] | None:
        """``(hdop, x_m, y_m)`` of the best cell for the moving node; ``None`` if every cell is singular."""
        finite = np.isfinite(self.hdop)
        if not finite.any():
            return None
        iy, ix = np.unravel_index(np.argmin(np.where(finite, self.hdop, np.inf)), self.hdop.shape)
        return float(self.hdop[iy, ix]), float(self.x_m[ix]), float(self.y_m[iy])

    def to_record(self) -> dict[str, Any]:
        """Summary of the map (the grid itself goes to NetCDF through :meth:`to_dataset`)."""
        finite = np.isfinite(self.hdop)
        best = self.minimum()
        return {
            "kind": self.kind,
            "sigma": self.sigma,
            "hdop_unit": self.hdop_unit,
            "target_m": self.target_m.tolist(),
            "fixed_nodes_m": self.fixed_nodes_m.tolist(),
            "grid_x_m": [float(self.x_m[0]), float(self.x_m[-1]), int(self.x_m.size)],
            "grid_y_m": [float(self.y_m[0]), float(self.y_m[-1]), int(self.y_m.size)],
            "min_hdop": None if best is None else best[0],
            "min_hdop_node_m": None if best is None else [best[1], best[2]],
            "median_hdop": float(np.median(self.hdop[finite])) if finite.any() else None,
            "singular_fraction": float(1.0 - finite.mean()),
        }

    def to_dataset(self) -> Any:
        """The map as an :class:`xarray.Dataset` (CF-style attributes), ready for ``to_netcdf``."""
        import xarray as xr

        finite = np.where(np.isfinite(self.hdop), self.hdop, np.nan)
        return xr.Dataset(
            {
                "hdop": (
                    ("y", "x"),
                    finite,
                    {
                        "long_name": "horizontal dilution of precision",
                        "units": _CF_UNITS[self.hdop_unit],
                    },
                ),
                "fixed_node_x": (
                    ("node",),
                    self.fixed_nodes_m[:, 0],
                    {"long_name": "fixed node east", "units": "m"},
                ),
                "fixed_node_y": (
                    ("node",),
                    self.fixed_nodes_m[:, 1],
                    {"long_name": "fixed node north", "units": "m"},
                ),
            },
            coords={
                "x": ("x", self.x_m, {"long_name": "moving node east", "units": "m"}),
                "y": ("y", self.y_m, {"long_name": "moving node north", "units": "m"}),
            },
            attrs={
                "title": f"HDOP map, {self.kind} measurements",
                "measurement": self.kind,
                "sigma": self.sigma,
                "target_x_m": float(self.target_m[0]),
                "target_y_m": float(self.target_m[1]),
                "definition": "sqrt(trace((H^T R^-1 H)^-1)), R = sigma^2 I (Dillard thesis eq. IV.9)",
                "source": "oceanloc",
            },
        )


def hdop_map(
    fixed_nodes_m: ArrayLike,
    target_m: ArrayLike,
    kind: MeasurementKind,
    *,
    x_range_m: tuple[float, float],
    y_range_m: tuple[float, float],
    resolution_m: float,
    sigma: float = 1.0,
    sound_speed_mps: float = 1500.0,
    pairs: ArrayLike | None = None,
) -> DopMap:
    """HDOP as one extra node moves over a grid, the other nodes and the target fixed (Figure 32).

    The moving node is the last node; TDOA pairs (default: all) index the full node list. The whole grid is
    one vectorized evaluation.
    """
    fixed = np.atleast_2d(np.asarray(fixed_nodes_m, dtype=float))
    if fixed.shape[-1] != 2:
        raise ConfigError(f"fixed nodes must be (n, 2), got {fixed.shape}")
    _validate.float_array("fixed_nodes_m", fixed, max_abs=_validate.MAX_LENGTH_M, allow_empty=True)
    if not resolution_m > 0:
        raise ConfigError(f"grid resolution must be positive, got {resolution_m}")
    _validate.number("resolution_m", resolution_m, lo=0.0, hi=_validate.MAX_LENGTH_M, lo_open=True)
    _check_sigma(sigma)
    for name, span in (("x", x_range_m), ("y", y_range_m)):
        lo, hi = _validate.float_array(f"{name}_range_m", span, shape=(2,), max_abs=_validate.MAX_LENGTH_M)
        if not hi > lo:
            raise ConfigError(f"grid {name} range must have max > min, got {lo}..{hi}")
        if (hi - lo) / resolution_m > 1e5:
            raise ArgumentError(
                f"{name}_range_m: {(hi - lo) / resolution_m:.3g} cells across at {resolution_m:g} m; "
                "at most 1e5: coarsen the resolution"
            )
    x = np.arange(x_range_m[0], x_range_m[1] + 0.5 * resolution_m, resolution_m)
    y = np.arange(y_range_m[0], y_range_m[1] + 0.5 * resolution_m, resolution_m)
    if x.size * y.size > 25_000_000:
        raise ConfigError(f"grid of {x.size} x {y.size} cells is too large; coarsen the resolution")
    gx, gy = np.meshgrid(x, y)
    moving = np.stack([gx, gy], axis=-1)[..., None, :]
    nodes = np.concatenate([np.broadcast_to(fixed, (*gx.shape, *fixed.shape)), moving], axis=-2)
    target = np.asarray(target_m, dtype=float)
    values = hdop(nodes, target, kind, sigma, pairs=pairs, sound_speed_mps=sound_speed_mps)
    return DopMap(
        x_m=x, y_m=y, hdop=values, fixed_nodes_m=fixed, target_m=target, kind=kind, sigma=float(sigma)
    )


MAX_PLACED_NODES = 10_000
"""Most nodes :func:`optimize_placement` places at once."""


def _check_sigma(sigma: float) -> None:
    if not (np.isfinite(sigma) and sigma > 0):
        raise ConfigError(f"measurement sigma must be positive, got {sigma}")


@dataclass(frozen=True, slots=True, kw_only=True)
class PlacementResult:
    """HDOP-optimal placement of ``n`` nodes around a target (thesis Chapter IV.A.4, Figures 34-35).

    Attributes
    ----------
    nodes_m : (n, 2) float
        Best placement found.
    hdop : float
        Its HDOP.
    ring_nodes_m : (n, 2) float
        The evenly spaced ring at the best common stand-off range (and, with fixed nodes, the best phase).
    ring_hdop : float
    gap : float
        ``ring_hdop / hdop - 1``: how much worse the even ring is than the optimum (0: the ring is optimal).
    start_hdop : (S,) float
        HDOP reached from each start (the spread shows how much a single local solve depends on its start).
    start_nodes_m : (S, n, 2) float
        Placement reached from each start.
    target_m : (2,) float
    fixed_nodes_m : (k, 2) float
        The nodes that were already in place (``k = 0`` when none).
    kind : str
    sigma : float
    """

    nodes_m: FloatArray
    hdop: float
    ring_nodes_m: FloatArray
    ring_hdop: float
    gap: float
    start_hdop: FloatArray
    start_nodes_m: FloatArray
    target_m: FloatArray
    fixed_nodes_m: FloatArray
    kind: str
    sigma: float

    def ranges_bearings(self) -> tuple[FloatArray, FloatArray]:
        """Range (m) and true bearing from the target of each placed node, radians clockwise from north
        (the +y axis) in ``[0, 2 pi)``."""
        d = self.nodes_m - self.target_m
        return np.hypot(d[:, 0], d[:, 1]), np.mod(np.arctan2(d[:, 0], d[:, 1]), 2 * np.pi)

    def to_record(self) -> dict[str, Any]:
        """The placement; bearings in degrees clockwise from north, as seen from the target."""
        ranges, bearings = self.ranges_bearings()
        return {
            "kind": self.kind,
            "sigma": self.sigma,
            "target_m": self.target_m.tolist(),
            "fixed_nodes_m": self.fixed_nodes_m.tolist(),
            "nodes_m": self.nodes_m.tolist(),
            "node_range_m": ranges.tolist(),
            "node_bearing_deg": np.degrees(bearings).tolist(),
            "bearing_convention": "degrees clockwise from north (+y), from the target to the node",
            "hdop": self.hdop,
            "ring_nodes_m": self.ring_nodes_m.tolist(),
            "ring_hdop": self.ring_hdop,
            "ring_gap": self.gap,
            "start_hdop": self.start_hdop.tolist(),
        }


def _polar_nodes(params: FloatArray, target: FloatArray) -> FloatArray:
    """``(..., 2n)`` = ranges then bearings -> node positions ``(..., n, 2)``."""
    n = params.shape[-1] // 2
    r, a = params[..., :n], params[..., n:]
    return target + np.stack([r * np.cos(a), r * np.sin(a)], axis=-1)


def optimize_placement(
    n_nodes: int,
    kind: MeasurementKind,
    *,
    target_m: ArrayLike = (0.0, 0.0),
    min_standoff_m: float,
    max_standoff_m: float,
    sigma: float = 1.0,
    fixed_nodes_m: ArrayLike | None = None,
    starts: int = 16,
    rng: np.random.Generator,
    sound_speed_mps: float = 1500.0,
    screen: int = 4096,
    progress: Callable[[int], None] | None = None,
) -> PlacementResult:
    """Minimize HDOP over the positions of ``n`` nodes, each between two stand-off ranges from the target.

    Multi-start local optimization (L-BFGS-B on the range and bearing of each node from the target, the
    ranges bounded by the stand-offs so that nodes neither run to infinity nor onto the target, with the
    gradient from central differences evaluated in one vectorized call). The starts are the best evenly
    spaced ring, a cluster on one side (the thesis' two initial conditions, Figures 34-35) and the best of
    ``screen`` random placements, all scored in one vectorized call.

    Parameters
    ----------
    n_nodes : int
        Number of nodes to place.
    kind : {"bearing", "range", "tdoa"}
    target_m : (2,) float
    min_standoff_m, max_standoff_m : float
        Allowed node ranges from the target, ``0 < min <= max``.
    sigma : float
        Measurement standard deviation (HDOP in metres); 1 gives the geometric factor.
    fixed_nodes_m : (k, 2) float, optional
        Nodes already in place (they count in the HDOP but do not move).
    starts : int
        Number of local optimizations.
    rng : numpy.random.Generator
        For the random starts.
    progress : callable, optional
        Called with 1 after each local optimization.
    """
    _validate.integer("n_nodes", n_nodes, lo=1, hi=MAX_PLACED_NODES)
    _validate.integer("starts", starts, lo=1, hi=10_000)
    _validate.integer("screen", screen, lo=1, hi=1_000_000)
    _check_kind(kind)
    fixed = (
        np.zeros((0, 2)) if fixed_nodes_m is None else np.atleast_2d(np.asarray(fixed_nodes_m, dtype=float))
    )
    _validate.float_array("fixed_nodes_m", fixed, max_abs=_validate.MAX_LENGTH_M, allow_empty=True)
    _validate.float_array("target_m", target_m, shape=(2,), max_abs=_validate.MAX_LENGTH_M)
    _validate.number("min_standoff_m", min_standoff_m, lo=0.0, hi=_validate.MAX_LENGTH_M, lo_open=True)
    _validate.number("max_standoff_m", max_standoff_m, lo=0.0, hi=_validate.MAX_LENGTH_M, lo_open=True)
    total = n_nodes + fixed.shape[0]
    rows = total * (total - 1) // 2 if kind == "tdoa" else total
    at_once = max(screen, 64 * 16, 4 * n_nodes)
    _validate.memory("n_nodes", at_once * rows * 2 * 8 * _WORK_COPIES, what=f"placing {n_nodes} nodes")
    if n_nodes < 1 or total < (3 if kind == "tdoa" else 2):
        raise ConfigError(f"{kind} placement needs at least {3 if kind == 'tdoa' else 2} nodes, got {total}")
    if not 0 < min_standoff_m <= max_standoff_m:
        raise ConfigError(f"need 0 < min stand-off <= max stand-off, got {min_standoff_m}, {max_standoff_m}")
    if starts < 1:
        raise ConfigError(f"need at least one start, got {starts}")
    _check_sigma(sigma)
    target = np.asarray(target_m, dtype=float)
    n = n_nodes

    def cost(params: FloatArray) -> FloatArray:
        moving = _polar_nodes(params, target)
        nodes = np.concatenate([np.broadcast_to(fixed, (*moving.shape[:-2], *fixed.shape)), moving], axis=-2)
        return hdop(nodes, target, kind, sigma, sound_speed_mps=sound_speed_mps)

    def log_cost(params: FloatArray) -> FloatArray:
        v = cost(params)
        return np.where(np.isfinite(v), np.log(np.where(np.isfinite(v), v, 1.0)), 1e3)

    radii = np.linspace(min_standoff_m, max_standoff_m, 64)
    phases = np.linspace(0.0, 2 * np.pi / max(n, 1), 16, endpoint=False) if fixed.size else np.zeros(1)
    rr, pp = np.meshgrid(radii, phases, indexing="ij")
    even = 2 * np.pi * np.arange(n) / n
    rings = np.concatenate([np.repeat(rr.reshape(-1, 1), n, axis=1), pp.reshape(-1, 1) + even], axis=1)
    ring_costs = cost(rings)
    best_ring = rings[int(np.argmin(ring_costs))]
    cluster = np.concatenate([np.full(n, min_standoff_m), np.linspace(0.0, 0.5 * np.pi, n)])
    random = np.concatenate(
        [rng.uniform(min_standoff_m, max_standoff_m, (screen, n)), rng.uniform(-np.pi, np.pi, (screen, n))],
        axis=1,
    )
    order = np.argsort(cost(random))
    initial = np.vstack([best_ring, cluster, random[order[: max(0, starts - 2)]]])[:starts]
    bounds = [(min_standoff_m, max_standoff_m)] * n + [(None, None)] * n
    step = np.concatenate([np.full(n, 1e-6 * max_standoff_m), np.full(n, 1e-6)])
    probes = np.concatenate([np.diag(step), -np.diag(step)])

    def fun_and_grad(p: FloatArray) -> tuple[float, FloatArray]:
        values = log_cost(np.vstack([p[None], p + probes]))
        grad = (values[1 : 2 * n + 1] - values[2 * n + 1 :]) / (2 * step)
        return float(values[0]), np.where(np.isfinite(grad), grad, 0.0)

    finals = np.empty_like(initial)
    for s, x0 in enumerate(initial):
        import scipy.optimize

        res = scipy.optimize.minimize(fun_and_grad, x0, jac=True, method="L-BFGS-B", bounds=bounds)
        finals[s] = res.x
        if progress:
            progress(1)
    values = cost(finals)
    best = int(np.argmin(values))
    ring_hdop = float(ring_costs.min())
    return PlacementResult(
        nodes_m=_polar_nodes(finals[best], target),
        hdop=float(values[best]),
        ring_nodes_m=_polar_nodes(best_ring, target),
        ring_hdop=ring_hdop,
        gap=ring_hdop / float(values[best]) - 1.0,
        start_hdop=values,
        start_nodes_m=_polar_nodes(finals, target),
        target_m=target,
        fixed_nodes_m=fixed,
        kind=kind,
        sigma=float(sigma),
    )
