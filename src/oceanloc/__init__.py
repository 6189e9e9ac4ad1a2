"""oceanloc: surface-based underwater acoustic localization.

Transponder surveys with D-optimal measurement planning (Garcia et al.), flock tracking with EKF/UKF and
dilution of precision (Dillard, "AquaQuad"), energy-aware drift planning (DR-RRT* and a drift/hop lattice
planner), and field tools for recorded data (survey journal, GPS/USBL logs, GNSS-A, replay).

Data flows one way through the layers (``docs/architecture.md``; ``tests/test_architecture.py`` checks
the imports)::

    foundation -> geo -> models -> io -> estimation -> planning -> config -> sim -> field
        -> evaluation -> reproduce -> report -> cli

foundation is ``_typing``, ``units``, ``errors``, ``_random`` and ``data``. A module imports only from
layers to its left (and its own subpackage); the command line is a thin shell over functions a notebook
user calls directly.

The main entry points are available from the top level, loaded on first use so that ``import oceanloc``
stays fast::

    import oceanloc
    scenario = oceanloc.load_survey_scenario("garcia2019-m4")
    mc = oceanloc.survey_monte_carlo(scenario, runs=16, seed=2019)

``oceanloc.__all__`` lists them; ``examples/`` shows them in use.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

# Public name -> (module, attribute in it). Resolved lazily by __getattr__ (PEP 562): the subpackages pull
# in numpy, scipy and xarray (0.3 to 0.9 s), which a plain `import oceanloc` skips.
_LAZY: dict[str, tuple[str, str]] = {
    # transponder surveys: scenarios, the MAP estimator, planners, closed loop, Monte Carlo
    "SurveyScenario": ("oceanloc.config.survey", "SurveyScenario"),
    "load_survey_scenario": ("oceanloc.config.survey", "load_survey_scenario"),
    "builtin_survey_scenarios": ("oceanloc.config.survey", "builtin_survey_scenarios"),
    "GaussianPrior": ("oceanloc.estimation.map_gauss_newton", "GaussianPrior"),
    "MapOptions": ("oceanloc.estimation.map_gauss_newton", "MapOptions"),
    "MapResult": ("oceanloc.estimation.map_gauss_newton", "MapResult"),
    "RangeProblem": ("oceanloc.estimation.map_gauss_newton", "RangeProblem"),
    "solve_map": ("oceanloc.estimation.map_gauss_newton", "solve_map"),
    "PlanningState": ("oceanloc.planning.measurement_sites", "PlanningState"),
    "LookaheadPlanner": ("oceanloc.planning.measurement_sites", "LookaheadPlanner"),
    "GreedyPlanner": ("oceanloc.planning.measurement_sites", "GreedyPlanner"),
    "RandomYawPlanner": ("oceanloc.planning.measurement_sites", "RandomYawPlanner"),
    "RandomDiskPlanner": ("oceanloc.planning.measurement_sites", "RandomDiskPlanner"),
    "simulate_surveys": ("oceanloc.sim.survey", "simulate_surveys"),
    "survey_monte_carlo": ("oceanloc.evaluation.survey", "survey_monte_carlo"),
    "rmsee": ("oceanloc.evaluation.metrics", "rmsee"),
    # consistency checks and confidence ellipses
    "confidence_ellipse": ("oceanloc.estimation.consistency", "confidence_ellipse"),
    "nees": ("oceanloc.estimation.consistency", "nees"),
    "chi_square_check": ("oceanloc.estimation.consistency", "chi_square_check"),
    # flock tracking
    "FlockScenario": ("oceanloc.config.flock", "FlockScenario"),
    "load_flock_scenario": ("oceanloc.config.flock", "load_flock_scenario"),
    "Gaussian": ("oceanloc.estimation.gaussian", "Gaussian"),
    "run_filter": ("oceanloc.estimation.tracking", "run_filter"),
    "pcrlb": ("oceanloc.estimation.bounds", "pcrlb"),
    "hdop": ("oceanloc.planning.dop", "hdop"),
    "hdop_map": ("oceanloc.planning.dop", "hdop_map"),
    "optimize_placement": ("oceanloc.planning.dop", "optimize_placement"),
    "estimate_delay": ("oceanloc.estimation.time_delay", "estimate_delay"),
    # energy-aware drift planning
    "DriftScenario": ("oceanloc.config.drift", "DriftScenario"),
    "load_drift_scenario": ("oceanloc.config.drift", "load_drift_scenario"),
    "problem_from_scenario": ("oceanloc.config.drift", "problem_from_scenario"),
    "DriftProblem": ("oceanloc.planning.drift_rrt.problem", "DriftProblem"),
    "PlanBudget": ("oceanloc.planning.drift_rrt.problem", "PlanBudget"),
    "make_drift_planner": ("oceanloc.planning.drift_rrt.planner", "make_planner"),
    "DriftPath": ("oceanloc.models.paths", "DriftPath"),
    # field data: logs, GNSS-A, survey journal
    "read_gnssa": ("oceanloc.io.gnssa", "read_gnssa"),
    "localize_gnssa": ("oceanloc.estimation.gnssa", "localize_gnssa"),
    "GnssaOptions": ("oceanloc.estimation.gnssa", "GnssaOptions"),
    "localize_beacons": ("oceanloc.estimation.range_logs", "localize_beacons"),
    "Journal": ("oceanloc.field.survey.journal", "Journal"),
    "survey_estimates": ("oceanloc.field.survey.estimates", "survey_estimates"),
    "next_waypoint": ("oceanloc.field.survey.estimates", "next_waypoint"),
}

__all__ = [
    "DriftPath",
    "DriftProblem",
    "DriftScenario",
    "FlockScenario",
    "Gaussian",
    "GaussianPrior",
    "GnssaOptions",
    "GreedyPlanner",
    "Journal",
    "LookaheadPlanner",
    "MapOptions",
    "MapResult",
    "PlanBudget",
    "PlanningState",
    "RandomDiskPlanner",
    "RandomYawPlanner",
    "RangeProblem",
    "SurveyScenario",
    "__version__",
    "builtin_survey_scenarios",
    "chi_square_check",
    "confidence_ellipse",
    "estimate_delay",
    "hdop",
    "hdop_map",
    "load_drift_scenario",
    "load_flock_scenario",
    "load_survey_scenario",
    "localize_beacons",
    "localize_gnssa",
    "make_drift_planner",
    "nees",
    "next_waypoint",
    "optimize_placement",
    "pcrlb",
    "problem_from_scenario",
    "read_gnssa",
    "rmsee",
    "run_filter",
    "simulate_surveys",
    "solve_map",
    "survey_estimates",
    "survey_monte_carlo",
]


def __getattr__(name: str) -> Any:
    """Import a public name's module on first access and cache the name in this module."""
    try:
        module_name, attribute = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module 'oceanloc' has no attribute {name!r}") from None
    value = getattr(importlib.import_module(module_name), attribute)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


