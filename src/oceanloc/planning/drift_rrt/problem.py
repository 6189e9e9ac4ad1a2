"""The drift-planning problem, budgets and results (OMPL's ``ProblemDefinition`` and ``PlannerStatus``).

A :class:`DriftProblem` bundles the space (bounds, obstacles), the propagator (current field and
integrator), start, goal disk, the vehicle's energy budget (flight speed, power, longest hop) and the
optional HDOP term. Every planner is a function ``plan(problem, rng, budget) -> DriftPlanResult``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal, TypeAlias, get_args

import numpy as np

from oceanloc._typing import BoolArray, FloatArray, IntArray
from oceanloc.errors import ConfigError
from oceanloc.models.energy import EnergyBudget
from oceanloc.models.paths import DriftPath
from oceanloc.models.powered import Propulsion, check_propulsion, leg_times_s
from oceanloc.planning.drift_rrt.objective import HdopTerm
from oceanloc.planning.drift_rrt.propagation import DriftPropagator
from oceanloc.planning.drift_rrt.space import DriftSpace
from oceanloc.planning.status import PlanStatus

Objective: TypeAlias = Literal["energy", "time"]
"""``energy``: flight energy plus the price of time (Wh); ``time``: the arrival time (s after the start)."""
OBJECTIVES: tuple[str, ...] = get_args(Objective)


@dataclass(frozen=True, slots=True, kw_only=True)
class DriftProblem:
    """Everything a drift planner needs.

    Attributes
    ----------
    space : DriftSpace
        Bounds and obstacles.
    propagator : DriftPropagator
        Current field and integrator.
    start_m, goal_m : (2,) float
        Start and goal, metres.
    goal_tolerance_m : float
        A path succeeds when it ends within this distance of the goal (100 m in the thesis).
    energy : EnergyBudget
        Flight power and speed, longest hop, solar income.
    hdop : HdopTerm or None
        Flock geometry for the HDOP cost term (the thesis planner needs it).
    horizon_s : float
        Longest drift the planners consider from any node (the trajectories of a stable vortex end in its
        centre within a few hours; time-periodic fields need a horizon).
    max_leg_m : float or None
        Longest single flight leg in the oceanloc planners; ``None`` lets flights be any length, which is how
        the thesis accounts its paths (consecutive hops merged into one straight flight).
    t0_s : float
        Start time (matters for time-dependent fields).
    time_weight_wh_per_h : float
        Price of time in the oceanloc planners' objective, Wh per hour of path: with 0 (the thesis, which
        reports flight energy only) drifting is free however long it takes; in closed circulations
        (gyres) a small price stops plans that circle for days to save a few watt-hours.
    objective : {"energy", "time"}
        What the oceanloc planner minimizes: flight energy plus the price of time (Wh), or the time to
        reach the goal (s).
    max_duration_s : float or None
        Deadline: the plan must reach the goal within this many seconds of ``t0_s`` (energy with a
        deadline); ``None``: no deadline.
    propulsion : {"air", "water"}
        What powered legs move through (:mod:`oceanloc.models.powered`): the air (a flying drifter, legs
        unaffected by the current, the thesis) or the water (a boat, carried by the current while it holds
        its course; obstacles are then land it cannot cross).
    """

    space: DriftSpace
    propagator: DriftPropagator
    start_m: FloatArray
    goal_m: FloatArray
    goal_tolerance_m: float = 100.0
    energy: EnergyBudget = field(default_factory=EnergyBudget)
    hdop: HdopTerm | None = None
    horizon_s: float = 24 * 3600.0
    max_leg_m: float | None = None
    t0_s: float = 0.0
    time_weight_wh_per_h: float = 0.0
    objective: Objective = "energy"
    max_duration_s: float | None = None
    propulsion: Propulsion = "air"

    def __post_init__(self) -> None:
        start = np.asarray(self.start_m, dtype=float).reshape(2)
        goal = np.asarray(self.goal_m, dtype=float).reshape(2)
        if not (np.all(np.isfinite(start)) and np.all(np.isfinite(goal))):
            raise ConfigError("start and goal must be finite (x, y) positions in metres")
        if not self.goal_tolerance_m > 0:
            raise ConfigError(f"goal tolerance must be positive, got {self.goal_tolerance_m}")
        if not math.isfinite(self.t0_s):
            raise ConfigError(f"start time t0_s must be finite, got {self.t0_s}")
        if not self.horizon_s > 0:
            raise ConfigError(f"planning horizon must be positive, got {self.horizon_s}")
        if not self.time_weight_wh_per_h >= 0:
            raise ConfigError(f"time weight must not be negative, got {self.time_weight_wh_per_h}")
        if self.max_leg_m is not None and not self.max_leg_m > 0:
            raise ConfigError(f"max_leg_m must be positive or None, got {self.max_leg_m}")
        if self.objective not in OBJECTIVES:
            raise ConfigError(f"objective must be one of {', '.join(OBJECTIVES)}; got '{self.objective}'")
        if self.max_duration_s is not None and not (
            self.max_duration_s > 0 and math.isfinite(self.max_duration_s)
        ):
            raise ConfigError(
                f"max_duration_s must be positive and finite or None, got {self.max_duration_s}"
            )
        check_propulsion(self.propulsion)
        object.__setattr__(self, "start_m", start)
        object.__setattr__(self, "goal_m", goal)

    @property
    def horizon_steps(self) -> int:
        """Drift steps in the horizon."""
        return max(round(self.horizon_s / self.propagator.dt_s), 1)

    @property
    def time_weight_m_per_s(self) -> float:
        """The time price in metres of flight per second (the lattice planner's unit)."""
        return self.time_weight_wh_per_h / 3600.0 / self.energy.flight_wh_per_m

    @property
    def deadline_s(self) -> float | None:
        """Latest arrival time (same clock as ``t0_s``), or ``None``."""
        return None if self.max_duration_s is None else self.t0_s + self.max_duration_s

    @property
    def end_s(self) -> float:
        """End of the planning window: the deadline, or the start plus the horizon."""
        return self.t0_s + (self.horizon_s if self.max_duration_s is None else self.max_duration_s)

    @property
    def in_water(self) -> bool:
        return self.propulsion == "water"

    @property
    def powered_rate(self) -> float:
        """Objective per second of powered travel, beyond the price of time: Wh/s (energy) or 0 (time)."""
        return self.energy.flight_power_w / 3600.0 if self.objective == "energy" else 0.0

    @property
    def time_rate(self) -> float:
        """Objective per second of the plan's duration: the price of time in Wh/s (energy), or 1 (time)."""
        return self.time_weight_wh_per_h / 3600.0 if self.objective == "energy" else 1.0

    def leg_times_s(self, start_m, end_m, t0_s) -> tuple[FloatArray, BoolArray]:
        """Times of straight powered legs (:func:`oceanloc.models.powered.leg_times_s`) and feasibility."""
        return leg_times_s(
            self.propulsion,
            self.propagator.field,
            start_m,
            end_m,
            t0_s,
            self.energy.flight_speed_mps,
        )

    def powered_energy_wh(self, path: DriftPath) -> float:
        """Energy of a path's powered legs (IV.14): by distance in the air, by powered time in the water."""
        if self.propulsion == "air":
            return float(self.energy.flight_energy_wh(path.flight_distance_m))
        return self.energy.flight_power_w * path.flight_time_s / 3600.0

    def objective_of(self, path: DriftPath) -> float:
        """The planner's objective of ``path``: Wh for ``energy`` (flight plus the price of time), seconds
        for ``time``; ``inf`` if it arrives after the deadline."""
        deadline = self.deadline_s
        if deadline is not None and path.n_points and path.times_s[-1] > deadline + 1e-6:
            return math.inf
        if self.objective == "time":
            return path.duration_s
        return self.powered_energy_wh(path) + self.time_weight_wh_per_h * path.duration_s / 3600.0

    @property
    def objective_unit(self) -> str:
        return "s" if self.objective == "time" else "Wh"

    @property
    def direct_flight_m(self) -> float:
        return float(np.linalg.norm(self.goal_m - self.start_m))

    @property
    def direct_flight_wh(self) -> float:
        """Baseline energy: fly straight from start to goal (the thesis' red line, 49.5 Wh); in the water,
        the straight powered leg begun at the start time (``inf`` if the current does not allow it)."""
        if self.propulsion == "air":
            return float(self.energy.flight_energy_wh(self.direct_flight_m))
        tau, _ = self.leg_times_s(self.start_m, self.goal_m, self.t0_s)
        return self.energy.flight_power_w * float(tau) / 3600.0

    @property
    def starts_in_goal(self) -> bool:
        """The start already lies inside the goal disk (nothing to plan)."""
        return self.direct_flight_m < self.goal_tolerance_m

    def validate_endpoints(self) -> str | None:
        """A message if the start or the goal is not a valid state, else ``None``."""
        for name, point in (("start", self.start_m), ("goal", self.goal_m)):
            if not bool(self.space.is_valid(point)):
                return f"{name} {point.tolist()} is outside the map or inside an obstacle"
        return None


@dataclass(frozen=True, slots=True, kw_only=True)
class PlanBudget:
    """How long a planner may run: iterations (sampling planners) and/or wall-clock seconds."""

    max_iterations: int | None = None
    max_seconds: float | None = None

    def __post_init__(self) -> None:
        if self.max_iterations is not None and self.max_iterations < 1:
            raise ConfigError(f"max_iterations must be at least 1, got {self.max_iterations}")
        if self.max_seconds is not None and not self.max_seconds > 0:
            raise ConfigError(f"max_seconds must be positive, got {self.max_seconds}")


@dataclass(frozen=True, slots=True, kw_only=True)
class SearchTree:
    """The tree a sampling planner grew (for figures).

    Attributes
    ----------
    positions_m : (N, 2) float
    parent : (N,) int
        Parent of each node (the root is its own parent).
    hop : (N,) bool
        Whether the edge from the parent is a flight.
    cost : (N,) float
        Cumulative cost of reaching each node (the planner's objective, IV.15 for DR-RRT*).
    branch_cost : (N,) float
        Cost of the edge from the parent.
    """

    positions_m: FloatArray
    parent: IntArray
    hop: BoolArray
    cost: FloatArray
    branch_cost: FloatArray


@dataclass(frozen=True, slots=True, kw_only=True)
class DriftPlanResult:
    """What a planner returns.

    Attributes
    ----------
    status : PlanStatus
    path : DriftPath or None
        The plan (consecutive flights merged); ``None`` if FAILED.
    flight_energy_wh : float
        Energy of the flights of the plan (IV.14); ``inf`` if FAILED.
    direct_flight_wh : float
        Baseline of the problem.
    compute_s : float
        Wall-clock planning time.
    iterations : int
        Iterations run (planner-specific).
    solutions : int
        Number of goal-reaching paths found (optimality-seeking mode keeps the cheapest).
    cost : float
        The planner's own objective of the returned path (IV.15 for the thesis planner).
    tree : SearchTree or None
        The search tree, for figures.
    message : str
    direct_chosen : bool
        The planner's own plan cost more than flying straight (or reached no goal), so the direct flight
        was returned instead (:func:`oceanloc.planning.drift_rrt.direct.prefer_direct`).
    """

    status: PlanStatus
    path: DriftPath | None
    flight_energy_wh: float
    direct_flight_wh: float
    compute_s: float
    iterations: int = 0
    solutions: int = 0
    cost: float = float("nan")
    tree: SearchTree | None = None
    message: str = ""
    direct_chosen: bool = False

    @property
    def success(self) -> bool:
        return self.status is PlanStatus.EXACT

    @property
    def saving(self) -> float:
        """Fraction of the direct-flight energy saved (negative if the plan flies more)."""
        if not self.success or not self.direct_flight_wh > 0:
            return float("nan")
        return 1.0 - self.flight_energy_wh / self.direct_flight_wh

    def to_record(self) -> dict[str, Any]:
        """Plain JSON-ready outcome: status, energies (Wh), saving, compute time (s) and the path's vertices
        (the search tree is left out: it is for figures)."""
        return {
            "status": self.status.value,
            "message": self.message,
            "flight_energy_wh": self.flight_energy_wh if self.path is not None else None,
            "direct_flight_wh": self.direct_flight_wh,
            "saving": self.saving if self.success and self.direct_flight_wh > 0 else None,
            "compute_s": self.compute_s,
            "iterations": self.iterations,
            "solutions": self.solutions,
            "cost": self.cost,
            "direct_chosen": self.direct_chosen,
            "tree_nodes": None if self.tree is None else int(self.tree.parent.size),
            "path": None if self.path is None else self.path.to_record(),
        }


def arrived_result(problem: DriftProblem) -> DriftPlanResult:
    """The plan of a problem whose start lies inside the goal disk: stay (a one-point path, 0 Wh)."""
    path = DriftPath(
        points_m=problem.start_m[None], times_s=np.array([problem.t0_s]), flight=np.zeros(0, bool)
    )
    return DriftPlanResult(
        status=PlanStatus.EXACT,
        path=path,
        flight_energy_wh=0.0,
        direct_flight_wh=problem.direct_flight_wh,
        compute_s=0.0,
        solutions=1,
        cost=0.0,
        message=f"the start is {problem.direct_flight_m:g} m from the goal, inside its "
        f"{problem.goal_tolerance_m:g} m disk: nothing to plan",
    )
