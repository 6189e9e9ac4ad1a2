import numpy as np
import pytest
from scipy import optimize, stats

from oceanloc.errors import ConfigError
from oceanloc.estimation.map_gauss_newton import GaussianPrior, MapOptions, RangeProblem, solve_map
from oceanloc.models.measurements import range_m

P_T = np.array([17.0, 15.0, -6.0])
TABLE_I = np.array([[5, 5, 0], [-5, 5, 0], [-5, -5, 0], [5, -5, 0]], float)
P0 = np.diag([100.0, 100.0, 4.0])


def _section_va(runs, seed, sigma=0.1):
    rng = np.random.default_rng(seed)
    prior = P_T + rng.multivariate_normal(np.zeros(3), P0, runs)
    z = range_m(P_T, TABLE_I)[None] + sigma * rng.standard_normal((runs, 4))
    problem = RangeProblem.build(np.broadcast_to(TABLE_I, (runs, 4, 3)), z, sigma)
    return problem, GaussianPrior(mean=prior, cov=P0)


def test_nees_is_chi_square_3_on_section_va():
    # Journal Section V-A: 500 runs, N = 4. Mean NEES of a consistent estimator is 3 with Monte Carlo
    # standard error sqrt(2*3/500) = 0.11; allow 3 SE. The KS p-value must not reject chi2(3) at 1%.
    problem, prior = _section_va(500, seed=11)
    res = solve_map(problem, prior)
    err = P_T - res.estimate
    nees = np.einsum("bi,bij,bj->b", err, res.information, err)
    assert res.converged.all()
    assert abs(nees.mean() - 3.0) < 3 * np.sqrt(6 / 500)
    assert stats.kstest(nees, stats.chi2(3).cdf).pvalue > 0.01


def test_matches_scipy_least_squares_optimum():
    problem, prior = _section_va(20, seed=3)
    res = solve_map(problem, prior)
    L = np.linalg.cholesky(np.linalg.inv(P0))
    for b in range(20):

        def resid(p, b=b):
            r = (problem.ranges_m[b] - range_m(p, problem.sensor_m[b])) / 0.1
            return np.concatenate([r, L.T @ (p - prior.mean[b])])

        ref = optimize.least_squares(resid, res.estimate[b], xtol=1e-14, ftol=1e-14, gtol=1e-14)
        np.testing.assert_allclose(res.estimate[b], ref.x, atol=1e-6)
        assert res.cost[b] == pytest.approx(0.5 * np.sum(ref.fun**2), rel=1e-9)


def test_covariance_is_inverse_information_eq22():
    problem, prior = _section_va(10, seed=5)
    res = solve_map(problem, prior)
    np.testing.assert_allclose(
        res.covariance @ res.information, np.broadcast_to(np.eye(3), (10, 3, 3)), atol=1e-9
    )


def test_step_control_never_increases_cost():
    # One range and a weak prior: plain Gauss-Newton oscillates; with step control each accepted
    # iteration lowers the cost, so the final cost is never above the starting cost and below GN's.
    rng = np.random.default_rng(2)
    runs = 200
    prior_mean = P_T + rng.multivariate_normal(np.zeros(3), np.diag([1e4, 1e4, 4.0]), runs)
    sensor = np.array([[-3.0, 9.0, 0.0]])
    z = range_m(P_T, sensor)[None] + 0.12 * rng.standard_normal((runs, 1))
    problem = RangeProblem.build(np.broadcast_to(sensor, (runs, 1, 3)), z, 0.12)
    prior = GaussianPrior(mean=prior_mean, cov=np.diag([1e4, 1e4, 4.0]))
    start_cost = 0.5 * ((z[:, 0] - range_m(prior_mean, sensor[0])) / 0.12) ** 2
    for iters in (1, 2, 3, 5, 10):
        res = solve_map(problem, prior, MapOptions(max_iterations=iters))
        assert np.all(res.cost <= start_cost + 1e-12)
    lm = solve_map(problem, prior, MapOptions(max_iterations=30))
    gn = solve_map(problem, prior, MapOptions(max_iterations=30, step_control=False))
    assert np.all(lm.cost <= gn.cost + 1e-9)
    assert np.mean(lm.cost < gn.cost - 1e-6) > 0.05  # plain GN is visibly worse on some runs


def test_never_returns_a_transponder_above_the_surface():
    # All sensors at z = 0: the likelihood cannot tell z from -z. Prior means drawn (or placed) above
    # the surface and starts in the mirror half-space still end below it.
    rng = np.random.default_rng(4)
    runs = 300
    prior_mean = P_T + rng.multivariate_normal(np.zeros(3), np.diag([100.0, 100.0, 100.0]), runs)
    prior_mean[:50, 2] = np.abs(prior_mean[:50, 2])
    z = range_m(P_T, TABLE_I)[None] + 0.1 * rng.standard_normal((runs, 4))
    problem = RangeProblem.build(np.broadcast_to(TABLE_I, (runs, 4, 3)), z, 0.1)
    start = prior_mean * np.array([1.0, 1.0, -1.0])
    res = solve_map(
        problem, GaussianPrior(mean=prior_mean, cov=np.diag([100.0, 100.0, 100.0])), initial=start
    )
    assert np.all(res.estimate[:, 2] <= 0.0)
    unconstrained = solve_map(
        problem,
        GaussianPrior(mean=prior_mean, cov=np.diag([100.0, 100.0, 100.0])),
        MapOptions(surface_z_m=None),
        initial=start,
    )
    assert np.any(unconstrained.estimate[:, 2] > 0.0)  # the constraint is doing work


