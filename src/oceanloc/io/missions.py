"""Drift plans as vehicle missions: MAVLink mission items, QGroundControl ``.plan`` files and the MAVLink
plain-text mission format (``QGC WPL 110``).

A drift plan alternates drifts with powered legs. A vehicle cannot be told "drift to this point" (where a
drift ends is the current's doing), only "hold for this long": a drift leg becomes a hold item of the
plan's duration, and each powered leg a navigation item to its end point. The mapping
(:func:`drift_mission`):

- ``vehicle="boat"`` (ArduPilot Rover in a BlueBoat or any surface vehicle): a powered leg is a
  ``MAV_CMD_NAV_WAYPOINT`` (16) at its end; a drift is ``MAV_CMD_NAV_DELAY`` (93) with ``param1`` the
  drift's seconds: Rover stops its motors for the delay and the current carries the boat (a loiter item
  would hold station against the current, the opposite of drifting). ``drift_item="loiter"`` writes
  ``MAV_CMD_NAV_LOITER_TIME`` (19) at the drift's start instead, for autopilots whose loiter lets the hull
  drift within a radius (``param3``, set to the drift's planned extent).
- ``vehicle="aquaquad"`` (a drifting quadrotor, Dillard's AquaQuad): each flight is
  ``MAV_CMD_NAV_TAKEOFF`` (22) to the cruise altitude, ``MAV_CMD_NAV_WAYPOINT`` to the landing point and
  ``MAV_CMD_NAV_LAND`` (21) there; a drift is ``MAV_CMD_NAV_DELAY`` on the water.

Item 0 is home (the plan's start), as ArduPilot stores it; the plain-text format writes it, the
``.plan`` file keeps it as ``plannedHomePosition`` (QGroundControl's own convention). The ``.plan`` layout
is QGroundControl's documented plan format (file version 1, mission version 2, ``SimpleItem`` entries with
seven ``params``, ``MAV_AUTOPILOT`` and ``MAV_TYPE`` numbers).
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from oceanloc.errors import ConfigError
from oceanloc.geo.projection import LocalProjection
from oceanloc.io._mavlink import mavlink
from oceanloc.models.paths import DriftPath

MissionVehicle = Literal["boat", "aquaquad"]
DriftItem = Literal["hold", "loiter"]

FIRMWARE_ARDUPILOT = mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA
VEHICLE_TYPES = {"boat": mavlink.MAV_TYPE_SURFACE_BOAT, "aquaquad": mavlink.MAV_TYPE_QUADROTOR}


@dataclass(frozen=True, slots=True, kw_only=True)
class MissionItem:
    """One MAVLink mission item (``MISSION_ITEM_INT``): command, frame, ``param1..4`` and x/y/z.

    Attributes
    ----------
    command : int
        ``MAV_CMD``.
    frame : int
        ``MAV_FRAME`` (``MAV_FRAME_MISSION`` for items without a position).
    params : (4,) float
        ``param1..4`` (``NaN``: unused).
    lat_deg, lon_deg, alt_m : float
        Position (0 for items without one).
    autocontinue : bool
    """

    command: int
    frame: int
    params: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    lat_deg: float = 0.0
    lon_deg: float = 0.0
    alt_m: float = 0.0
    autocontinue: bool = True

    @property
    def has_position(self) -> bool:
        return self.frame != mavlink.MAV_FRAME_MISSION


def waypoint(lat_deg: float, lon_deg: float, alt_m: float = 0.0) -> MissionItem:
    """``MAV_CMD_NAV_WAYPOINT`` at a position (relative altitude), no hold."""
    return MissionItem(
        command=mavlink.MAV_CMD_NAV_WAYPOINT,
        frame=mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT,
        lat_deg=lat_deg,
        lon_deg=lon_deg,
        alt_m=alt_m,
    )


def drift_mission(
    plan: DriftPath,
    projection: LocalProjection,
    *,
    vehicle: MissionVehicle = "boat",
    altitude_m: float = 20.0,
    drift_item: DriftItem = "hold",
) -> list[MissionItem]:
    """The mission items of ``plan`` (see the module docstring); item 0 is home at the plan's start."""
    if vehicle not in VEHICLE_TYPES:
        raise ConfigError(f"mission vehicle must be one of {', '.join(VEHICLE_TYPES)}; got '{vehicle}'")
    if drift_item not in ("hold", "loiter"):
        raise ConfigError(f"drift item must be 'hold' or 'loiter'; got '{drift_item}'")
    if not (math.isfinite(altitude_m) and 0.0 < altitude_m <= 500.0):
        raise ConfigError(f"mission altitude must be within (0, 500] m, got {altitude_m}")
    if plan.n_points == 0:
        raise ConfigError("an empty plan has no mission")
    lon, lat = projection.to_lonlat(plan.points_m[:, 0], plan.points_m[:, 1])
    items = [waypoint(float(lat[0]), float(lon[0]))]
    i = 0
    n_edges = plan.flight.size
    landed = True
    while i < n_edges:
        j = i
        while j < n_edges and plan.flight[j] == plan.flight[i]:
            j += 1
        if not plan.flight[i]:
            seconds = float(plan.times_s[j] - plan.times_s[i])
            extent = float(np.max(np.linalg.norm(plan.points_m[i : j + 1] - plan.points_m[i], axis=1)))
            items.append(_drift(drift_item, seconds, float(lat[i]), float(lon[i]), extent))
        else:
            for k in range(i, j):
                la, lo = float(lat[k + 1]), float(lon[k + 1])
                if vehicle == "boat":
                    items.append(waypoint(la, lo))
                    continue
                if landed:
                    items.append(
                        MissionItem(
                            command=mavlink.MAV_CMD_NAV_TAKEOFF,
                            frame=mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                            params=(0.0, 0.0, 0.0, math.nan),
                            lat_deg=float(lat[k]),
                            lon_deg=float(lon[k]),
                            alt_m=altitude_m,
                        )
                    )
                items.append(waypoint(la, lo, altitude_m))
                items.append(
                    MissionItem(
                        command=mavlink.MAV_CMD_NAV_LAND,
                        frame=mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                        params=(0.0, 0.0, 0.0, math.nan),
                        lat_deg=la,
                        lon_deg=lo,
                    )
                )
                landed = True
        i = j
    return items


