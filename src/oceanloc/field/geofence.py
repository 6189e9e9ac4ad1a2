"""Safety checks of a live survey, as pure functions: the geofence, the leg length and the link watchdog.

- **Geofence.** A circle about the start (:func:`fence_from_radius`) or a GeoJSON polygon read from a file
  (:func:`read_geofence`; RFC 7946: ``[longitude, latitude]`` positions, closed rings, one exterior ring,
  no holes). The fence lives in metres east and north of its origin on the WGS84 surface
  (:class:`oceanloc.geo.projection.LocalProjection`), where "inside" is decided by the even-odd rule
  (polygons) or the distance to the centre (circles).
- **Commanded sites** (:func:`check_site`): no site that is sent to the vehicle leaves the fence, and no
  leg from where the vehicle is to the site is longer than ``max_leg_m``. A site that breaks either is
  clipped (pulled to the nearest point ``margin_m`` inside the fence; a long leg shortened along its
  line) or refused, each with a reason. The returned site is always verified against both rules at the
  end, so a clipped site is inside by construction; when clipping cannot satisfy both, the site is refused.
- **Link watchdog** (:func:`watchdog_check`): the position, the ranges and the vehicle link each have a
  timeout; when any goes quiet past it the verdict is the action HOLD and a message saying which and for
  how long; HOLD is asked again when the vehicle link comes back while others are still quiet (the first
  HOLD may not have reached the boat), and ``resume`` once all are fresh again.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Literal

import numpy as np

from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.errors import ConfigError
from oceanloc.geo.projection import LocalProjection
from oceanloc.io.geojson import ring_signed_area

# -- the fence -----------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True, kw_only=True)
class Geofence:
    """A geofence in metres about its origin.

    Attributes
    ----------
    origin_lat_deg, origin_lon_deg : float
        Origin of the local frame: the circle's centre, or the polygon's first vertex.
    radius_m : float
        The circle's radius, metres (NaN for a polygon).
    ring_en_m : (n, 2) float
        A polygon's vertices, east and north metres, counter-clockwise, not repeated at the end (empty for
        a circle).
    source : str
        Where the fence came from (``radius 500 m about ...`` or the file name), for messages.
    """

    origin_lat_deg: float
    origin_lon_deg: float
    radius_m: float = math.nan
    ring_en_m: FloatArray = field(default_factory=lambda: np.zeros((0, 2)))
    source: str = ""

    @property
    def kind(self) -> Literal["radius", "polygon"]:
        return "radius" if self.ring_en_m.shape[0] == 0 else "polygon"

    @property
    def projection(self) -> LocalProjection:
        return LocalProjection(lat0_deg=self.origin_lat_deg, lon0_deg=self.origin_lon_deg)

    def to_local(self, lat_deg: ArrayLike, lon_deg: ArrayLike) -> FloatArray:
        """Points (degrees) to ``(..., 2)`` east/north metres in the fence's frame."""
        e, n = self.projection.to_local(lon_deg, lat_deg)
        return np.stack(np.broadcast_arrays(e, n), axis=-1)

    def to_lat_lon(self, en_m: ArrayLike) -> tuple[float, float]:
        """One local point (metres) back to latitude and longitude, degrees."""
        p = np.asarray(en_m, dtype=float)
        lon, lat = self.projection.to_lonlat(p[0], p[1])
        return float(lat), float(lon)

    def to_record(self) -> dict:
        return {
            "kind": self.kind,
            "origin_lat_deg": self.origin_lat_deg,
            "origin_lon_deg": self.origin_lon_deg,
            "radius_m": None if self.kind == "polygon" else self.radius_m,
            "n_vertices": int(self.ring_en_m.shape[0]),
            "source": self.source,
        }


def fence_from_radius(center_lat_deg: float, center_lon_deg: float, radius_m: float) -> Geofence:
    """A circular fence of ``radius_m`` metres about a point (usually the start)."""
    if not (math.isfinite(radius_m) and radius_m > 0.0):
        raise ConfigError(f"geofence radius must be a positive number of metres, got {radius_m}")
    LocalProjection(lat0_deg=center_lat_deg, lon0_deg=center_lon_deg)  # validates the centre
    return Geofence(
        origin_lat_deg=float(center_lat_deg),
        origin_lon_deg=float(center_lon_deg),
        radius_m=float(radius_m),
        source=f"radius {radius_m:g} m about {center_lat_deg:.6f}, {center_lon_deg:.6f}",
    )


