"""Every public function, called with hostile arrays, raises oceanloc's own error or returns finite results.

A valid call is built for each entry point of ``oceanloc.__all__`` that takes arrays or sizes; hypothesis
then corrupts one argument at a time: a NaN, an infinity, 1e308, 1e-300, an empty array, a wrong shape,
or a huge size. The only outcomes accepted are an :class:`~oceanloc.errors.OceanlocError` (whose message
names the argument where the argument is an array) or a result whose numbers are all finite (HDOP may be
``+inf``, its documented value for a singular geometry). A ``LinAlgError``, ``MemoryError``, ``IndexError``,
a silent NaN, or a hang (hypothesis' deadline) fails the test.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import oceanloc
from oceanloc.errors import OceanlocError
from oceanloc.estimation.gaussian import Gaussian
from tests.estimation.flock_cases import SENSORS, consistent_bearing_problem

CORRUPTIONS = ("nan", "inf", "-inf", "1e308", "-1e308", "1e-300", "empty", "drop-axis", "add-axis", "huge")


def corrupt(value: np.ndarray, how: str, where: float) -> np.ndarray:
    """``value`` with one element (at the fraction ``where`` of its flat length) or its shape spoiled."""
    x = np.array(value, dtype=float)
    if how == "empty":
        return np.zeros((0,) * max(x.ndim, 1))
    if how == "drop-axis":
        return x.reshape(-1)[:-1] if x.ndim <= 1 else x[..., 0]
    if how == "add-axis":
        return x[..., None]
    if how == "huge":
        return np.full(x.shape, 1e300)
    if x.size == 0:
        return x
    flat = x.reshape(-1)
    flat[min(int(where * flat.size), flat.size - 1)] = float(how)
    return flat.reshape(x.shape)


def _numbers(obj: object, seen: int = 0) -> list[np.ndarray]:
    """Every float array or float in a result (dataclass fields, tuples, lists, dicts), recursively."""
    if seen > 6:
        return []
    if isinstance(obj, np.ndarray):
        return [obj] if obj.dtype.kind == "f" else []
    if isinstance(obj, float | np.floating):
        return [np.asarray(obj)]
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return [a for f in dataclasses.fields(obj) for a in _numbers(getattr(obj, f.name), seen + 1)]
    if isinstance(obj, tuple | list):
        return [a for item in obj for a in _numbers(item, seen + 1)]
    if isinstance(obj, dict):
        return [a for item in obj.values() for a in _numbers(item, seen + 1)]
    return []


def _outcome(call: Callable[[], object], *, inf_allowed: bool = False) -> str:
    """``"error"`` for an oceanloc error, ``"finite"`` for a clean result; anything else fails."""
    try:
        with np.errstate(all="ignore"):
            result = call()
    except OceanlocError as exc:
        assert "\n" not in str(exc).strip(), f"error message over several lines: {exc}"
        return "error"
    for a in _numbers(result):
        bad = np.isnan(a) if inf_allowed else ~np.isfinite(a)
        assert not bad.any(), f"non-finite result {a} from {call}"
    return "finite"


def _range_case() -> dict[str, np.ndarray]:
    sensors = np.array([[30.0, 0.0, 0.0], [0.0, 30.0, 0.0], [-30.0, 0.0, 0.0], [0.0, -30.0, 0.0]])
    truth = np.array([2.0, -1.0, -20.0])
    ranges = np.linalg.norm(sensors - truth, axis=1)[None]
    return {
        "sensor_m": sensors,
        "ranges_m": ranges,
        "sigma_m": np.array([0.1]),
        "prior_mean": np.array([[0.0, 0.0, -18.0]]),
        "prior_cov": np.diag([25.0, 25.0, 4.0]),
        "initial": np.array([[1.0, 1.0, -19.0]]),
    }


def _solve_map(a: dict) -> object:
    problem = oceanloc.RangeProblem.build(a["sensor_m"], a["ranges_m"], a["sigma_m"])
    prior = oceanloc.GaussianPrior(mean=a["prior_mean"], cov=a["prior_cov"])
    return oceanloc.solve_map(problem, prior, initial=a["initial"])


MOTION, MODEL, INIT, _TRUTH, Z = consistent_bearing_problem(2, 6, seed=4)


def _run_filter(a: dict) -> object:
    initial = Gaussian(mean=a["mean"], cov=a["cov"])
    return oceanloc.run_filter(
        "ukf", initial, MOTION, MODEL, a["measurements"], a["sensors_m"], record_covariances=True
    )


ARRAY_CASES: dict[str, tuple[Callable[[], dict], Callable[[dict], object]]] = {
    "solve_map": (_range_case, _solve_map),
    "confidence_ellipse": (
        lambda: {"center_m": np.zeros((3, 2)), "cov_m2": np.tile(np.diag([4.0, 1.0]), (3, 1, 1))},
        lambda a: oceanloc.confidence_ellipse(a["center_m"], a["cov_m2"]),
    ),
    "nees": (
        lambda: {"errors_m": np.ones((5, 2, 3)), "information": np.tile(np.eye(3), (5, 2, 1, 1))},
        lambda a: oceanloc.nees(a["errors_m"], a["information"]),
    ),
    "chi_square_check": (
        lambda: {"samples": np.linspace(1.0, 6.0, 10)},
        lambda a: oceanloc.chi_square_check(a["samples"], 3),
    ),
    "rmsee": (lambda: {"errors_m": np.ones((10, 2, 3))}, lambda a: oceanloc.rmsee(a["errors_m"])),
    "pcrlb": (
        lambda: {
            "initial_cov": np.eye(4) * 100.0,
            "transition": np.eye(4) + np.diag([1.0, 1.0], 2),
            "process_noise": np.eye(4) * 0.01,
            "information": np.tile(np.diag([1.0, 1.0, 0.0, 0.0]), (5, 1, 1)),
        },
        lambda a: oceanloc.pcrlb(a["initial_cov"], a["transition"], a["process_noise"], a["information"]),
    ),
    "run_filter": (
        lambda: {
            "mean": INIT.mean.copy(),
            "cov": INIT.cov.copy(),
            "measurements": Z.copy(),
            "sensors_m": np.broadcast_to(SENSORS, (6, 4, 2)).copy(),
        },
        _run_filter,
    ),
    "hdop": (
        lambda: {"nodes_m": SENSORS.copy(), "target_m": np.array([10.0, 5.0]), "sigma": np.array(1.0)},
        lambda a: oceanloc.hdop(a["nodes_m"], a["target_m"], "range", a["sigma"]),
    ),
    "hdop_map": (
        lambda: {
            "fixed_nodes_m": SENSORS[:3].copy(),
            "target_m": np.zeros(2),
            "x_range_m": np.array([-50, 50.0]),
        },
        lambda a: oceanloc.hdop_map(
            a["fixed_nodes_m"],
            a["target_m"],
            "bearing",
            x_range_m=tuple(a["x_range_m"]),
            y_range_m=(-50.0, 50.0),
            resolution_m=10.0,
        ),
    ),
    "estimate_delay": (
        lambda: {"a": np.sin(np.arange(256) * 0.3), "b": np.sin(np.arange(256) * 0.3 + 0.6)},
        lambda a: oceanloc.estimate_delay(a["a"], a["b"], 8000.0, method="xcorr"),
    ),
    "PlanningState": (
        lambda: {
            "pos_enu_m": np.zeros((2, 3)),
            "yaw_rad": np.zeros(2),
            "estimates_m": np.ones((2, 1, 3)),
            "covariances_m2": np.tile(np.eye(3), (2, 1, 1, 1)),
        },
        lambda a: oceanloc.GreedyPlanner(max_distance_m=5.0, sigma_range_m=0.5).plan(
            oceanloc.PlanningState(**a)
        ),
    ),
}


@pytest.mark.parametrize("name", sorted(ARRAY_CASES))
def test_the_valid_call_of_each_case_returns_finite_results(name):
    build, call = ARRAY_CASES[name]
    assert _outcome(lambda: call(build()), inf_allowed=name.startswith("hdop")) == "finite"


@pytest.mark.parametrize("name", sorted(ARRAY_CASES))
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_hostile_arrays_get_an_oceanloc_error_or_finite_results(name, data):
    build, call = ARRAY_CASES[name]
    args = build()
    key = data.draw(st.sampled_from(sorted(args)), label="argument")
    how = data.draw(st.sampled_from(CORRUPTIONS), label="corruption")
    where = data.draw(st.floats(0.0, 1.0), label="where")
    args[key] = corrupt(args[key], how, where)
    _outcome(lambda: call(args), inf_allowed=name.startswith("hdop"))


SCENARIO = oceanloc.load_survey_scenario("garcia2019-m1")
RNG = np.random.default_rng(0)
SIZE_CALLS: dict[str, tuple[Callable[[int], object], tuple[int, ...]]] = {
    "optimize_placement n_nodes": (
        lambda n: oceanloc.optimize_placement(
            n, "range", min_standoff_m=10.0, max_standoff_m=100.0, rng=RNG, starts=1, screen=64
        ),
        (-1, 0, 10**6, 10**9, 10**18),
    ),
    "optimize_placement screen": (
        lambda n: oceanloc.optimize_placement(
            3, "tdoa", min_standoff_m=10.0, max_standoff_m=100.0, rng=RNG, starts=1, screen=n
        ),
        (-1, 0, 10**9, 10**18),
    ),
    "survey_monte_carlo runs": (
        lambda n: oceanloc.survey_monte_carlo(SCENARIO, n, 0),
        (-1, 0, 10**9, 10**18),
    ),
    "simulate_surveys run index": (lambda n: oceanloc.simulate_surveys(SCENARIO, [n], 0), (-1, -(10**18))),
    "simulate_surveys seed": (lambda n: oceanloc.simulate_surveys(SCENARIO, [0], n), (-1, 10**30)),
    "MapOptions max_iterations": (lambda n: oceanloc.MapOptions(max_iterations=n), (-1, 0, 10**9, 10**18)),
}


@pytest.mark.parametrize(
    ("name", "size"), [(name, size) for name, (_, sizes) in SIZE_CALLS.items() for size in sizes]
)
def test_hostile_sizes_get_an_oceanloc_error(name, size):
    """Sizes that would allocate gigabytes (``optimize_placement(10**6)`` asked for 30 GiB) or make no sense
    are refused at the entry."""
    call, _ = SIZE_CALLS[name]
    with pytest.raises(OceanlocError):
        call(size)


@pytest.mark.parametrize(
    ("call", "names"),
    [
        (lambda: oceanloc.rmsee(np.zeros((0, 3))), "errors_m"),
        (lambda: oceanloc.confidence_ellipse([], np.zeros((0, 0))), "center_m"),
        (lambda: oceanloc.nees(np.full((2, 1, 3), np.nan), np.tile(np.eye(3), (2, 1, 1, 1))), "errors_m"),
        (lambda: oceanloc.chi_square_check([1.0, np.nan, 3.0], 3), "samples"),
        (
            lambda: oceanloc.pcrlb(
                np.full((4, 4), np.nan), np.eye(4), np.eye(4), np.tile(np.eye(4), (3, 1, 1))
            ),
            "initial_cov",
        ),
        (
            lambda: _solve_map({**_range_case(), "ranges_m": np.array([[np.nan, 30.0, 30.0, 30.0]])}),
            "ranges_m",
        ),
        (lambda: _solve_map({**_range_case(), "ranges_m": np.full((1, 4), 1e300)}), "ranges_m"),
        (lambda: _solve_map({**_range_case(), "prior_cov": np.eye(3) * 1e300}), "prior covariance"),
        (lambda: _solve_map({**_range_case(), "sigma_m": np.array([1e-300])}), "sigma_m"),
        (
            lambda: _run_filter(
                {
                    "mean": INIT.mean,
                    "cov": np.full_like(INIT.cov, np.nan),
                    "measurements": Z,
                    "sensors_m": np.broadcast_to(SENSORS, (6, 4, 2)),
                }
            ),
            "initial.cov",
        ),
        (
            lambda: _run_filter(
                {
                    "mean": INIT.mean,
                    "cov": np.tile(np.eye(4) * 1e308, (2, 1, 1)),
                    "measurements": Z,
                    "sensors_m": np.broadcast_to(SENSORS, (6, 4, 2)),
                }
            ),
            "initial.cov",
        ),
    ],
)
def test_the_audited_cases_name_the_argument(call, names):
    """The audit's cases, each once: the error names the argument (no LinAlgError, IndexError, NaN)."""
    with pytest.raises(OceanlocError, match=names):
        call()
