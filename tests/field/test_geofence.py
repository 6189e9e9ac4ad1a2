"""Safety checks: geofence (circle, GeoJSON polygon), leg limit, link watchdog; properties with hypothesis."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from oceanloc.errors import ConfigError
from oceanloc.field.geofence import (
    WatchdogConfig,
    check_site,
    contains,
    contains_local,
    fence_from_radius,
    fence_from_ring,
    read_geofence,
    watchdog_check,
    watchdog_heard,
    watchdog_start,
)
from oceanloc.geo.projection import LocalProjection

LAT0, LON0 = 32.70, -117.25
PROJ = LocalProjection(lat0_deg=LAT0, lon0_deg=LON0)


def at(north_m: float, east_m: float) -> tuple[float, float]:
    """The point ``north_m``, ``east_m`` from (LAT0, LON0) on the WGS84 surface: (lat, lon) degrees."""
    lon, lat = PROJ.to_lonlat(east_m, north_m)
    return float(lat), float(lon)


def north_east(lat: float, lon: float) -> tuple[float, float]:
    e, n = PROJ.to_local(lon, lat)
    return float(n), float(e)


def ring_lon_lat(points_ne):
    ring = [[at(n, e)[1], at(n, e)[0]] for n, e in points_ne]
    return [*ring, ring[0]]


# an L-shaped (non-convex) fence: 400 m x 400 m with the north-east 200 m x 200 m quarter cut away
L_SHAPE = [(0, 0), (0, 400), (200, 400), (200, 200), (400, 200), (400, 0)]


def write(tmp_path, doc, name="fence.geojson"):
    p = tmp_path / name
    p.write_text(doc if isinstance(doc, str) else json.dumps(doc))
    return p


def polygon_doc(ring):
    return {
        "type": "FeatureCollection",
        "features": [
            {"type": "Feature", "properties": {}, "geometry": {"type": "Polygon", "coordinates": [ring]}}
        ],
    }


# -- fences --------------------------------------------------------------------------------------------------


def test_radius_fence_contains_by_distance():
    fence = fence_from_radius(LAT0, LON0, 100.0)
    assert contains(fence, *at(99.0, 0.0))
    assert not contains(fence, *at(0.0, 101.0))
    assert fence.to_record()["kind"] == "radius"


def test_geojson_polygon_is_read_and_oriented_counter_clockwise(tmp_path):
    clockwise = ring_lon_lat(L_SHAPE)  # north-then-east order runs clockwise
    fence = read_geofence(write(tmp_path, polygon_doc(clockwise)))
    assert fence.kind == "polygon"
    assert fence.ring_en_m.shape == (6, 2)
    x, y = fence.ring_en_m.T
    assert 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) == pytest.approx(120_000.0, rel=1e-3)  # m^2
    assert contains(fence, *at(100.0, 100.0))
    assert contains(fence, *at(300.0, 100.0))
    assert not contains(fence, *at(300.0, 300.0))  # the cut-away corner
    assert not contains(fence, *at(-10.0, 100.0))


@pytest.mark.parametrize(
    ("doc", "reason"),
    [
        ("{ not json", "not JSON \\(line 1, column 3"),
        ({"type": "Point", "coordinates": [0, 0]}, "no Polygon in the GeoJSON \\(found Point\\)$"),
        ({"type": "FeatureCollection", "features": []}, "no Polygon in the GeoJSON$"),
        (
            {"type": "MultiPolygon", "coordinates": [[ring_lon_lat(L_SHAPE)], [ring_lon_lat(L_SHAPE)]]},
            "2 polygons in the GeoJSON; the geofence must be one",
        ),
        (
            {
                "type": "Polygon",
                "coordinates": [ring_lon_lat(L_SHAPE), ring_lon_lat([(1, 1), (1, 2), (2, 2)])],
            },
            "1 hole\\(s\\); holes are not supported",
        ),
        ({"type": "Polygon", "coordinates": [ring_lon_lat(L_SHAPE)[:-1]]}, "ring is not closed"),
        ({"type": "Polygon", "coordinates": [ring_lon_lat([(0, 0), (0, 10)])]}, "at least 4 positions"),
        (
            {"type": "Polygon", "coordinates": [[[0, 95], [1, 95], [1, 96], [0, 95]]]},
            "within \\[-180, 180\\]",
        ),
        (
            {"type": "Polygon", "coordinates": [ring_lon_lat([(0, 0), (100, 100), (0, 100), (100, 0)])]},
            "crosses itself \\(edges 1 and 3\\)",
        ),
        ({"type": "Polygon", "coordinates": [ring_lon_lat([(0, 0), (0, 50), (0, 100)])]}, "encloses no area"),
        ({"type": "Polygon", "coordinates": [[["a", "b"], [1, 2]]]}, "lists of numbers"),
    ],
)
def test_bad_geojson_fences_are_refused_naming_the_file_and_the_fault(tmp_path, doc, reason):
    p = write(tmp_path, doc)
    with pytest.raises(ConfigError, match=reason) as info:
        read_geofence(p)
    assert str(info.value).startswith(f"{p}: ")


def test_missing_geofence_file_is_a_clear_error(tmp_path):
    with pytest.raises(ConfigError, match="cannot read the geofence \\(No such file or directory\\)"):
        read_geofence(tmp_path / "nope.geojson")


def test_bad_radius_is_refused():
    with pytest.raises(ConfigError, match="radius must be a positive number of metres, got -5"):
        fence_from_radius(LAT0, LON0, -5.0)


# -- commanded sites -----------------------------------------------------------------------------------------


def test_a_site_inside_is_passed_unchanged():
    fence = fence_from_radius(LAT0, LON0, 500.0)
    r = check_site(fence, LAT0, LON0, *at(100.0, 100.0))
    assert r.status == "inside"
    assert (r.lat_deg, r.lon_deg) == at(100.0, 100.0)
    assert r.leg_m == pytest.approx(math.hypot(100.0, 100.0), abs=1e-6)


def test_a_site_outside_a_circle_is_clipped_to_the_margin_inside():
    fence = fence_from_radius(LAT0, LON0, 500.0)
    r = check_site(fence, LAT0, LON0, *at(600.0, 0.0), margin_m=5.0)
    assert r.status == "clipped"
    assert r.message.startswith("site clipped by 105 m: 100 m outside the geofence (radius 500 m about")
    assert north_east(r.lat_deg, r.lon_deg) == pytest.approx((495.0, 0.0), abs=0.01)
    assert r.to_record()["status"] == "clipped"


def test_refuse_policy_refuses_with_the_reason():
    fence = fence_from_radius(LAT0, LON0, 500.0)
    r = check_site(fence, LAT0, LON0, *at(0.0, -700.0), policy="refuse")
    assert r.status == "refused"
    assert r.message.startswith("site refused: 200 m outside the geofence")
    assert math.isnan(r.lat_deg)
    assert r.to_record()["lat_deg"] is None


def test_a_long_leg_is_shortened_along_its_line():
    fence = fence_from_radius(LAT0, LON0, 5_000.0)
    r = check_site(fence, LAT0, LON0, *at(0.0, 1_000.0), max_leg_m=300.0)
    assert r.status == "clipped"
    assert r.leg_m == pytest.approx(300.0, abs=0.01)
    assert north_east(r.lat_deg, r.lon_deg) == pytest.approx((0.0, 300.0), abs=0.01)
    assert "leg 1000 m longer than the 300 m allowed" in r.message


def test_a_site_in_the_cut_away_corner_of_a_non_convex_fence_is_clipped_inside():
    fence = fence_from_ring(ring_lon_lat(L_SHAPE), source="L")
    r = check_site(fence, *at(100.0, 100.0), *at(260.0, 240.0), margin_m=2.0)
    assert r.status == "clipped"
    assert contains(fence, r.lat_deg, r.lon_deg)
    # nearest boundary: the edge north = 200 m... or east = 200 m; 40 m away either way, then 2 m in
    assert r.moved_m == pytest.approx(42.0, abs=0.5)


# hypothesis: random star-shaped (often non-convex) polygons and circles; random sites and vehicle positions
@st.composite
def fences(draw):
    if draw(st.booleans()):
        return fence_from_radius(LAT0, LON0, draw(st.floats(20.0, 2_000.0)))
    n = draw(st.integers(3, 12))
    angles = np.sort(
        np.array(draw(st.lists(st.floats(0.0, 2 * math.pi), min_size=n, max_size=n, unique=True)))
    )
    gaps = np.diff(np.r_[angles, angles[0] + 2 * math.pi])
    # Star-shaped about the centre only while every angular gap is under pi: a wider gap lets the edge
    # across it pass the centre's far side and cross other edges (a self-crossing ring, rightly refused).
    if np.min(gaps) < 0.05 or np.max(gaps) >= math.pi - 0.05:
        angles = np.linspace(0.0, 2 * math.pi, n, endpoint=False)
    radii = np.array(draw(st.lists(st.floats(50.0, 1_500.0), min_size=n, max_size=n)))
    pts = [(r * math.cos(a), r * math.sin(a)) for a, r in zip(angles, radii, strict=True)]
    return fence_from_ring(ring_lon_lat(pts), source="star")


offsets = st.tuples(st.floats(-3_000.0, 3_000.0), st.floats(-3_000.0, 3_000.0))


@given(
    fence=fences(),
    vehicle=offsets,
    site=offsets,
    max_leg=st.one_of(st.just(math.inf), st.floats(10.0, 2_000.0)),
)
def test_a_commanded_site_is_always_inside_the_fence_and_within_the_leg_limit(fence, vehicle, site, max_leg):
    r = check_site(fence, *at(*vehicle), *at(*site), max_leg_m=max_leg)
    assert r.status in ("inside", "clipped", "refused")
    assert r.message
    if r.ok:
        assert contains(fence, r.lat_deg, r.lon_deg)
        v = fence.to_local(*at(*vehicle))
        s = fence.to_local(r.lat_deg, r.lon_deg)
        assert math.hypot(*(s - v)) <= max_leg * (1 + 1e-6)
    if r.status == "inside":
        assert (r.lat_deg, r.lon_deg) == at(*site)


@given(fence=fences(), site=offsets)
def test_without_a_leg_limit_clipping_never_refuses_and_refuse_never_moves(fence, site):
    clipped = check_site(fence, LAT0, LON0, *at(*site))
    assert clipped.ok  # the nearest boundary point, pulled 1 m inside, always exists for these fences
    refused = check_site(fence, LAT0, LON0, *at(*site), policy="refuse")
    inside = bool(contains(fence, *at(*site)))
    assert refused.status == ("inside" if inside else "refused")


def test_contains_local_is_vectorized():
    fence = fence_from_ring(ring_lon_lat(L_SHAPE))
    pts = fence.to_local(*np.array([at(100, 100), at(300, 300), at(300, 100)]).T)
    assert contains_local(fence, pts).tolist() == [True, False, True]


# -- the link watchdog --------------------------------------------------------------------------------------


def test_watchdog_holds_on_a_quiet_stream_says_which_and_resumes():
    cfg = WatchdogConfig(position_timeout_s=5.0, ranges_timeout_s=30.0, vehicle_timeout_s=3.0)
    s = watchdog_start(0.0)
    for t in (1.0, 2.0, 3.0):
        s = watchdog_heard(s, "position", t)
        s = watchdog_heard(s, "ranges", t)
        s = watchdog_heard(s, "vehicle", t)
    v = watchdog_check(s, 4.0, cfg)
    assert v.action == "continue"
    s = watchdog_heard(watchdog_heard(v.state, "position", 6.0), "ranges", 6.0)  # the vehicle goes quiet at 3
    v = watchdog_check(s, 6.5, cfg)
    assert v.action == "hold"
    assert v.quiet == ("vehicle",)
    assert v.message == "no vehicle for 3.5 s (timeout 3 s): HOLD"
    v = watchdog_check(v.state, 7.0, cfg)
    assert v.action == "wait"
    s = watchdog_heard(v.state, "vehicle", 11.0)  # the link comes back, but the position is now quiet
    v = watchdog_check(s, 11.5, cfg)
    assert v.action == "hold"
    assert v.quiet == ("position",)
    assert v.message.endswith("(vehicle link back: HOLD again)")
    s = watchdog_heard(watchdog_heard(v.state, "position", 12.0), "vehicle", 12.0)
    v = watchdog_check(s, 12.0, cfg)
    assert (v.action, v.message) == ("resume", "position, ranges and vehicle link back")
    assert watchdog_check(v.state, 12.5, cfg).action == "continue"


def test_watchdog_refuses_unknown_streams_and_bad_timeouts():
    with pytest.raises(
        ConfigError, match="watchdog source must be one of position, ranges, vehicle, got 'gps'"
    ):
        watchdog_heard(watchdog_start(0.0), "gps", 1.0)
    with pytest.raises(ConfigError, match="ranges timeout must be a positive number of seconds, got 0"):
        WatchdogConfig(ranges_timeout_s=0.0)


events = st.lists(
    st.tuples(st.sampled_from(["position", "ranges", "vehicle", "check"]), st.floats(0.0, 20.0))
)


@given(events=events)
def test_watchdog_never_continues_while_a_stream_is_past_its_timeout(events):
    cfg = WatchdogConfig(position_timeout_s=2.0, ranges_timeout_s=6.0, vehicle_timeout_s=1.0)
    s = watchdog_start(0.0)
    t = 0.0
    last = {"position": 0.0, "ranges": 0.0, "vehicle": 0.0}
    holding = False
    for kind, dt in events:
        t += dt
        if kind != "check":
            s = watchdog_heard(s, kind, t)
            last[kind] = t
            continue
        v = watchdog_check(s, t, cfg)
        stale = {k for k, heard in last.items() if t - heard > cfg.timeout_s(k)}
        assert set(v.quiet) == stale
        if stale:
            assert v.action in ("hold", "wait")
            assert v.action == "hold" or holding  # the first verdict of a quiet spell is HOLD
        else:
            assert v.action == ("resume" if holding else "continue")
        holding = bool(stale)
        s = v.state