def fence_from_ring(ring_lon_lat_deg: ArrayLike, source: str = "polygon") -> Geofence:
    """A polygon fence from one closed ring of ``[lon, lat]`` positions (degrees), checked as a file's."""
    ring = np.asarray(ring_lon_lat_deg, dtype=float)
    if ring.ndim != 2 or ring.shape[1] < 2 or ring.shape[0] < 4:
        raise ConfigError(f"{source}: a polygon ring needs at least 4 positions (3 distinct, closed)")
    ring = ring[:, :2]
    if not np.all(np.isfinite(ring)):
        raise ConfigError(f"{source}: NaN or infinite coordinate in the polygon")
    if np.any(np.abs(ring[:, 1]) >= 90.0) or np.any(np.abs(ring[:, 0]) > 180.0):
        raise ConfigError(f"{source}: positions must be [longitude, latitude] within [-180, 180] x (-90, 90)")
    if not np.array_equal(ring[0], ring[-1]):
        raise ConfigError(f"{source}: the polygon ring is not closed (RFC 7946 3.1.6: last position = first)")
    lon0, lat0 = ring[0]
    fence = Geofence(origin_lat_deg=float(lat0), origin_lon_deg=float(lon0), source=source)
    en = fence.to_local(ring[:-1, 1], ring[:-1, 0])
    if np.unique(np.round(en, 6), axis=0).shape[0] < 3:
        raise ConfigError(f"{source}: the polygon has fewer than 3 distinct vertices")
    crossing = _self_crossing(en)
    if crossing is not None:
        raise ConfigError(
            f"{source}: the polygon crosses itself (edges {crossing[0] + 1} and {crossing[1] + 1})"
        )
    area = ring_signed_area(np.vstack([en, en[:1]]))
    if abs(area) < 1.0:
        raise ConfigError(f"{source}: the polygon encloses no area ({abs(area):.2g} m^2)")
    if area < 0.0:
        en = en[::-1].copy()
    return replace(fence, ring_en_m=en)


