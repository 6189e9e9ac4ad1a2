"""Plan where to measure next: D-optimal look-ahead over yaw rates and greedy within a reach.

After five ranges along a straight line from the scenario's start (garcia2019-m4: four transponders), the
current MAP estimates and covariances form a ``PlanningState``. ``LookaheadPlanner`` (journal eqs. 28-40)
plans k = 2 yaw rates; ``GreedyPlanner`` (PLANS 2018 eqs. 18-29) the best surface point within 5 m. Both
maximize the information gain ``sum_m log det Y_{N+k}^m - log det Y_N^m`` (nats) to its global optimum;
the greedy plan is compared with 2000 random points of the same disk.
"""

import numpy as np

from oceanloc.config.survey import load_survey_scenario
from oceanloc.estimation.map_gauss_newton import GaussianPrior, RangeProblem, solve_map
from oceanloc.models.measurements import range_m
from oceanloc.planning.measurement_sites import GreedyPlanner, LookaheadPlanner, PlanningState

sc = load_survey_scenario("garcia2019-m4")
rng = np.random.default_rng(7)
truth_m = sc.transponders_enu_m
heading = np.array([np.cos(sc.start_yaw_rad), np.sin(sc.start_yaw_rad), 0.0])
sites_m = sc.start_enu_m + np.arange(5)[:, None] * sc.speed_mps * sc.period_s * heading  # (5, 3)

ranges = range_m(truth_m[:, None, :], sites_m[None]) + sc.sigma_range_m * rng.standard_normal(
    (len(truth_m), 5)
)
problem = RangeProblem.build(np.broadcast_to(sites_m, (*ranges.shape, 3)), ranges, sc.sigma_range_m)
prior_mean = truth_m + np.sqrt(np.diag(sc.prior_cov_m2)) * rng.standard_normal(truth_m.shape)
fit = solve_map(problem, GaussianPrior(mean=prior_mean, cov=sc.prior_cov_m2))

# One planning problem (batch of 1) holding all four transponders.
state = PlanningState(
    pos_enu_m=sites_m[-1][None],
    yaw_rad=np.array([sc.start_yaw_rad]),
    estimates_m=fit.estimate[None],
    covariances_m2=fit.covariance[None],
)
lookahead = LookaheadPlanner(
    horizon=2,
    max_yaw_rate_rad_s=sc.max_yaw_rate_rad_s,
    speed_mps=sc.speed_mps,
    period_s=sc.period_s,
    sigma_range_m=sc.sigma_range_m,
)
greedy = GreedyPlanner(max_distance_m=5.0, sigma_range_m=sc.sigma_range_m)

plan = lookahead.plan(state)
rates = np.degrees(plan.yaw_rates_rad_s[0])
east, north = plan.next_pos_enu_m[0, :2]
print(
    f"look-ahead k=2: yaw rates {rates[0]:+.1f}, {rates[1]:+.1f} deg/s;"
    f" next site E {east:.2f} N {north:.2f} m;"
    f" gain {plan.objective[0]:.3f} nats ({plan.solve_time_s * 1e3:.1f} ms)"
)

plan = greedy.plan(state)
print(
    f"greedy d_max=5 m: next site E {plan.next_pos_enu_m[0, 0]:.2f} N {plan.next_pos_enu_m[0, 1]:.2f} m, "
    f"{np.linalg.norm(plan.next_pos_enu_m[0] - sites_m[-1]):.2f} m away; gain {plan.objective[0]:.3f} nats"
)

# 2000 points uniform in area over the same disk: none should beat the planner's global optimum.
rho = 5.0 * np.sqrt(rng.uniform(size=2000))
theta = rng.uniform(-np.pi, np.pi, 2000)
points = sites_m[-1] + np.column_stack([rho * np.cos(theta), rho * np.sin(theta), 0 * rho])
random_gain = greedy.gain(state, points[None])[0]
best, median = random_gain.max(), np.median(random_gain)
print(f"random points in the disk: best gain {best:.3f} nats, median {median:.3f} nats")
print(f"greedy minus best random: {plan.objective[0] - random_gain.max():.2e} nats")
