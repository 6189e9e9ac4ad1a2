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
    # netcdf: path (relative to this file; a NetCDF file or a Zarr store), u, v, depth_m or depth_index,
    # time_window = ["2024-03-01T00:00:00", "2024-03-02T00:00:00"], origin_lonlat_deg

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
    # start_lonlat_deg = [-117.3, 32.6] and goal_lonlat_deg instead of start_m/goal_m (lon/lat products)

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
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from oceanloc.config.builtin import builtin_folder, builtin_names, resolve_scenario
from oceanloc.config.drift_currents import (
    MAX_COORD_M,
    MAX_CURRENT_MPS,
    MAX_DT_S,
    MAX_HORIZON_H,
    MAX_HORIZON_STEPS,
    MAX_LENGTH_M,
    MAX_SEED,
    MIN_DT_S,
    CurrentSettings,
    _coords,
    _currents,
)
from oceanloc.config.toml_fields import Table
from oceanloc.errors import ConfigError
from oceanloc.geo.projection import LocalProjection
from oceanloc.models.currents import CurrentField, time_span_s
from oceanloc.models.drift import METHODS, Method
from oceanloc.models.energy import EnergyBudget
from oceanloc.models.obstacles import ObstacleMap
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
    ensemble : tuple of CurrentField
        The members of an ensemble forecast (``current`` is their mean); empty for one forecast.
    time_origin : str or None
        The product's first time slice (ISO 8601), time 0 of ``start_time_s``.
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
    ensemble: tuple[CurrentField, ...] = ()
    time_origin: str | None = None
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
    start = _position(t, "start", currents.projection)
    goal = _position(t, "goal", currents.projection)
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


def _position(t: Table, what: str, projection: LocalProjection | None) -> np.ndarray:
    """``{what}_m`` (metres in the local frame) or ``{what}_lonlat_deg`` (a product's longitude/latitude)."""
    key_m, key_ll = f"{what}_m", f"{what}_lonlat_deg"
    if t.has(key_ll):
        if t.has(key_m):
            raise t.error(key_ll, f"give {key_m} or {key_ll}, not both")
        if projection is None:
            raise t.error(key_ll, "needs a longitude/latitude current product; use " + key_m)
        lonlat = t.vector(key_ll, 2)
        if not (-360.0 <= lonlat[0] <= 360.0 and -90.0 < lonlat[1] < 90.0):
            raise t.error(key_ll, f"must be [lon, lat] in degrees, got {lonlat.tolist()}")
        x, y = projection.to_local(lonlat[0], lonlat[1])
        return np.array([float(x), float(y)])
    return _coords(t, key_m, 2)


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
        ensemble=currents.members,
        time_origin=currents.time_origin,
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