def read_geofence(path: str | Path) -> Geofence:
    """Read a polygon fence from a GeoJSON file: a FeatureCollection, a Feature or a bare geometry.

    Exactly one Polygon must be present (a MultiPolygon of one polygon is accepted); it must have no holes.

    Raises
    ------
    ConfigError
        Naming the file and what is wrong: unreadable, not JSON (with line and column), no polygon or
        several, holes, a ring that is open, too short, out of range, of no area, or crossing itself.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(
            f"{p}: cannot read the geofence ({getattr(exc, 'strerror', None) or exc})"
        ) from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ConfigError(f"{p}: not JSON (line {exc.lineno}, column {exc.colno}: {exc.msg})") from None
    except RecursionError:
        raise ConfigError(f"{p}: JSON nested too deeply to be a geofence") from None
    polygons: list = []
    others: list[str] = []
    try:
        _collect_polygons(doc, polygons, others)
    except ConfigError as exc:
        raise ConfigError(f"{p}: {exc}") from None
    if not polygons:
        found = f" (found {', '.join(sorted(set(others)))})" if others else ""
        raise ConfigError(f"{p}: no Polygon in the GeoJSON{found}")
    if len(polygons) > 1:
        raise ConfigError(f"{p}: {len(polygons)} polygons in the GeoJSON; the geofence must be one")
    rings = polygons[0]
    if not isinstance(rings, list) or not rings:
        raise ConfigError(f"{p}: the Polygon has no coordinates")
    if len(rings) > 1:
        raise ConfigError(f"{p}: the polygon has {len(rings) - 1} hole(s); holes are not supported")
    try:
        ring = np.asarray(rings[0], dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(f"{p}: polygon positions must be lists of numbers [lon, lat]") from None
    return fence_from_ring(ring, source=str(p))


_MAX_GEOJSON_DEPTH = 16
"""Deepest nesting of GeoJSON objects searched for the polygon (FeatureCollection > Feature >
GeometryCollection > ... is a handful of levels in any real file)."""


def _collect_polygons(doc: object, polygons: list, others: list[str]) -> None:
    """The Polygon coordinate lists in a GeoJSON document, searched without recursion.

    Raises
    ------
    ConfigError
        Objects nested deeper than ``_MAX_GEOJSON_DEPTH`` (the caller adds the file name).
    """
    stack: list[tuple[object, int]] = [(doc, 0)]
    while stack:
        obj, depth = stack.pop()
        if not isinstance(obj, Mapping):
            continue
        if depth > _MAX_GEOJSON_DEPTH:
            raise ConfigError(f"GeoJSON objects nested deeper than {_MAX_GEOJSON_DEPTH} levels")
        kind = obj.get("type")
        children: list = []
        if kind == "FeatureCollection":
            children = obj.get("features") or []
        elif kind == "Feature":
            children = [obj.get("geometry")]
        elif kind == "GeometryCollection":
            children = obj.get("geometries") or []
        elif kind == "Polygon":
            polygons.append(obj.get("coordinates"))
        elif kind == "MultiPolygon":
            polygons.extend(obj.get("coordinates") or [])
        elif isinstance(kind, str):
            others.append(kind)
        if isinstance(children, list):
            stack.extend((child, depth + 1) for child in reversed(children))


_CROSSING_CHUNK = 1 << 20
"""Candidate edge pairs tested per vectorized batch (bounds the check's memory)."""


def _self_crossing(ring_en: FloatArray) -> tuple[int, int] | None:
    """The first pair ``(i, j)``, ``i < j``, of non-adjacent edges that cross, or None.

    A sweep along one axis: the edges sorted by their lower coordinate on it, each is tested only
    against the edges whose extent on that axis overlaps its own (found by binary search), then against
    those whose extent on the other axis overlaps too, then by the orientation test, all in vectorized
    batches. The axis with fewer overlapping pairs is swept. For a coastline the pairs are a small
    multiple of the edges, so a 200,000-vertex ring is checked in a fraction of a second.
    """
    a = ring_en
    b = np.roll(ring_en, -1, axis=0)
    n = a.shape[0]
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    best: tuple[int, int] | None = None
    sweeps = []
    for axis in (0, 1):
        order = np.argsort(lo[:, axis], kind="stable")
        ends = np.searchsorted(lo[order, axis], hi[order, axis], side="right")
        counts = np.maximum(ends - np.arange(n) - 1, 0)
        sweeps.append((int(counts.sum()), axis, order, counts))
    _, axis, order, counts = min(sweeps, key=lambda sweep: sweep[0])
    other = 1 - axis
    first = np.concatenate([[0], np.cumsum(counts)])
    start = 0
    while start < n:
        stop = int(np.searchsorted(first, first[start] + _CROSSING_CHUNK, side="right")) - 1
        stop = max(stop, start + 1)
        c = counts[start:stop]
        i_sorted = np.repeat(np.arange(start, stop), c)
        offset = np.arange(int(c.sum())) - np.repeat(first[start:stop] - first[start], c)
        i, j = order[i_sorted], order[i_sorted + 1 + offset]
        gap = np.abs(i - j)
        keep = (gap > 1) & (gap < n - 1)
        keep &= (lo[i, other] <= hi[j, other]) & (lo[j, other] <= hi[i, other])
        i, j = i[keep], j[keep]
        cross = _segments_cross(a[i], b[i], a[j], b[j])
        if np.any(cross):
            pairs = np.sort(np.stack([i[cross], j[cross]], axis=-1), axis=-1)
            k = np.lexsort((pairs[:, 1], pairs[:, 0]))[0]
            found = (int(pairs[k, 0]), int(pairs[k, 1]))
            best = found if best is None else min(best, found)
        start = stop
    return best


def _segments_cross(p1: FloatArray, p2: FloatArray, q1: FloatArray, q2: FloatArray) -> np.ndarray:
    """Whether segments ``p1 p2`` and ``q1 q2`` cross properly (touching or collinear is not crossing)."""

    def orient(a, b, c):
        return np.sign(
            (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1])
            - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0])
        )

    d1, d2 = orient(q1, q2, p1), orient(q1, q2, p2)
    d3, d4 = orient(p1, p2, q1), orient(p1, p2, q2)
    return (d1 * d2 < 0) & (d3 * d4 < 0)