def _drift(kind: DriftItem, seconds: float, lat: float, lon: float, extent_m: float) -> MissionItem:
    if kind == "hold":
        return MissionItem(
            command=mavlink.MAV_CMD_NAV_DELAY,
            frame=mavlink.MAV_FRAME_MISSION,
            params=(round(seconds, 1), -1.0, -1.0, -1.0),
        )
    return MissionItem(
        command=mavlink.MAV_CMD_NAV_LOITER_TIME,
        frame=mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT,
        params=(round(seconds, 1), 0.0, round(max(extent_m, 1.0), 1), 0.0),
        lat_deg=lat,
        lon_deg=lon,
    )


def qgc_plan(
    items: Sequence[MissionItem], *, vehicle: MissionVehicle = "boat", cruise_speed_mps: float = 2.0
) -> dict[str, Any]:
    """A QGroundControl plan (its documented JSON format) from mission items whose item 0 is home."""
    if len(items) < 2:
        raise ConfigError("a QGroundControl plan needs home and at least one mission item")
    home = items[0]
    entries = []
    for k, it in enumerate(items[1:], start=1):
        params: list[float | None] = [None if math.isnan(p) else float(p) for p in it.params]
        if it.has_position:
            params += [round(it.lat_deg, 8), round(it.lon_deg, 8), float(it.alt_m)]
        else:
            params += [0.0, 0.0, 0.0]
        entry: dict[str, Any] = {
            "autoContinue": bool(it.autocontinue),
            "command": int(it.command),
            "doJumpId": k,
            "frame": int(it.frame),
            "params": params,
            "type": "SimpleItem",
        }
        if it.has_position:
            entry.update({"AMSLAltAboveTerrain": None, "Altitude": float(it.alt_m), "AltitudeMode": 1})
        entries.append(entry)
    return {
        "fileType": "Plan",
        "geoFence": {"circles": [], "polygons": [], "version": 2},
        "groundStation": "QGroundControl",
        "mission": {
            "cruiseSpeed": float(cruise_speed_mps),
            "firmwareType": int(FIRMWARE_ARDUPILOT),
            "globalPlanAltitudeMode": 1,
            "hoverSpeed": float(cruise_speed_mps),
            "items": entries,
            "plannedHomePosition": [round(home.lat_deg, 8), round(home.lon_deg, 8), 0.0],
            "vehicleType": int(VEHICLE_TYPES[vehicle]),
            "version": 2,
        },
        "rallyPoints": {"points": [], "version": 2},
        "version": 1,
    }


def waypoints_text(items: Sequence[MissionItem]) -> str:
    """The MAVLink plain-text mission (``QGC WPL 110``: index, current, frame, command, param1..4, x, y, z,
    autocontinue, tab-separated), item 0 home."""
    lines = ["QGC WPL 110"]
    for k, it in enumerate(items):
        p = [0.0 if math.isnan(v) else v for v in it.params]
        cells = [
            k,
            1 if k == 0 else 0,
            it.frame,
            it.command,
            *p,
            it.lat_deg,
            it.lon_deg,
            it.alt_m,
            int(it.autocontinue),
        ]
        lines.append("\t".join(f"{c:.8f}" if isinstance(c, float) else str(c) for c in cells))
    return "\n".join(lines) + "\n"


def read_waypoints_text(text: str, source: str = "mission") -> list[MissionItem]:
    """Parse ``QGC WPL 110`` text (the inverse of :func:`waypoints_text`); errors name the line."""
    lines = [ln for ln in text.splitlines() if ln.strip()]
    if not lines or not lines[0].startswith("QGC WPL"):
        raise ConfigError(f"{source}: line 1: expected 'QGC WPL 110'")
    items = []
    for no, ln in enumerate(lines[1:], start=2):
        cells = ln.split("\t")
        if len(cells) != 12:
            raise ConfigError(f"{source}: line {no}: expected 12 tab-separated fields, got {len(cells)}")
        try:
            v = [float(c) for c in cells]
        except ValueError:
            raise ConfigError(f"{source}: line {no}: not numbers") from None
        items.append(
            MissionItem(
                command=int(v[3]), frame=int(v[2]), params=(v[4], v[5], v[6], v[7]),
                lat_deg=v[8], lon_deg=v[9], alt_m=v[10], autocontinue=bool(v[11]),
            )
        )  # fmt: skip
    return items


def write_qgc_plan(path: str | Path, plan: dict[str, Any]) -> Path:
    p = Path(path)
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(json.dumps(plan, indent=4) + "\n", encoding="utf-8")
    except OSError as exc:
        raise ConfigError(f"{p}: cannot write the plan ({exc})") from None
    return p


def write_waypoints(path: str | Path, items: Sequence[MissionItem]) -> Path:
    p = Path(path)
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(waypoints_text(items), encoding="utf-8")
    except OSError as exc:
        raise ConfigError(f"{p}: cannot write the mission ({exc})") from None
    return p
