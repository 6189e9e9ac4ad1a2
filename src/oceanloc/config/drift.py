"""Drift-planning scenarios: TOML file -> validated, frozen :class:`DriftScenario`.

The thesis' scenarios ship as ``oceanloc/config/scenarios/drift/*.toml`` and are addressed by name.
A file describes the current, the map, the route, the vehicle, the flock for the HDOP term, the planner
and the path-following trial::

    [scenario]
    name = "my-drift"
    description = "..."

    [currents]
    kind = "thesis-vortex"         # thesis-vortex | vortex | double-gyre | uniform | tidal | linear |
                                   # rankine | netcdf
    interpolation = "cell"         # thesis-vortex: cell (the thesis' lookup) | linear
    # vortex: scale_m; double-gyre: length_m, amplitude_mps, epsilon, period_h, origin_m;
    # uniform: velocity_mps = [u, v];
    # tidal: mean_mps = [u, v], amplitude_mps = [u, v], period_h, phase_deg (uniform, oscillating);
    # linear: matrix_per_s = [[a, b], [c, d]], offset_mps = [u, v] (v = A p + b: shear, strain);
    # rankine: centre_m, core_radius_m, peak_speed_mps, pulse, period_h, background_mps;
    # netcdf: path (relative to this file), u, v, depth_index, origin_lonlat_deg

    [drift]
    integrator = "euler"           # euler (the thesis) | rk4
    dt_s = 60.0
    horizon_h = 24.0               # longest drift considered from any point

    [map]
    bounds_m = [-5000.0, 5000.0, -5000.0, 5000.0]   # x_min, x_max, y_min, y_max (netcdf: the grid if omitted)
    inflation_m = 0.0                               # safety margin around obstacles
    flights_avoid_obstacles = false                 # true: obstacles are no-fly zones too
    [[map.rectangles]]
    x_m = [-4000.0, -2000.0]
    y_m = [-4000.0, -3000.0]
    [[map.polygons]]
    vertices_m = [[0.0, 0.0], [1000.0, 0.0], [500.0, 800.0]]

    [route]
    start_m = [-4000.0, 4000.0]
    goal_m = [3000.0, -3000.0]
    goal_tolerance_m = 100.0
    start_time_s = 0.0             # start time in the field's clock (s; a double gyre's phase, or
                                   # seconds after a netcdf product's first slice); netcdf may give
    # start_time = "2024-01-01T06:00:00" instead (ISO 8601, within the product's time axis)

    [vehicle]                      # Table 1 and (IV.14)
    flight_power_w = 200.0
    flight_speed_kn = 20.0
    max_flight_time_s = 120.0
    nautical_mile_m = 1852.0       # 2000 only to reproduce the thesis' energies
    flight_legs = "hop"            # hop: legs of at most one hop; any: any length (thesis accounting)
    propulsion = "air"             # air: flights unaffected by the current (the AquaQuad); water: a boat
                                   # moving at flight_speed_kn through the water, carried by the current

    [hdop]                         # flock geometry of the HDOP cost term (bearing-only, as the thesis)
    others_m = [[5000.0, 5000.0], [5000.0, -5000.0], [-5000.0, -5000.0]]
    target_m = [3100.0, -2900.0]

    [planner]
    kind = "oceanloc"              # oceanloc | thesis-single | thesis-optimality-seeking
    seed = 1
    time_weight_wh_per_h = 0.0     # price of time in the oceanloc planner (0: flight energy only)
    objective = "energy"           # energy: flight energy plus the price of time; time: arrive first
    deadline_h = 12.0              # optional: reach the goal within this many hours of the start

    [following]                    # path following in a "true" current (V.D)
    watch_circle_m = 150.0
    current_scale = 1.1            # true current = scale * rotate(planning current) + noise
    current_rotation_deg = 5.0
    noise_mps = 0.05
    noise_correlation_s = 1800.0
    stray_m = 400.0                # replan when farther than this from the planned track
    max_replans = 20
    runs = 200
    seed = 7
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from oceanloc.config.builtin import builtin_folder, builtin_names, resolve_scenario
from oceanloc.config.toml_fields import Table
from oceanloc.errors import ConfigError
from oceanloc.geo.projection import LocalProjection
from oceanloc.models.currents import (
    CurrentField,
    DoubleGyreCurrent,
    LinearCurrent,
    RankineVortexCurrent,
    TidalCurrent,
    UniformCurrent,
    VortexCurrent,
    thesis_vortex_grid,
    time_span_s,
)
from oceanloc.models.currents_cf import land_obstacles, open_current_netcdf
from oceanloc.models.drift import METHODS, Method
from oceanloc.models.energy import EnergyBudget
from oceanloc.models.obstacles import ObstacleMap, OccupancyGrid
from oceanloc.models.powered import PROPULSIONS, Propulsion
from oceanloc.planning.drift_rrt.lattice import check_lattice_memory
from oceanloc.planning.drift_rrt.objective import HdopTerm
from oceanloc.planning.drift_rrt.oceanloc_planner import DEFAULT_OPTIONS, needs_time
from oceanloc.planning.drift_rrt.planner import DriftPlannerName, parse_planner_name
from oceanloc.planning.drift_rrt.problem import OBJECTIVES, DriftProblem, Objective
from oceanloc.planning.drift_rrt.propagation import DriftPropagator
from oceanloc.planning.drift_rrt.space import DriftSpace
from oceanloc.planning.drift_rrt.time_plan import DEFAULT_TIME_OPTIONS
from oceanloc.planning.drift_rrt.time_values import TimeLattice
from oceanloc.units import DEG

CURRENT_KINDS = ("thesis-vortex", "vortex", "double-gyre", "uniform", "tidal", "linear", "rankine", "netcdf")

# Physical ranges of the scenario fields (every value outside is a one-line error naming the field).
MAX_CURRENT_MPS = 10.0
"""Fastest current accepted, m/s (the strongest tidal races run at about 5 m/s)."""
MAX_COORD_M = 1e7
"""Largest coordinate of a local frame, metres (a quarter of the Earth's circumference)."""
MAX_LENGTH_M = 1e6
"""Largest length scale of an analytic field, metres."""
MIN_DT_S, MAX_DT_S = 1.0, 3600.0
"""Drift step range, seconds."""
MAX_HORIZON_H = 24.0 * 30
"""Longest drift horizon, hours (a month)."""
MAX_HORIZON_STEPS = 200_000
"""Most drift steps in one horizon (horizon / step)."""
MAX_SEED = 2**63 - 1


@dataclass(frozen=True, slots=True, kw_only=True)
class FollowingSettings:
    """Path following in a true current that differs from the planning current (V.D).

    Attributes
    ----------
    watch_circle_m : float
        A hop fires when the drifter is within this distance of the planned take-off point.
    current_scale : float
        The true current is the planning current scaled by this factor ...
    current_rotation_rad : float
        ... and rotated by this angle ...
    noise_mps : float
        ... plus a random, spatially uniform current of this standard deviation per component ...
    noise_correlation_s : float
        ... correlated in time over this scale (first-order Gauss-Markov).
    stray_m : float
        Replan when the drifter is farther than this from the rest of its planned drift track.
    max_replans : int
        Give up after this many replans.
    runs : int
        Monte Carlo runs.
    seed : int
        Master seed.
    """

    watch_circle_m: float = 150.0
    current_scale: float = 1.1
    current_rotation_rad: float = 5.0 * DEG
    noise_mps: float = 0.05
    noise_correlation_s: float = 1800.0
    stray_m: float = 400.0
    max_replans: int = 20
    runs: int = 200
    seed: int = 7


@dataclass(frozen=True, slots=True, kw_only=True)
class DriftScenario:
    """A validated drift-planning scenario (build the planning problem with
    :func:`problem_from_scenario`).

    Attributes
    ----------
    name, description : str
    current : CurrentField
        The planning current.
    integrator : {"euler", "rk4"}
    dt_s : float
        Drift step.
    horizon_s : float
        Longest drift considered from any point.
    obstacles : ObstacleMap
        Bounds, obstacles (and land cells of a gridded product), inflation margin.
    flights_avoid_obstacles : bool
    start_m, goal_m : (2,) float
    goal_tolerance_m : float
    start_time_s : float
        Start time in the current's clock, seconds (every drift leg is integrated from its own start time).
    energy : EnergyBudget
    max_leg_m : float or None
        Longest flight leg (one hop) or ``None`` for flights of any length.
    propulsion : {"air", "water"}
        What powered legs move through (:mod:`oceanloc.models.powered`).
    objective : {"energy", "time"}
        What the oceanloc planner minimizes.
    max_duration_s : float or None
        Deadline after the start, seconds (energy with a deadline), or ``None``.
    hdop_others_m : (n, 2) float or None
        Other flock members for the HDOP term.
    hdop_target_m : (2,) float or None
    planner : str
        Default planner (one of :data:`~oceanloc.planning.drift_rrt.planner.PLANNER_NAMES`).
    seed : int
        Default planner seed.
    time_weight_wh_per_h : float
        Price of time in the oceanloc planner's objective (0: flight energy only, as the thesis).
    following : FollowingSettings
    projection : LocalProjection or None
        Local frame of a longitude/latitude current product (plans are written in lon/lat too).
    currents_description : str
    data_files : tuple of str
        Data files the scenario reads (a current product), for provenance.
    toml_text : str
        The scenario's TOML text (its SHA-256 goes into every record's provenance).
    """

    name: str
    description: str = ""
    current: CurrentField
    integrator: Method = "rk4"
    dt_s: float = 60.0
    horizon_s: float = 24 * 3600.0
    obstacles: ObstacleMap
    flights_avoid_obstacles: bool = False
    start_m: np.ndarray
    goal_m: np.ndarray
    goal_tolerance_m: float = 100.0
    start_time_s: float = 0.0
    energy: EnergyBudget = field(default_factory=EnergyBudget)
    max_leg_m: float | None = None
    propulsion: Propulsion = "air"
    objective: Objective = "energy"
    max_duration_s: float | None = None
    hdop_others_m: np.ndarray | None = None
    hdop_target_m: np.ndarray | None = None
    planner: DriftPlannerName = "oceanloc"
    seed: int = 1
    time_weight_wh_per_h: float = 0.0
    following: FollowingSettings = field(default_factory=FollowingSettings)
    projection: LocalProjection | None = None
    currents_description: str = ""
    data_files: tuple[str, ...] = ()
    toml_text: str = field(default="", repr=False)


def builtin_drift_scenarios() -> list[str]:
    """Names of the drift scenarios shipped with oceanloc."""
    return builtin_names("drift")


def load_drift_scenario(name_or_path: str | Path) -> DriftScenario:
    """Load a built-in drift scenario by name or a scenario file by path (data files resolve beside it).

    The scenario keeps its TOML text (:attr:`DriftScenario.toml_text`) so results can carry its hash.
    """
    try:
        root, folder = resolve_scenario(name_or_path, "drift")
    except RecursionError:
        raise ConfigError(
            f"{name_or_path}: TOML nested too deeply to read (a scenario needs two levels of tables)"
        ) from None
    if folder is None:
        text = builtin_folder("drift").joinpath(f"{name_or_path}.toml").read_text(encoding="utf-8")
    else:
        text = Path(name_or_path).read_text(encoding="utf-8")
    scenario = drift_scenario_from_table(root, base_dir=folder or Path(str(builtin_folder("drift"))))
    return dataclasses.replace(scenario, toml_text=text)


def check_planning_memory(scenario: DriftScenario, source: str) -> None:
    """Raise a ConfigError naming ``source`` if the lattice planner would need more memory than allowed.

    The estimate (:func:`oceanloc.planning.drift_rrt.lattice.lattice_memory_bytes`) counts the lattice
    nodes over ``[map] bounds_m`` and the drift samples over ``[drift] horizon_h / dt_s``; the message says
    which of them to change.
    """
    try:
        problem = problem_from_scenario(scenario)
        if needs_time(problem):
            TimeLattice(problem, DEFAULT_TIME_OPTIONS, np.zeros(2)).check_memory()
        else:
            check_lattice_memory(problem, DEFAULT_OPTIONS)
    except ConfigError as exc:
        raise ConfigError(f"{source}: {exc}") from None


@dataclass(frozen=True, slots=True, kw_only=True)
class CurrentSettings:
    """``[currents]``: the planning current, its georeference, a one-line description, land cells."""

    field: CurrentField
    projection: LocalProjection | None
    description: str
    land: OccupancyGrid | None = None
    data_files: tuple[str, ...] = ()
    time_origin: str | None = None


def _currents(t: Table, base_dir: Path) -> CurrentSettings:
    kind = t.str("kind", "thesis-vortex", choices=CURRENT_KINDS)
    if kind == "thesis-vortex":
        interp = t.str("interpolation", "cell", choices=("cell", "linear"))
        scale = t.float("scale_m", 10_000.0, lo=1.0, hi=MAX_LENGTH_M)
        f: CurrentField = thesis_vortex_grid(interp, scale_m=scale)  # type: ignore[arg-type]
        how = "piecewise constant per cell" if interp == "cell" else "bilinear"
        return CurrentSettings(
            field=f, projection=None, description=f"thesis vortex sampled every {0.05 * scale:g} m ({how})"
        )
    if kind == "vortex":
        scale = t.float("scale_m", 10_000.0, lo=1.0, hi=MAX_LENGTH_M)
        half = t.float("half_width_m", 0.5 * scale, lo=0.0, lo_open=True, hi=MAX_LENGTH_M)
        return CurrentSettings(
            field=VortexCurrent(scale_m=scale, half_width_m=half),
            projection=None,
            description=f"analytic thesis vortex (scale {scale:g} m)",
        )
    if kind == "double-gyre":
        length = t.float("length_m", 5000.0, lo=1.0, hi=MAX_LENGTH_M)
        amp = t.float("amplitude_mps", 0.5, lo=0.0, hi=MAX_CURRENT_MPS)
        eps = t.float("epsilon", 0.0, lo=0.0, hi=1.0)
        period_h = t.float("period_h", 24.0, lo=0.01, hi=24.0 * 365)
        origin = _coords(t, "origin_m", 2, [0.0, 0.0])
        f = DoubleGyreCurrent(
            length_m=length,
            amplitude_mps=amp,
            epsilon=eps,
            omega_rad_s=2 * math.pi / (period_h * 3600.0),
            origin_m=(float(origin[0]), float(origin[1])),
        )
        desc = f"double gyre L = {length:g} m, A = {amp:g} m/s, eps = {eps:g}"
        return CurrentSettings(field=f, projection=None, description=desc)
    if kind == "uniform":
        vel = t.vector("velocity_mps", 2)
        if not np.all(np.abs(vel) <= MAX_CURRENT_MPS):
            raise t.error(
                "velocity_mps",
                f"components must lie within [-{MAX_CURRENT_MPS:g}, {MAX_CURRENT_MPS:g}] m/s, "
                f"got {vel.tolist()}",
            )
        return CurrentSettings(
            field=UniformCurrent(velocity_mps=(float(vel[0]), float(vel[1]))),
            projection=None,
            description=f"uniform {vel.tolist()} m/s",
        )
    if kind == "tidal":
        mean = _velocity(t, "mean_mps", [0.0, 0.0])
        amp = _velocity(t, "amplitude_mps")
        period_h = t.float("period_h", 12.42, lo=0.01, hi=24.0 * 365)
        phase = t.float("phase_deg", 0.0, lo=-360.0, hi=360.0)
        f = TidalCurrent(
            mean_mps=(float(mean[0]), float(mean[1])),
            amplitude_mps=(float(amp[0]), float(amp[1])),
            period_s=period_h * 3600.0,
            phase_rad=phase * DEG,
        )
        desc = f"tidal stream {mean.tolist()} + {amp.tolist()} sin(2 pi t / {period_h:g} h) m/s"
        return CurrentSettings(field=f, projection=None, description=desc)
    if kind == "linear":
        raw = t._get("matrix_per_s", None)
        try:
            mat = np.asarray(raw, dtype=float).reshape(2, 2)
        except (TypeError, ValueError):
            raise t.error("matrix_per_s", f"must be [[a, b], [c, d]] in 1/s, got {raw!r}") from None
        if not (np.all(np.isfinite(mat)) and np.all(np.abs(mat) <= 1.0)):
            raise t.error(
                "matrix_per_s", f"entries must be finite and within [-1, 1] 1/s, got {mat.tolist()}"
            )
        off = _velocity(t, "offset_mps", [0.0, 0.0])
        f = LinearCurrent(
            matrix_per_s=((mat[0, 0], mat[0, 1]), (mat[1, 0], mat[1, 1])),
            offset_mps=(float(off[0]), float(off[1])),
        )
        return CurrentSettings(
            field=f, projection=None, description=f"linear v = {mat.tolist()} p + {off.tolist()}"
        )
    if kind == "rankine":
        centre = _coords(t, "centre_m", 2, [0.0, 0.0])
        radius = t.float("core_radius_m", 2000.0, lo=1.0, hi=MAX_LENGTH_M)
        peak = t.float("peak_speed_mps", 0.5, lo=-MAX_CURRENT_MPS, hi=MAX_CURRENT_MPS)
        pulse = t.float("pulse", 0.0, lo=0.0, hi=1.0)
        period_h = t.float("period_h", 6.0, lo=0.01, hi=24.0 * 365)
        bg = _velocity(t, "background_mps", [0.0, 0.0])
        f = RankineVortexCurrent(
            centre_m=(float(centre[0]), float(centre[1])),
            core_radius_m=radius,
            peak_speed_mps=peak,
            pulse=pulse,
            period_s=period_h * 3600.0,
            background_mps=(float(bg[0]), float(bg[1])),
        )
        desc = (
            f"Rankine vortex R = {radius:g} m, {peak:g} m/s pulsing {pulse:g} over {period_h:g} h, "
            f"carried at {bg.tolist()} m/s"
        )
        return CurrentSettings(field=f, projection=None, description=desc)
    return _netcdf_currents(t, base_dir)


def _velocity(t: Table, key: str, default: object = None) -> np.ndarray:
    """A ``[u, v]`` velocity in m/s within plus or minus :data:`MAX_CURRENT_MPS`."""
    vel = t.vector(key, 2) if default is None else t.vector(key, 2, default)
    if not np.all(np.abs(vel) <= MAX_CURRENT_MPS):
        raise t.error(
            key,
            f"components must lie within [-{MAX_CURRENT_MPS:g}, {MAX_CURRENT_MPS:g}] m/s, got {vel.tolist()}",
        )
    return vel


def _netcdf_currents(t: Table, base_dir: Path) -> CurrentSettings:
    rel = t.str("path")
    path = Path(rel) if Path(rel).is_absolute() else base_dir / rel
    u = t.str("u", "") or None
    v = t.str("v", "") or None
    depth = t.int("depth_index", -1, lo=-1)
    origin = t.vector("origin_lonlat_deg", 2, []) if t.has("origin_lonlat_deg") else None
    if origin is not None and not (-180.0 <= origin[0] <= 360.0 and -90.0 <= origin[1] <= 90.0):
        raise t.error(
            "origin_lonlat_deg",
            f"must be [lon, lat] within [-180, 360] and [-90, 90] degrees, got {origin.tolist()}",
        )
    interp = t.str("interpolation", "linear", choices=("cell", "linear"))
    product = open_current_netcdf(
        path,
        u_var=u,
        v_var=v,
        depth_index=None if depth < 0 else depth,
        origin_lonlat_deg=None if origin is None else (float(origin[0]), float(origin[1])),
        interpolation=interp,  # type: ignore[arg-type]
    )
    f = product.field
    with np.errstate(invalid="ignore"):
        peak = float(np.nanmax(np.hypot(f.u_mps, f.v_mps))) if np.isfinite(f.u_mps).any() else 0.0
    if not peak <= MAX_CURRENT_MPS:
        raise t.error(
            "path",
            f"{path.name} holds currents up to {peak:.3g} m/s; speeds must lie within "
            f"[0, {MAX_CURRENT_MPS:g}] m/s "
            "(check the variables' units and fill values)",
        )
    return CurrentSettings(
        field=product.field,
        projection=product.projection,
        description=product.description,
        land=land_obstacles(product.field),
        data_files=(str(path),),
        time_origin=product.time_origin,
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class DriftSettings:
    """``[drift]``: integrator, step (s) and the longest drift considered (s)."""

    integrator: Method
    dt_s: float
    horizon_s: float


def _drift_settings(t: Table) -> DriftSettings:
    method = t.str("integrator", "rk4", choices=METHODS)
    dt = t.float("dt_s", 60.0, lo=MIN_DT_S, hi=MAX_DT_S)
    horizon_h = t.float("horizon_h", 24.0, lo=0.0, lo_open=True, hi=MAX_HORIZON_H)
    steps = horizon_h * 3600.0 / dt
    if steps > MAX_HORIZON_STEPS:
        raise t.error(
            "horizon_h",
            f"{horizon_h:g} h at dt_s = {dt:g} s is {steps:.3g} drift steps; at most {MAX_HORIZON_STEPS} "
            f"(raise dt_s to at least {horizon_h * 3600.0 / MAX_HORIZON_STEPS:.3g} s or shorten horizon_h to "
            f"at most {MAX_HORIZON_STEPS * dt / 3600.0:.3g} h)",
        )
    t.check_unknown()
    return DriftSettings(integrator=method, dt_s=dt, horizon_s=horizon_h * 3600.0)  # type: ignore[arg-type]


@dataclass(frozen=True, slots=True, kw_only=True)
class MapSettings:
    """``[map]``: the obstacle map and whether flights must avoid obstacles too."""

    obstacles: ObstacleMap
    flights_avoid_obstacles: bool


def _coords(t: Table, key: str, length: int, default: object = None) -> np.ndarray:
    """A vector of ``length`` finite coordinates (m) within plus or minus :data:`MAX_COORD_M`."""
    value = t.vector(key, length) if default is None else t.vector(key, length, default)
    if not np.all(np.abs(value) <= MAX_COORD_M):
        raise t.error(
            key, f"coordinates must lie within [-{MAX_COORD_M:g}, {MAX_COORD_M:g}] m, got {value.tolist()}"
        )
    return value


def _map_bounds(t: Table, default_bounds: tuple[float, float, float, float] | None) -> np.ndarray:
    if t.has("bounds_m") or default_bounds is None:
        bounds = _coords(t, "bounds_m", 4)
    else:
        bounds = np.asarray(default_bounds, dtype=float)
    if not (bounds[0] < bounds[1] and bounds[2] < bounds[3]):
        raise t.error(
            "bounds_m", f"must be [x_min, x_max, y_min, y_max] with min < max, got {bounds.tolist()}"
        )
    return bounds


def _rectangles(t: Table) -> np.ndarray:
    rects = []
    for rt in t.tables("rectangles"):
        xr = _coords(rt, "x_m", 2)
        yr = _coords(rt, "y_m", 2)
        if not (xr[0] < xr[1] and yr[0] < yr[1]):
            raise rt.error(
                "x_m",
                f"needs increasing x_m = [x0, x1] and y_m = [y0, y1], got {xr.tolist()}, {yr.tolist()}",
            )
        rects.append([xr[0], xr[1], yr[0], yr[1]])
        rt.check_unknown()
    return np.asarray(rects, dtype=float).reshape(-1, 4)


def _polygons(t: Table) -> tuple[np.ndarray, ...]:
    polys = []
    for pt in t.tables("polygons"):
        raw = pt._get("vertices_m", None)
        try:
            verts = np.asarray(raw, dtype=float)
        except (TypeError, ValueError):
            raise pt.error("vertices_m", "must be a list of [x, y] pairs") from None
        if verts.ndim != 2 or verts.shape[1] != 2 or verts.shape[0] < 3 or not np.all(np.isfinite(verts)):
            raise pt.error("vertices_m", f"needs at least three finite [x, y] vertices, got {raw!r}")
        if not np.all(np.abs(verts) <= MAX_COORD_M):
            raise pt.error("vertices_m", f"coordinates must lie within [-{MAX_COORD_M:g}, {MAX_COORD_M:g}] m")
        polys.append(verts)
        pt.check_unknown()
    return tuple(polys)


def _map_settings(t: Table, currents: CurrentSettings) -> MapSettings:
    bounds = _map_bounds(t, currents.field.bounds_m)
    inflation = t.float("inflation_m", 0.0, lo=0.0, hi=MAX_LENGTH_M)
    no_fly = t.bool("flights_avoid_obstacles", False)
    rects = _rectangles(t)
    polys = _polygons(t)
    t.check_unknown()
    obstacles = ObstacleMap(
        bounds_m=tuple(bounds.tolist()),
        rectangles_m=rects,
        polygons_m=polys,
        grid=currents.land,
        inflation_m=inflation,
    )
    return MapSettings(obstacles=obstacles, flights_avoid_obstacles=no_fly)


@dataclass(frozen=True, slots=True, kw_only=True)
class RouteSettings:
    """``[route]``: start and goal (m) and the goal disk's radius (m)."""

    start_m: np.ndarray
    goal_m: np.ndarray
    goal_tolerance_m: float
    start_time_s: float = 0.0


MAX_START_TIME_S = 1e10
"""Largest start time accepted, seconds (about 300 years: any clock of a field)."""


def _start_time(t: Table, currents: CurrentSettings, horizon_s: float) -> float:
    """``start_time_s`` (seconds in the field's clock) or ``start_time`` (ISO 8601, gridded products).

    For a field with a time axis the start must lie within it and the horizon must end by its last slice
    (beyond it the current is unknown); the error gives the allowed range.
    """
    if t.has("start_time") and t.has("start_time_s"):
        raise t.error("start_time", "give start_time or start_time_s, not both")
    if t.has("start_time"):
        text = t.str("start_time")
        if currents.time_origin is None:
            raise t.error("start_time", "needs a current product with a time axis; use start_time_s")
        try:
            when = np.datetime64(text.strip().rstrip("Z"), "s")
        except ValueError:
            raise t.error(
                "start_time", f"must be an ISO 8601 time such as 2024-01-01T06:00:00, got {text!r}"
            ) from None
        t0 = float((when - np.datetime64(currents.time_origin, "s")) / np.timedelta64(1, "s"))
        key = "start_time"
    else:
        t0 = t.float("start_time_s", 0.0, lo=-MAX_START_TIME_S, hi=MAX_START_TIME_S)
        key = "start_time_s"
    span = time_span_s(currents.field)
    if span is not None:
        first, last = span
        if not first <= t0 < last:
            origin = f" after {currents.time_origin}" if currents.time_origin else ""
            raise t.error(
                key, f"must lie within the current's time axis, [{first:g}, {last:g}) s{origin}; got {t0:g} s"
            )
        if t0 + horizon_s > last:
            raise t.error(
                key,
                f"the drift horizon ({horizon_s / 3600:g} h) would run past the current's last time slice "
                f"({last:g} s); start by {last - horizon_s:g} s or shorten [drift] horizon_h to at most "
                f"{(last - t0) / 3600:g} h",
            )
    return t0


def _route(t: Table, currents: CurrentSettings, horizon_s: float) -> RouteSettings:
    start = _coords(t, "start_m", 2)
    goal = _coords(t, "goal_m", 2)
    tol = t.float("goal_tolerance_m", 100.0, lo=0.0, lo_open=True, hi=MAX_LENGTH_M)
    gap = float(np.linalg.norm(goal - start))
    if gap < tol:
        raise t.error(
            "goal_m",
            f"{goal.tolist()} is {gap:g} m from start_m, inside the goal disk "
            f"(goal_tolerance_m = {tol:g} m): "
            "nothing to plan; move the goal or reduce goal_tolerance_m",
        )
    t0 = _start_time(t, currents, horizon_s)
    t.check_unknown()
    return RouteSettings(start_m=start, goal_m=goal, goal_tolerance_m=tol, start_time_s=t0)


def _check_route(t: Table, route: RouteSettings, obstacles: ObstacleMap) -> None:
    """Start and goal must be free states of the map."""
    for key, point in (("start_m", route.start_m), ("goal_m", route.goal_m)):
        if not bool(obstacles.is_free(point)):
            raise t.error(key, f"{point.tolist()} is outside the map bounds or inside an obstacle")


@dataclass(frozen=True, slots=True, kw_only=True)
class VehicleSettings:
    """``[vehicle]``: the energy budget (Table 1, IV.14), the longest flight leg (m, ``None``: any) and what
    powered legs move through."""

    energy: EnergyBudget
    max_leg_m: float | None
    propulsion: Propulsion = "air"


def _vehicle(t: Table) -> VehicleSettings:
    energy = EnergyBudget(
        base_load_w=t.float("base_load_w", 5.0, lo=0.0, hi=1e4),
        sensing_w=t.float("sensing_w", 10.0, lo=0.0, hi=1e4),
        sensing_hours_per_day=t.float("sensing_hours_per_day", 6.0, lo=0.0, hi=24.0),
        flight_power_w=t.float("flight_power_w", 200.0, lo=1.0, hi=1e5),
        flight_speed_kn=t.float("flight_speed_kn", 20.0, lo=0.5, hi=200.0),
        solar_wh_per_day=t.float("solar_wh_per_day", 400.0, lo=0.0, hi=1e5),
        max_flight_time_s=t.float("max_flight_time_s", 120.0, lo=1.0, hi=86_400.0),
        nautical_mile_m=t.float("nautical_mile_m", 1852.0, lo=1000.0, hi=3000.0),
    )
    legs = t.str("flight_legs", "hop", choices=("hop", "any"))
    propulsion = t.str("propulsion", "air", choices=PROPULSIONS)
    t.check_unknown()
    return VehicleSettings(
        energy=energy,
        max_leg_m=energy.max_hop_m if legs == "hop" and propulsion == "air" else None,
        propulsion=propulsion,  # type: ignore[arg-type]
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class HdopSettings:
    """``[hdop]``: other flock members and the target of the HDOP term (m), or neither."""

    others_m: np.ndarray | None = None
    target_m: np.ndarray | None = None


def _hdop(t: Table) -> HdopSettings:
    if not t.has("others_m"):
        t.check_unknown()
        return HdopSettings()
    raw = t._get("others_m", None)
    try:
        others = np.asarray(raw, dtype=float).reshape(-1, 2)
    except (TypeError, ValueError):
        raise t.error("others_m", "must be a list of [x, y] positions") from None
    if others.shape[0] < 1 or not np.all(np.abs(others) <= MAX_COORD_M):
        raise t.error(
            "others_m", f"needs at least one [x, y] position within [-{MAX_COORD_M:g}, {MAX_COORD_M:g}] m"
        )
    target = _coords(t, "target_m", 2)
    t.check_unknown()
    return HdopSettings(others_m=others, target_m=target)


@dataclass(frozen=True, slots=True, kw_only=True)
class PlannerSettings:
    """``[planner]``: default planner, its seed, the price of time (Wh per hour), the objective and the
    deadline (s after the start, or ``None``)."""

    planner: DriftPlannerName
    seed: int
    time_weight_wh_per_h: float
    objective: Objective = "energy"
    max_duration_s: float | None = None


def _planner_settings(t: Table, horizon_s: float) -> PlannerSettings:
    raw = t.str("kind", "oceanloc")
    planner = parse_planner_name(raw, t.where("kind") + ":")
    seed = t.int("seed", 1, lo=0, hi=MAX_SEED)
    time_weight = t.float("time_weight_wh_per_h", 0.0, lo=0.0, hi=1e4)
    objective = t.str("objective", "energy", choices=OBJECTIVES)
    deadline = None
    if t.has("deadline_h"):
        deadline = t.float("deadline_h", 12.0, lo=0.0, lo_open=True, hi=MAX_HORIZON_H) * 3600.0
        if deadline > horizon_s + 1e-6:
            raise t.error(
                "deadline_h",
                f"{deadline / 3600:g} h is beyond the planning horizon "
                f"([drift] horizon_h = {horizon_s / 3600:g} h)",
            )
    t.check_unknown()
    return PlannerSettings(
        planner=planner,
        seed=seed,
        time_weight_wh_per_h=time_weight,
        objective=objective,  # type: ignore[arg-type]
        max_duration_s=deadline,
    )


def _following(t: Table) -> FollowingSettings:
    following = FollowingSettings(
        watch_circle_m=t.float("watch_circle_m", 150.0, lo=0.0, lo_open=True, hi=MAX_LENGTH_M),
        current_scale=t.float("current_scale", 1.1, lo=0.0, hi=10.0),
        current_rotation_rad=t.float("current_rotation_deg", 5.0, lo=-180.0, hi=180.0) * DEG,
        noise_mps=t.float("noise_mps", 0.05, lo=0.0, hi=MAX_CURRENT_MPS),
        noise_correlation_s=t.float("noise_correlation_s", 1800.0, lo=1.0, hi=1e7),
        stray_m=t.float("stray_m", 400.0, lo=0.0, lo_open=True, hi=MAX_LENGTH_M),
        max_replans=t.int("max_replans", 20, lo=0, hi=1000),
        runs=t.int("runs", 200, lo=1, hi=100_000),
        seed=t.int("seed", 7, lo=0, hi=MAX_SEED),
    )
    t.check_unknown()
    return following


def drift_scenario_from_table(root: Table, base_dir: Path | None = None) -> DriftScenario:
    """Validate a parsed drift scenario; every error names the file, table and field.

    Each table is read by its own function (``[currents]``, ``[drift]``, ``[map]``, ``[route]``,
    ``[vehicle]``, ``[hdop]``, ``[planner]``, ``[following]``), each returning a small frozen result.
    """
    base = base_dir or Path.cwd()
    head = root.table("scenario")
    name = head.str("name")
    description = head.str("description", "")
    head.check_unknown()
    cur_t = root.table("currents")
    currents = _currents(cur_t, base)
    cur_t.check_unknown()
    drift = _drift_settings(root.table("drift", required=False))
    map_ = _map_settings(root.table("map", required=False), currents)
    route_t = root.table("route")
    route = _route(route_t, currents, drift.horizon_s)
    vehicle = _vehicle(root.table("vehicle", required=False))
    hdop = _hdop(root.table("hdop", required=False))
    planner = _planner_settings(root.table("planner", required=False), drift.horizon_s)
    following = _following(root.table("following", required=False))
    root.check_unknown()
    _check_route(route_t, route, map_.obstacles)
    scenario = DriftScenario(
        name=name,
        description=description,
        current=currents.field,
        integrator=drift.integrator,
        dt_s=drift.dt_s,
        horizon_s=drift.horizon_s,
        obstacles=map_.obstacles,
        flights_avoid_obstacles=map_.flights_avoid_obstacles,
        start_m=route.start_m,
        goal_m=route.goal_m,
        goal_tolerance_m=route.goal_tolerance_m,
        start_time_s=route.start_time_s,
        energy=vehicle.energy,
        max_leg_m=vehicle.max_leg_m,
        propulsion=vehicle.propulsion,
        objective=planner.objective,
        max_duration_s=planner.max_duration_s,
        hdop_others_m=hdop.others_m,
        hdop_target_m=hdop.target_m,
        planner=planner.planner,
        seed=planner.seed,
        time_weight_wh_per_h=planner.time_weight_wh_per_h,
        following=following,
        projection=currents.projection,
        currents_description=currents.description,
        data_files=currents.data_files,
    )
    if scenario.planner == "oceanloc":
        check_planning_memory(scenario, root.source)
    return scenario


def problem_from_scenario(scenario: DriftScenario) -> DriftProblem:
    """The planning problem a validated scenario file describes."""
    hdop = None
    if scenario.hdop_others_m is not None and scenario.hdop_target_m is not None:
        hdop = HdopTerm(others_m=scenario.hdop_others_m, target_m=scenario.hdop_target_m)
    return DriftProblem(
        space=DriftSpace(
            obstacles=scenario.obstacles, flights_avoid_obstacles=scenario.flights_avoid_obstacles
        ),
        propagator=DriftPropagator(field=scenario.current, dt_s=scenario.dt_s, method=scenario.integrator),
        start_m=scenario.start_m,
        goal_m=scenario.goal_m,
        goal_tolerance_m=scenario.goal_tolerance_m,
        energy=scenario.energy,
        hdop=hdop,
        horizon_s=scenario.horizon_s,
        max_leg_m=scenario.max_leg_m,
        time_weight_wh_per_h=scenario.time_weight_wh_per_h,
        t0_s=scenario.start_time_s,
        objective=scenario.objective,
        max_duration_s=scenario.max_duration_s,
        propulsion=scenario.propulsion,
    )
