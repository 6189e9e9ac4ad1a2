import dataclasses
import json
from pathlib import Path

import numpy as np
import pymap3d
import pytest
from scipy import stats

from oceanloc.config.survey import PlannerSettings
from oceanloc.errors import DataError
from oceanloc.estimation.range_logs import localize_beacons
from oceanloc.field.survey.estimates import RANGE_STATUS, next_waypoint, survey_estimates, vehicle_yaw
from oceanloc.field.survey.export import export_csv, export_geojson
from oceanloc.field.survey.journal import Journal, JournalRecords, append_gps_log, append_range_log
from oceanloc.field.survey.settings import JournalSettings
from oceanloc.io.geojson import ring_signed_area
from oceanloc.io.nmea import read_nmea
from oceanloc.io.usbl import align_ranges, read_usbl
from oceanloc.planning.measurement_sites import GreedyPlanner, LookaheadPlanner, PlanningState
from oceanloc.sim.logs import PierLogSettings, simulate_pier_logs

SETTINGS = JournalSettings(planner=PlannerSettings(kind="greedy", max_distance_m=4.0), beacons=(1, 2))


@pytest.fixture(scope="module")
def survey(tmp_path_factory) -> tuple[Path, JournalRecords]:
    """A journal holding 10 min of simulated pier logs (both beacons estimated)."""
    folder = tmp_path_factory.mktemp("pier")
    logs = simulate_pier_logs(folder, PierLogSettings(duration_s=600.0), np.random.default_rng(3))
    with Journal.start(folder / "survey.db", SETTINGS.to_meta()) as j:
        append_gps_log(j, read_nmea(logs.nmea_path), logs.nmea_path)
        append_range_log(j, read_usbl(logs.ranges_path, beacons=(1, 2)), logs.ranges_path)
        return folder, j.records()


def test_estimates_are_localize_beacons_on_the_logs_to_the_bit(survey):
    folder, records = survey
    est = survey_estimates(records, SETTINGS)
    aligned = align_ranges(read_nmea(folder / "gps.nmea"), read_usbl(folder / "ranges.csv", beacons=(1, 2)))
    direct = localize_beacons(aligned, sigma_range_m=SETTINGS.sigma_range_m)
    np.testing.assert_array_equal(est.beacons, [1, 2])
    np.testing.assert_array_equal(est.positions_enu_m, [d.position_enu_m for d in direct])
    np.testing.assert_array_equal(est.covariances_m2, [d.covariance_m2 for d in direct])
    np.testing.assert_array_equal(est.ranges_excluded, [d.n_excluded for d in direct])
    counts = np.bincount(est.range_status, minlength=len(RANGE_STATUS))
    assert counts[0] == est.ranges_used.sum() and counts[1] == est.ranges_excluded.sum()
    assert counts.sum() == records.n_ranges
    # 95 % ellipse: a b = chi2_2(0.95) sqrt(det P_EN).
    det = np.linalg.det(est.covariances_m2[:, :2, :2])
    np.testing.assert_allclose(
        est.ellipse_area_m2, np.pi * stats.chi2.ppf(0.95, 2) * np.sqrt(det), rtol=1e-12
    )


def test_greedy_next_is_within_reach_and_is_the_planner_called_directly(survey):
    _, records = survey
    est = survey_estimates(records, SETTINGS)
    w = next_waypoint(records, SETTINGS, estimates=est)
    last = est.track_enu_m[-1]
    assert w.heading_source == "unused"
    assert np.hypot(*(w.next_enu_m - last)[:2]) <= SETTINGS.planner.max_distance_m + 1e-9
    assert w.distance_m == pytest.approx(4.0, abs=1e-6)  # the D-optimal site lies on the reach boundary
    state = PlanningState(
        pos_enu_m=last[None],
        yaw_rad=np.zeros(1),
        estimates_m=est.positions_enu_m[None],
        covariances_m2=est.covariances_m2[None],
    )
    plan = GreedyPlanner(max_distance_m=4.0, sigma_range_m=SETTINGS.sigma_range_m).plan(state)
    np.testing.assert_array_equal(w.next_enu_m, plan.next_pos_enu_m[0])
    lat, lon, h = pymap3d.enu2geodetic(*w.next_enu_m, est.origin.lat_deg, est.origin.lon_deg, est.origin.h_m)
    np.testing.assert_allclose(w.next_geodetic, [lat, lon, h], rtol=0, atol=1e-9)


