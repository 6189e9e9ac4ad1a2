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
    with pytest.raises(ConfigError, match="standard deviations"):
        RangeProblem.build(TABLE_I, np.ones(4), -1.0)
    with pytest.raises(ConfigError, match="sensor_m has shape"):
        RangeProblem.build(np.zeros((3, 3)), np.ones((1, 4)), 1.0)