def contains_local(fence: Geofence, en_m: ArrayLike) -> np.ndarray:
    """Whether local points ``(..., 2)`` are inside the fence (even-odd rule; a circle's edge is inside)."""
    p = np.asarray(en_m, dtype=float)
    if fence.kind == "radius":
        return np.hypot(p[..., 0], p[..., 1]) <= fence.radius_m
    a = fence.ring_en_m
    b = np.roll(a, -1, axis=0)
    x, y = p[..., 0, None], p[..., 1, None]
    straddles = (a[:, 1] > y) != (b[:, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_cross = a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return (np.count_nonzero(straddles & (x < x_cross), axis=-1) % 2) == 1


def contains(fence: Geofence, lat_deg: ArrayLike, lon_deg: ArrayLike) -> np.ndarray:
    """Whether points (degrees) are inside the fence."""
    return contains_local(fence, fence.to_local(lat_deg, lon_deg))


def _nearest_on_boundary(fence: Geofence, p: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The nearest boundary point to ``p`` and a unit vector pointing into the fence from there.

    On an edge that is the edge's inward normal; at a vertex, the sum of the two edges' inward normals
    (along the bisector of the interior angle, which points inside for convex and reflex vertices alike).
    """
    if fence.kind == "radius":
        r = math.hypot(p[0], p[1])
        u = p / r if r > 0 else np.array([1.0, 0.0])
        return fence.radius_m * u, -u
    a = fence.ring_en_m
    d = np.roll(a, -1, axis=0) - a
    length = np.hypot(d[:, 0], d[:, 1])
    normals = np.stack([-d[:, 1], d[:, 0]], axis=-1) / length[:, None]  # left of a CCW edge: inward
    t = np.clip(np.einsum("ij,ij->i", p - a, d) / length**2, 0.0, 1.0)
    q = a + t[:, None] * d
    k = int(np.argmin(np.hypot(*(q - p).T)))
    inward = normals[k]
    if t[k] <= 0.0:
        inward = normals[k] + normals[k - 1]
    elif t[k] >= 1.0:
        inward = normals[k] + normals[(k + 1) % a.shape[0]]
    norm = math.hypot(*inward)
    return q[k], (inward / norm if norm > 1e-12 else normals[k])


def _clip_into(fence: Geofence, p: FloatArray, margin_m: float) -> FloatArray | None:
    """A point inside the fence near ``p``: ``margin_m`` inside if the fence allows, else just inside.

    None if no inside point was found along the inward direction (the caller refuses the site).
    """
    if fence.kind == "radius":
        r = math.hypot(p[0], p[1])
        keep = max(fence.radius_m - margin_m, 0.0)
        return p.copy() if r <= keep else (p * (keep / r) if r > 0 else p.copy())
    q, inward = _nearest_on_boundary(fence, p)
    best = None
    for step in max(margin_m, 1e-3) * 2.0 ** np.arange(-30.0, 5.0):  # a hair inside, out to 16 margins
        candidate = q + step * inward
        if not contains_local(fence, candidate):
            continue
        if _boundary_distance(fence, candidate) >= margin_m * 0.999:
            return candidate  # the nearest one that keeps the margin
        best = candidate  # inside, short of the margin: the deepest so far
    return best


def _boundary_distance(fence: Geofence, p: FloatArray) -> float:
    q, _ = _nearest_on_boundary(fence, p)
    return float(math.hypot(*(p - q)))


# -- commanded sites -----------------------------------------------------------------------------------------


SiteStatus = Literal["inside", "clipped", "refused"]


@dataclass(frozen=True, slots=True, kw_only=True)
class CheckedSite:
    """A site checked before it is commanded.

    Attributes
    ----------
    status : str
        ``inside`` (as asked), ``clipped`` (moved inside the fence or within the leg limit) or ``refused``.
    message : str
        The reason, for the status line and the journal.
    lat_deg, lon_deg : float
        The site to command, degrees (NaN when refused).
    requested_lat_deg, requested_lon_deg : float
        The site asked for.
    moved_m : float
        How far the site was moved, metres (0 when inside; NaN when refused).
    leg_m : float
        Distance from the vehicle to the site to command, metres (NaN when refused).
    """

    status: SiteStatus
    message: str
    lat_deg: float
    lon_deg: float
    requested_lat_deg: float
    requested_lon_deg: float
    moved_m: float
    leg_m: float

    @property
    def ok(self) -> bool:
        return self.status != "refused"

    def to_record(self) -> dict:
        def num(x: float) -> float | None:
            return x if math.isfinite(x) else None

        return {
            "status": self.status,
            "message": self.message,
            "lat_deg": num(self.lat_deg),
            "lon_deg": num(self.lon_deg),
            "requested_lat_deg": self.requested_lat_deg,
            "requested_lon_deg": self.requested_lon_deg,
            "moved_m": num(self.moved_m),
            "leg_m": num(self.leg_m),
        }


def check_site(
    fence: Geofence,
    vehicle_lat_deg: float,
    vehicle_lon_deg: float,
    site_lat_deg: float,
    site_lon_deg: float,
    *,
    max_leg_m: float = math.inf,
    policy: Literal["clip", "refuse"] = "clip",
    margin_m: float = 1.0,
) -> CheckedSite:
    """Check (and with ``policy="clip"`` repair) a site before it is sent to the vehicle.

    A site outside the fence is moved to the nearest point ``margin_m`` inside it (the margin keeps the
    MAVLink rounding of 1e-7 degrees, about 1 cm, and the boat's waypoint radius on the right side); a leg
    longer than ``max_leg_m`` is shortened along the line from the vehicle. Both rules are verified on the
    final site; if clipping cannot meet both, or the policy is ``refuse``, the site is refused.
    """
    if policy not in ("clip", "refuse"):
        raise ConfigError(f"geofence policy must be 'clip' or 'refuse', got {policy!r}")
    if not (max_leg_m > 0.0):
        raise ConfigError(f"maximum leg must be a positive number of metres, got {max_leg_m}")
    if not (math.isfinite(margin_m) and margin_m >= 0.0):
        raise ConfigError(f"geofence margin must be 0 or more metres, got {margin_m}")
    values = (vehicle_lat_deg, vehicle_lon_deg, site_lat_deg, site_lon_deg)
    if not all(math.isfinite(v) for v in values):
        return _refused(site_lat_deg, site_lon_deg, "site or vehicle position is not a number")
    vehicle = fence.to_local(vehicle_lat_deg, vehicle_lon_deg)
    asked = fence.to_local(site_lat_deg, site_lon_deg)
    site = asked.copy()
    inside = bool(contains_local(fence, site))
    leg = float(math.hypot(*(site - vehicle)))
    long_leg = leg > max_leg_m
    if inside and not long_leg:
        return CheckedSite(
            status="inside",
            message=f"site inside the geofence, leg {leg:.0f} m",
            lat_deg=float(site_lat_deg),
            lon_deg=float(site_lon_deg),
            requested_lat_deg=float(site_lat_deg),
            requested_lon_deg=float(site_lon_deg),
            moved_m=0.0,
            leg_m=leg,
        )
    reasons = []
    if not inside:
        reasons.append(f"{_boundary_distance(fence, site):.0f} m outside the geofence ({fence.source})")
    if long_leg:
        reasons.append(f"leg {leg:.0f} m longer than the {max_leg_m:g} m allowed")
    why = "; ".join(reasons)
    if policy == "refuse":
        return _refused(site_lat_deg, site_lon_deg, f"site refused: {why}")
    for _ in range(4):  # alternate the two repairs; each keeps what the other made true, but check
        if not contains_local(fence, site):
            clipped = _clip_into(fence, site, margin_m)
            if clipped is None:
                break
            site = clipped
        d = site - vehicle
        leg = float(math.hypot(*d))
        if leg > max_leg_m:
            site = vehicle + d * (max_leg_m * (1.0 - 1e-9) / leg)
        if contains_local(fence, site) and math.hypot(*(site - vehicle)) <= max_leg_m:
            break
    lat, lon = fence.to_lat_lon(site)
    final = fence.to_local(lat, lon)  # verify what will be commanded, after the round trip to degrees
    final_leg = float(math.hypot(*(final - vehicle)))
    if not (bool(contains_local(fence, final)) and final_leg <= max_leg_m * (1.0 + 1e-9)):
        return _refused(site_lat_deg, site_lon_deg, f"site refused: {why}; no clipped site meets both rules")
    moved = float(math.hypot(*(final - asked)))
    return CheckedSite(
        status="clipped",
        message=f"site clipped by {moved:.0f} m: {why}",
        lat_deg=lat,
        lon_deg=lon,
        requested_lat_deg=float(site_lat_deg),
        requested_lon_deg=float(site_lon_deg),
        moved_m=moved,
        leg_m=final_leg,
    )


def _refused(lat: float, lon: float, message: str) -> CheckedSite:
    return CheckedSite(
        status="refused",
        message=message,
        lat_deg=math.nan,
        lon_deg=math.nan,
        requested_lat_deg=float(lat),
        requested_lon_deg=float(lon),
        moved_m=math.nan,
        leg_m=math.nan,
    )


# -- the link watchdog ---------------------------------------------------------------------------------------

SOURCES: tuple[str, ...] = ("position", "ranges", "vehicle")
"""The streams the watchdog watches."""


@dataclass(frozen=True, slots=True, kw_only=True)
class WatchdogConfig:
    """Timeouts of the three streams, seconds (of the monotonic clock the loop uses)."""

    position_timeout_s: float = 5.0
    ranges_timeout_s: float = 30.0
    vehicle_timeout_s: float = 3.0

    def __post_init__(self) -> None:
        for source in SOURCES:
            value = self.timeout_s(source)
            if not (math.isfinite(value) and value > 0.0):
                raise ConfigError(f"{source} timeout must be a positive number of seconds, got {value}")

    def timeout_s(self, source: str) -> float:
        return float(getattr(self, f"{source}_timeout_s"))


@dataclass(frozen=True, slots=True, kw_only=True)
class WatchdogState:
    """When each stream was last heard (seconds) and whether the loop is holding for it."""

    last_heard_s: tuple[float, float, float]
    holding: bool = False
    vehicle_was_quiet: bool = False


Action = Literal["continue", "hold", "wait", "resume"]


@dataclass(frozen=True, slots=True, kw_only=True)
class WatchdogVerdict:
    """What the loop should do now.

    Attributes
    ----------
    action : str
        ``continue`` (all fresh), ``hold`` (command HOLD now), ``wait`` (holding; nothing to send) or
        ``resume`` (all fresh again after holding: plan and command again).
    message : str
        Which streams are quiet and for how long, or that they are back.
    quiet : tuple of str
        The streams past their timeout.
    state : WatchdogState
        The state to pass to the next call.
    """

    action: Action
    message: str
    quiet: tuple[str, ...]
    state: WatchdogState

    def to_record(self) -> dict:
        return {"action": self.action, "message": self.message, "quiet": list(self.quiet)}


def watchdog_start(t_s: float) -> WatchdogState:
    """A watchdog whose streams count as heard at ``t_s`` (the start gives each its timeout of grace)."""
    return WatchdogState(last_heard_s=(float(t_s),) * len(SOURCES))


def watchdog_heard(state: WatchdogState, source: str, t_s: float) -> WatchdogState:
    """Note that ``source`` (position, ranges or vehicle) was heard at ``t_s``."""
    if source not in SOURCES:
        raise ConfigError(f"watchdog source must be one of {', '.join(SOURCES)}, got {source!r}")
    last = list(state.last_heard_s)
    i = SOURCES.index(source)
    last[i] = max(last[i], float(t_s))
    return replace(state, last_heard_s=tuple(last))


def watchdog_check(state: WatchdogState, t_s: float, config: WatchdogConfig) -> WatchdogVerdict:
    """The verdict at ``t_s``: HOLD when a stream is quiet past its timeout (see the module docstring)."""
    ages = [t_s - last for last in state.last_heard_s]
    quiet = tuple(s for s, age in zip(SOURCES, ages, strict=True) if age > config.timeout_s(s))
    vehicle_quiet = "vehicle" in quiet
    if quiet:
        parts = [
            f"no {s} for {ages[SOURCES.index(s)]:.1f} s (timeout {config.timeout_s(s):g} s)" for s in quiet
        ]
        message = "; ".join(parts) + ": HOLD"
        if not state.holding:
            action: Action = "hold"
        elif state.vehicle_was_quiet and not vehicle_quiet:
            action = "hold"  # the link is back: the first HOLD may never have arrived
            message += " (vehicle link back: HOLD again)"
        else:
            action = "wait"
        new = replace(state, holding=True, vehicle_was_quiet=vehicle_quiet)
        return WatchdogVerdict(action=action, message=message, quiet=quiet, state=new)
    if state.holding:
        new = replace(state, holding=False, vehicle_was_quiet=False)
        return WatchdogVerdict(
            action="resume", message="position, ranges and vehicle link back", quiet=(), state=new
        )
    return WatchdogVerdict(action="continue", message="links fresh", quiet=(), state=state)
