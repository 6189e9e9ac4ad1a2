"""A drift scenario on a forecast product chosen at the command line (``oceanloc drift-plan --currents``).

:func:`scenario_on_product` keeps a scenario's vehicle, planner, integrator and following settings and
replaces its current, map and route with a product read from a file (or several files, the members of an
ensemble): the level (``depth_m``) and the time window are the user's; the map is the product's grid with
its land as obstacles (grown by the scenario's margin); start and goal are longitude/latitude; the start
time is an ISO 8601 time within the product (its first slice by default) and the planning horizon is cut
to the product's last slice. Every check of a scenario file applies, with errors naming the option.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from oceanloc.config.drift import DriftScenario, check_planning_memory
from oceanloc.config.drift_currents import check_product_speeds, product_settings
from oceanloc.errors import ConfigError, DataError
from oceanloc.models.currents import GridCurrent
from oceanloc.models.currents_cf import CurrentProduct, assemble_product, open_current_product
from oceanloc.models.obstacles import ObstacleMap

__all__ = ["ProductRoute", "scenario_on_product"]


@dataclass(frozen=True, slots=True, kw_only=True)
class ProductRoute:
    """What the command line asks of a product.

    Attributes
    ----------
    paths : tuple of Path
        The product (one file or Zarr store), or one file per ensemble member.
    start_lonlat_deg, goal_lonlat_deg : (lon, lat)
    start_time : str or None
        ISO 8601; the product's first slice when ``None``.
    depth_m : float or None
        Level nearest to this depth; the surface when ``None``.
    time_window : (start, end) or None
        ISO 8601 times: the slices read.
    """

    paths: tuple[Path, ...]
    start_lonlat_deg: tuple[float, float]
    goal_lonlat_deg: tuple[float, float]
    start_time: str | None = None
    depth_m: float | None = None
    time_window: tuple[str, str] | None = None


def _read(route: ProductRoute) -> CurrentProduct:
    origin = (
        0.5 * (route.start_lonlat_deg[0] + route.goal_lonlat_deg[0]),
        0.5 * (route.start_lonlat_deg[1] + route.goal_lonlat_deg[1]),
    )
    kw = dict(depth_m=route.depth_m, time_window=route.time_window, origin_lonlat_deg=origin)
    products = [open_current_product(p, **kw) for p in route.paths]
    if len(products) == 1:
        return products[0]
    first = products[0]
    for p, prod in zip(route.paths[1:], products[1:], strict=True):
        same = (
            prod.field.x_m.shape == first.field.x_m.shape
            and prod.field.y_m.shape == first.field.y_m.shape
            and np.allclose(prod.field.x_m, first.field.x_m)
            and np.allclose(prod.field.y_m, first.field.y_m)
            and prod.time_origin == first.time_origin
            and (prod.field.time_s is None) == (first.field.time_s is None)
            and (prod.field.time_s is None or np.array_equal(prod.field.time_s, first.field.time_s))
        )
        if not same or prod.members:
            raise DataError(f"{p}: an ensemble member must share the first member's grid and time axis")
    u = np.stack([prod.field.u_mps for prod in products])
    v = np.stack([prod.field.v_mps for prod in products])
    desc = f"{len(products)} files: {first.description}"
    return assemble_product(
        first.field.x_m,
        first.field.y_m,
        u,
        v,
        first.field.time_s,
        first.time_origin,
        first.projection,
        desc,
        [],
        first.field.interpolation,
        layout=first.layout,
    )


def scenario_on_product(base: DriftScenario, route: ProductRoute) -> DriftScenario:
    """``base`` on the product of ``route`` (see the module docstring)."""
    product = _read(route)
    try:
        check_product_speeds(product, route.paths[0].name)
    except ValueError as exc:
        raise ConfigError(f"--currents: {exc}") from None
    if product.projection is None:
        raise ConfigError(
            "--currents: the product is on projected x/y, not longitude/latitude; use --scenario"
        )
    settings = product_settings(product, tuple(str(p) for p in route.paths))
    f: GridCurrent = product.field
    proj = product.projection
    start = np.array(proj.to_local(*route.start_lonlat_deg), dtype=float)
    goal = np.array(proj.to_local(*route.goal_lonlat_deg), dtype=float)
    obstacles = ObstacleMap(bounds_m=f.bounds_m, grid=settings.land, inflation_m=base.obstacles.inflation_m)
    for name, point in (("--start", start), ("--goal", goal)):
        if not bool(obstacles.is_free(point)):
            raise ConfigError(
                f"{name}: outside the product's grid, on land or within {obstacles.inflation_m:g} m of it"
            )
    if float(np.linalg.norm(goal - start)) < base.goal_tolerance_m:
        raise ConfigError(f"--goal: within {base.goal_tolerance_m:g} m of --start: nothing to plan")
    t0 = 0.0
    span_end = math.inf if f.time_s is None else float(f.time_s[-1])
    if route.start_time is not None:
        if product.time_origin is None:
            raise ConfigError("--start-time: the product has no time axis")
        try:
            when = np.datetime64(route.start_time.strip().rstrip("Z"), "s")
        except ValueError:
            raise ConfigError(f"--start-time: {route.start_time!r} is not an ISO 8601 time") from None
        t0 = float((when - np.datetime64(product.time_origin[:19], "s")) / np.timedelta64(1, "s"))
        if f.time_s is not None and not float(f.time_s[0]) <= t0 < span_end:
            raise ConfigError(
                f"--start-time: {route.start_time} is outside the product's time axis "
                f"({product.time_origin} + {span_end / 3600:g} h)"
            )
    horizon = min(base.horizon_s, span_end - t0)
    if base.max_duration_s is not None and base.max_duration_s > horizon:
        raise ConfigError(
            f"--deadline-h: {base.max_duration_s / 3600:g} h runs past the product's last slice "
            f"({horizon / 3600:g} h after the start)"
        )
    scenario = dataclasses.replace(
        base,
        name=f"{base.name}@{route.paths[0].stem}",
        current=f,
        obstacles=obstacles,
        start_m=start,
        goal_m=goal,
        start_time_s=t0,
        horizon_s=horizon,
        projection=proj,
        currents_description=product.description,
        data_files=settings.data_files,
        ensemble=product.members,
        time_origin=product.time_origin,
        hdop_others_m=None,
        hdop_target_m=None,
    )
    check_planning_memory(scenario, "--currents")
    return scenario
