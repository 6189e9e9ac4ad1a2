"""Localize seafloor transponders from simulated ranges with the batch MAP solver (journal eqs. 10-22).

Loads a survey scenario (a built-in name or a TOML file), drives the vehicle once around a 30 m circle
through the survey area, simulates noisy ranges to every transponder, and solves all transponders as one
batch with ``solve_map``. Prints each estimate, its error and its 95 % horizontal confidence ellipse.

    python examples/localize_transponders.py [SCENARIO]      # default: garcia2019-m4
"""

import sys

import numpy as np

from oceanloc.config.survey import load_survey_scenario
from oceanloc.estimation.consistency import confidence_ellipse
from oceanloc.estimation.map_gauss_newton import GaussianPrior, RangeProblem, solve_map
from oceanloc.models.measurements import range_m

scenario = load_survey_scenario(sys.argv[1] if len(sys.argv) > 1 else "garcia2019-m4")
truth_m = scenario.transponders_enu_m  # (M, 3), metres
rng = np.random.default_rng(2019)

# Vehicle sites: 40 points on a circle of radius 30 m about the transponders' centroid, at the surface.
angle = np.linspace(0.0, 2.0 * np.pi, 40, endpoint=False)
centre = truth_m[:, :2].mean(axis=0)
sites_m = np.column_stack([centre[0] + 30 * np.cos(angle), centre[1] + 30 * np.sin(angle), 0 * angle])

# Ranges: one row per transponder (the batch), one column per site; noise N(0, sigma^2).
ranges = range_m(truth_m[:, None, :], sites_m[None, :, :])
ranges = ranges + scenario.sigma_range_m * rng.standard_normal(ranges.shape)
problem = RangeProblem.build(np.broadcast_to(sites_m, (*ranges.shape, 3)), ranges, scenario.sigma_range_m)

# Prior: each mean drawn from N(truth, P_0), as the papers' Monte Carlo does. Gauss-Newton starts at the
# circle's centre, 5 m deep: with a 100 m prior sigma, a start at a far prior mean can end in a local minimum.
prior_sd = np.sqrt(np.diag(scenario.prior_cov_m2))
prior = GaussianPrior(mean=truth_m + prior_sd * rng.standard_normal(truth_m.shape), cov=scenario.prior_cov_m2)
start_m = np.broadcast_to([centre[0], centre[1], -5.0], truth_m.shape)
result = solve_map(problem, prior, initial=start_m)

ellipse = confidence_ellipse(result.estimate[:, :2], result.covariance[:, :2, :2], 0.95)
print(f"scenario {scenario.name}: {len(truth_m)} transponders, {len(sites_m)} ranges each")
for m, est in enumerate(result.estimate):
    error = np.linalg.norm(est - truth_m[m])
    print(
        f"transponder {m + 1}: estimate E {est[0]:7.3f} N {est[1]:7.3f} U {est[2]:7.3f} m, "
        f"error {error:.3f} m, 95% ellipse {ellipse.semi_major_m[m]:.3f} x {ellipse.semi_minor_m[m]:.3f} m "
        f"at {np.degrees(ellipse.angle_rad[m]):+.0f} deg from east, "
        f"converged {bool(result.converged[m])} in {int(result.iterations[m])} iterations"
    )
print(f"max error {np.max(np.linalg.norm(result.estimate - truth_m, axis=1)):.4f} m")
