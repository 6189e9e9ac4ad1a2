import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from matplotlib.path import Path as MplPath

from oceanloc.errors import ConfigError
from oceanloc.models.obstacles import ObstacleMap, OccupancyGrid

BOUNDS = (-5000.0, 5000.0, -5000.0, 5000.0)
RECTS = np.array([[-4000.0, -2000.0, -4000.0, -3000.0], [-500.0, 1500.0, -500.0, 1500.0]])
TRIANGLE = np.array([[2000.0, 2000.0], [4000.0, 2500.0], [2500.0, 4000.0]])


def test_rectangles_are_half_open_like_the_thesis_cells():
    m = ObstacleMap(bounds_m=BOUNDS, rectangles_m=RECTS)
    pts = np.array([[-500.0, -500.0], [1500.0, 0.0], [0.0, 1500.0], [1499.9, 1499.9], [-500.1, 0.0]])
    assert m.is_free(pts).tolist() == [False, True, True, False, True]
    assert m.is_free([[5000.0, 5000.0], [5000.1, 0.0]]).tolist() == [True, False]  # closed map bounds


def test_inflation_is_the_distance_to_the_obstacle():
    m = ObstacleMap(bounds_m=BOUNDS, rectangles_m=RECTS[1:], inflation_m=100.0)
    # Near a corner the blocked region is rounded: distance to (1500, 1500).
    assert not m.is_free([1570.0, 1570.0])  # 99 m away
    assert m.is_free([1572.0, 1572.0])  # 101.8 m away
    assert not m.is_free([1599.0, 0.0]) and m.is_free([1601.0, 0.0])


def test_scalar_path_equals_array_path():
    for inflation in (0.0, 75.0):
        m = ObstacleMap(bounds_m=BOUNDS, rectangles_m=RECTS, polygons_m=(TRIANGLE,), inflation_m=inflation)
        rng = np.random.default_rng(0)
        pts = rng.uniform(-5100, 5100, size=(300, 2))
        vec = m.is_free(pts)
        scal = [m.is_free_xy(float(x), float(y)) for x, y in pts]
        assert vec.tolist() == scal


def test_polygon_inside_matches_matplotlib():
    m = ObstacleMap(bounds_m=BOUNDS, polygons_m=(TRIANGLE,))
    rng = np.random.default_rng(1)
    pts = rng.uniform(1500, 4500, size=(2000, 2))
    inside = MplPath(TRIANGLE).contains_points(pts)
    assert np.array_equal(~m.is_free(pts), inside)


def _sampled_segment_free(m, a, b, n=4001):
    s = np.linspace(0.0, 1.0, n)[:, None]
    return bool(np.all(m.is_free(a + s * (b - a))))


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-5000, 5000), min_size=4, max_size=4), st.sampled_from([0.0, 60.0]))
@example([0.0, 1500.0, 2000.0, 2000.0], 0.0)  # starts on a rectangle edge
def test_segment_test_agrees_with_dense_sampling(coords, inflation):
    m = ObstacleMap(bounds_m=BOUNDS, rectangles_m=RECTS, polygons_m=(TRIANGLE,), inflation_m=inflation)
    a, b = np.array(coords[:2]), np.array(coords[2:])
    exact = bool(m.segment_free(a, b))
    sampled = _sampled_segment_free(m, a, b)
    if exact:
        assert sampled  # an exact "free" can never be contradicted by a sample
    elif sampled:
        # Sampling every ~3.5 m can only miss a clip of the obstacle shallower than that, or a graze of an
        # edge (segments treat obstacles as closed sets, points as half-open): a 1 um margin must touch.
        s = np.linspace(0.0, 1.0, 200_001)[:, None]
        closed = ObstacleMap(
            bounds_m=BOUNDS, rectangles_m=RECTS, polygons_m=(TRIANGLE,), inflation_m=inflation + 1e-6
        )
        assert not np.all(closed.is_free(a + s * (b - a)))


def test_segment_batch_shapes():
    m = ObstacleMap(bounds_m=BOUNDS, rectangles_m=RECTS)
    a = np.array([[-4000.0, 4000.0], [-4000.0, 4000.0]])
    b = np.array([[3000.0, -3000.0], [-4000.0, -2000.0]])
    assert m.segment_free(a, b).tolist() == [False, True]


def test_occupancy_grid_and_its_inflation():
    occ = np.zeros((10, 10), dtype=bool)
    occ[5, 5] = True
    grid = OccupancyGrid(x0_m=0.0, y0_m=0.0, cell_m=10.0, occupied=occ)
    m = ObstacleMap(bounds_m=(0.0, 100.0, 0.0, 100.0), grid=grid)
    assert not m.is_free([55.0, 55.0]) and m.is_free([65.0, 55.0])
    grown = m.with_inflation(10.0)
    assert not grown.is_free([65.0, 55.0]) and grown.is_free([75.0, 55.0])
    assert m.grid is grid  # the map keeps the raw grid; inflation is applied on top
    assert not m.segment_free([0.0, 55.0], [99.0, 55.0])


def test_rasterize_marks_obstacle_cells():
    m = ObstacleMap(bounds_m=BOUNDS, rectangles_m=RECTS)
    g = m.rasterize(500.0)
    assert g.occupied.shape == (20, 20)
    assert g.occupied.sum() == 4 * 2 + 4 * 4


def test_bad_maps_are_rejected():
    with pytest.raises(ConfigError, match="bounds"):
        ObstacleMap(bounds_m=(1.0, 0.0, 0.0, 1.0))
    with pytest.raises(ConfigError, match="rectangle"):
        ObstacleMap(bounds_m=BOUNDS, rectangles_m=[[1.0, 0.0, 0.0, 1.0]])
    with pytest.raises(ConfigError, match="polygon"):
        ObstacleMap(bounds_m=BOUNDS, polygons_m=([[0.0, 0.0], [1.0, 1.0]],))