def test_lookahead_heading_from_hdt_then_fixes_then_start(survey):
    _, records = survey
    s = dataclasses.replace(
        SETTINGS, planner=PlannerSettings(kind="lookahead", horizon=2), speed_mps=1.0, period_s=3.0
    )
    yaw, source = vehicle_yaw(records, s)
    assert source == "HDT" and yaw == pytest.approx(np.deg2rad(90.0 - records.heading_deg[-1]))
    w = next_waypoint(records, s)
    assert w.waypoints_enu_m.shape == (2, 3) and w.distance_m == pytest.approx(3.0)
    direct = LookaheadPlanner(
        horizon=2, max_yaw_rate_rad_s=s.max_yaw_rate_rad_s, speed_mps=1.0, period_s=3.0, sigma_range_m=1.006
    )
    est = survey_estimates(records, s)
    state = PlanningState(
        pos_enu_m=est.track_enu_m[-1:],
        yaw_rad=np.array([yaw]),
        estimates_m=est.positions_enu_m[None],
        covariances_m2=est.covariances_m2[None],
    )
    np.testing.assert_array_equal(w.waypoints_enu_m, direct.plan(state).waypoints_enu_m[0])
    no_hdt = dataclasses.replace(records, heading_t_unix_s=np.zeros(0), heading_deg=np.zeros(0))
    yaw, source = vehicle_yaw(no_hdt, s)
    step = np.diff(est.track_enu_m[-2:], axis=0)[0]
    assert source == "fixes" and yaw == pytest.approx(np.arctan2(step[1], step[0]))
    one_fix = dataclasses.replace(
        no_hdt, **{f: getattr(no_hdt, f)[:1] for f in ("fix_t_unix_s", "lat_deg", "lon_deg", "h_m")}
    )
    assert vehicle_yaw(one_fix, dataclasses.replace(s, heading_deg=0.0)) == (
        pytest.approx(np.pi / 2),
        "start",
    )
    with pytest.raises(DataError, match="no vehicle heading"):
        vehicle_yaw(one_fix, s)


def test_next_before_enough_ranges_says_what_is_missing(survey):
    _, records = survey
    few = dataclasses.replace(
        records, **{f: getattr(records, f)[:5] for f in ("range_t_unix_s", "beacon", "range_m")}
    )
    est = survey_estimates(few, SETTINGS)
    n1, n2 = (few.beacon == 1).sum(), (few.beacon == 2).sum()
    assert est.n_beacons == 0 and est.waiting_ranges.tolist() == [n1, n2] and n1 + n2 == 5
    assert [RANGE_STATUS[k] for k in est.range_status] == ["waiting"] * 5
    with pytest.raises(DataError, match=rf"no beacon estimated yet .* so far 1: {n1}, 2: {n2}"):
        next_waypoint(few, SETTINGS)