if TYPE_CHECKING:  # static type checkers and IDEs see the real objects
    from oceanloc.config.drift import DriftScenario, load_drift_scenario, problem_from_scenario
    from oceanloc.config.flock import FlockScenario, load_flock_scenario
    from oceanloc.config.survey import SurveyScenario, builtin_survey_scenarios, load_survey_scenario
    from oceanloc.estimation.bounds import pcrlb
    from oceanloc.estimation.consistency import chi_square_check, confidence_ellipse, nees
    from oceanloc.estimation.gaussian import Gaussian
    from oceanloc.estimation.gnssa import GnssaOptions, localize_gnssa
    from oceanloc.estimation.map_gauss_newton import (
        GaussianPrior,
        MapOptions,
        MapResult,
        RangeProblem,
        solve_map,
    )
    from oceanloc.estimation.range_logs import localize_beacons
    from oceanloc.estimation.time_delay import estimate_delay
    from oceanloc.evaluation.metrics import rmsee
    from oceanloc.evaluation.survey import survey_monte_carlo
    from oceanloc.field.survey.estimates import next_waypoint, survey_estimates
    from oceanloc.field.survey.journal import Journal
    from oceanloc.io.gnssa import read_gnssa
    from oceanloc.models.paths import DriftPath
    from oceanloc.planning.dop import hdop, hdop_map, optimize_placement
    from oceanloc.planning.drift_rrt.planner import make_planner as make_drift_planner
    from oceanloc.planning.drift_rrt.problem import DriftProblem, PlanBudget
    from oceanloc.planning.measurement_sites import (
        GreedyPlanner,
        LookaheadPlanner,
        PlanningState,
        RandomDiskPlanner,
        RandomYawPlanner,
    )
    from oceanloc.sim.survey import simulate_surveys