def test_masked_measurements_are_ignored():
    problem, prior = _section_va(5, seed=8)
    z = problem.ranges_m.copy()
    z[:, 0] += 50.0
    mask = np.array([False, True, True, True])
    masked = solve_map(RangeProblem.build(problem.sensor_m, z, 0.1, mask), prior)
    dropped = solve_map(RangeProblem.build(problem.sensor_m[:, 1:], problem.ranges_m[:, 1:], 0.1), prior)
    np.testing.assert_allclose(masked.estimate, dropped.estimate, atol=1e-8)


def test_bad_inputs_raise_config_errors():
    with pytest.raises(ConfigError, match="delta_min_m"):
        MapOptions(delta_min_m=0.0)
    with pytest.raises(ConfigError, match=r"sigma_m: -1 is outside the allowed range \[1e-06, 1e\+06\] m"):
        RangeProblem.build(TABLE_I, np.ones(4), -1.0)
    with pytest.raises(ConfigError, match="sensor_m: shape"):
        RangeProblem.build(np.zeros((3, 3)), np.ones((1, 4)), 1.0)


@pytest.mark.parametrize(
    ("mean", "cov", "message"),
    [
        (
            [1.0, 2.0, -3.0],
            np.diag([100.0, -100.0, 4.0]),
            r"problem 0 is not positive definite \(eigenvalues -100",
        ),
        ([1.0, 2.0, -3.0], [[4.0, 5.0, 0], [5.0, 4.0, 0], [0, 0, 1]], "problem 0 is not positive definite"),
        ([1.0, 2.0, -3.0], np.diag([100.0, 0.0, 4.0]), r"problem 0 is singular \(eigenvalues 0, 4, 100 m\^2"),
        ([1.0, 2.0, -3.0], np.diag([5e-324**2, 1.0, 1.0]), "problem 0 is singular"),
        (
            [1.0, 2.0, -3.0],
            np.diag([np.inf, 1.0, 1.0]),
            "holds NaN or infinite values .a sigma beyond 1e154 m",
        ),
        ([1.0, 2.0, -3.0], np.diag([np.nan, 1.0, 1.0]), "problem 0 holds NaN or infinite values"),
        ([1.0, 2.0, -3.0], [[4.0, 1.0, 0], [0.0, 4.0, 0], [0, 0, 1]], "problem 0 is not symmetric"),
        (
            [np.nan, 2.0, -3.0],
            P0,
            r"prior mean of problem 0 holds NaN or infinite values: \[nan, 2.0, -3.0\]",
        ),
        ([np.inf, 2.0, -3.0], P0, "prior mean of problem 0 holds NaN or infinite values"),
    ],
)
def test_bad_priors_are_config_errors_naming_the_problem(mean, cov, message):
    problem = RangeProblem.build(TABLE_I, range_m(P_T, TABLE_I), 0.1)
    with pytest.raises(ConfigError, match=message):
        solve_map(problem, GaussianPrior(mean=np.asarray(mean)[None], cov=np.asarray(cov)))


def test_a_bad_prior_in_a_batch_is_named_by_its_index():
    problem = RangeProblem.build(
        np.broadcast_to(TABLE_I, (3, 4, 3)), np.tile(range_m(P_T, TABLE_I), (3, 1)), 0.1
    )
    cov = np.stack([P0, P0, np.diag([1.0, 1.0, -1.0])])
    with pytest.raises(ConfigError, match="prior covariance of problem 2 is not positive definite"):
        solve_map(problem, GaussianPrior(mean=np.tile(P_T, (3, 1)), cov=cov))


def test_prior_mean_on_the_only_sensor_is_degenerate_not_converged():
    """One sensor and the prior mean on it: the range has no direction there, the step is zero, and the
    old solver reported convergence at the sensor. Now the status says so; a start off the sensor (second
    problem) moves to the range sphere and converges."""
    sensor = np.array([[0.0, 0.0, -5.0]])
    problem = RangeProblem.build(np.broadcast_to(sensor, (2, 1, 3)), np.array([[10.0], [10.0]]), 0.1)
    prior = GaussianPrior(mean=np.array([[0.0, 0.0, -5.0], [1.0, 0.0, -5.0]]), cov=P0)
    res = solve_map(problem, prior)
    assert res.status.tolist() == ["degenerate", "converged"]
    assert res.converged.tolist() == [False, True]
    assert "measurement 0 has no information at the estimate" in res.message[0] and res.message[1] == ""
    np.testing.assert_array_equal(res.estimate[0], sensor[0])
    assert np.linalg.norm(res.estimate[1] - sensor[0]) == pytest.approx(10.0, abs=0.05)
    # Several sensors, one at the start: the others move the estimate off it and it converges.
    problem = RangeProblem.build(TABLE_I, range_m(P_T, TABLE_I), 0.1)
    res = solve_map(problem, GaussianPrior(mean=TABLE_I[:1], cov=P0))
    assert res.status.tolist() == ["converged"]
    assert np.linalg.norm(res.estimate[0] - TABLE_I[0]) > 1.0


def test_iteration_limit_is_a_status_with_a_message():
    problem, prior = _section_va(2, seed=3)
    res = solve_map(problem, prior, MapOptions(max_iterations=1))
    assert res.status.tolist() == ["max-iterations"] * 2
    assert res.message[0] == "step test not met in 1 iterations" and not res.converged.any()