def test_geojson_points_ellipses_and_track(survey, tmp_path: Path):
    _, records = survey
    est = survey_estimates(records, SETTINGS)
    data = json.loads(export_geojson(tmp_path / "s.geojson", records, est).read_text())
    assert data["type"] == "FeatureCollection"
    kinds = [f["properties"]["kind"] for f in data["features"]]
    assert kinds == ["beacon", "ellipse", "beacon", "ellipse", "track"]
    o = est.origin
    for i in range(2):
        point, ellipse = data["features"][2 * i], data["features"][2 * i + 1]
        lat, lon, h = pymap3d.enu2geodetic(*est.positions_enu_m[i], o.lat_deg, o.lon_deg, o.h_m)
        np.testing.assert_allclose(point["geometry"]["coordinates"], [lon, lat, h], rtol=0, atol=1e-10)
        assert point["properties"]["sigma_e_m"] == est.sigma_enu_m[i, 0]
        ring = np.array(ellipse["geometry"]["coordinates"][0])
        assert ring.shape == (129, 2) and np.array_equal(ring[0], ring[-1])  # closed, lon/lat pairs
        assert np.all(np.abs(ring[:, 0] - lon) < 1e-4) and np.all(np.abs(ring[:, 1] - lat) < 1e-4)
        e, n, _ = pymap3d.geodetic2enu(
            ring[:, 1], ring[:, 0], est.positions_enu_m[i, 2] + o.h_m, o.lat_deg, o.lon_deg, o.h_m
        )
        area = ring_signed_area(np.stack([e, n], axis=1))
        expected = np.pi * stats.chi2.ppf(0.95, 2) * np.sqrt(np.linalg.det(est.covariances_m2[i, :2, :2]))
        assert area > 0  # counter-clockwise exterior ring
        assert area == pytest.approx(expected, rel=2e-3)  # 128-gon inscribed: -0.04 %
        assert ellipse["properties"]["area_m2"] == pytest.approx(expected, rel=1e-12)
    track = np.array(data["features"][-1]["geometry"]["coordinates"])
    assert track.shape == (records.n_fixes, 3)
    np.testing.assert_array_equal(track[:, :2], np.stack([records.lon_deg, records.lat_deg], axis=1))


def test_csv_export_tables(survey, tmp_path: Path):
    _, records = survey
    est = survey_estimates(records, SETTINGS)
    paths = export_csv(tmp_path / "csv", records, est)
    assert [p.name for p in paths] == ["fixes.csv", "headings.csv", "ranges.csv", "estimates.csv"]
    fixes = np.genfromtxt(paths[0], delimiter=",", names=True, dtype=None, encoding="utf-8")
    assert fixes.size == records.n_fixes
    np.testing.assert_array_equal(fixes["lat_deg"], records.lat_deg)
    ranges = paths[2].read_text().splitlines()
    assert ranges[0] == "t_unix_s,utc,beacon,range_m,status" and len(ranges) == records.n_ranges + 1
    statuses = [line.rsplit(",", 1)[1] for line in ranges[1:]]
    assert statuses.count("outlier") == est.ranges_excluded.sum()
    table = np.genfromtxt(paths[3], delimiter=",", names=True)
    np.testing.assert_array_equal(table["e_m"], est.positions_enu_m[:, 0])
    np.testing.assert_array_equal(table["ellipse95_semi_major_m"], est.ellipses.semi_major_m)


def test_estimates_say_whether_each_ellipse_can_be_trusted(survey):
    # 10 min of pier logs: hundreds of ranges per beacon from a wide track, so the range model is linear
    # over each 95 % ellipsoid (statistic below log 2); four ranges from one short leg are not.
    from oceanloc.estimation.consistency import range_linearization_check

    _, records = survey
    est = survey_estimates(records, SETTINGS)
    assert est.trusted.tolist() == [True, True]
    assert np.all(est.linearity < np.log(2.0))
    rec = est.to_record()["beacons"][0]
    assert rec["ellipse_trusted"] is True and rec["linearity"] == pytest.approx(float(est.linearity[0]))
    assert rec["trust_message"] == "ellipse trusted: the range model is linear over it"
    # the same check straight from its function on two close sites: not trusted
    p = np.array([[10.0, 0.0, -8.0]])
    sensors = np.array([[[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [1.0, 0.0, 0.0], [1.5, 0.0, 0.0]]])
    ranges = np.linalg.norm(sensors - p[:, None], axis=-1)
    h = (p[:, None] - sensors)[0] / ranges[0][:, None]
    prior = np.diag([100.0, 100.0, 10.0]) ** 2
    cov = np.linalg.inv(h.T @ h / 1.0 + np.linalg.inv(prior))
    check = range_linearization_check(p, cov[None], sensors, ranges, np.ones((1, 4), bool), 1.0, p, prior)
    assert not check.trusted[0]
