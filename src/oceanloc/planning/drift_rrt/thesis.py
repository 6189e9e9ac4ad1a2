"""DR-RRT*: the thesis' dead-reckoning RRT* (Dillard, Chapter IV.C, Table 3, Appendix C).

One iteration drifts the newest node one step (the dead-reckoning branch, Euler over 60 s). A counter
grows while the drift does not bring the node closer to the goal by more than 0.1 m/s, or when the drift
step is blocked (obstacle, map edge); after 10 such iterations the planner hops:

1. target: the goal with probability 0.05, otherwise a point uniform over the map;
2. parent: of the N = 5 nodes nearest the target, the one with the least position cost
   ``K1 HDOP / HDOP_max + K2 d_goal / d_max`` (IV.15 with a nominal 2-minute flight);
3. hop: straight to the goal if the parent is within one hop of it (cost ``K3 d / d_hop``), otherwise a
   full hop ``d_hop = 2 min x 20 kn`` towards the target (cost ``K3``); the landing must be valid;
4. rewire: each of the N nodes nearest the new node, within ``R = 2.5 km``, that is a hop node or the child of
   one, takes the new node as parent if that lowers its cumulative cost (a flight of cost
   ``K3 d / d_hop``); its descendants' costs follow.

The drift then continues from the newest node. A node within 100 m of the goal is a solution. The
single-solution mode stops there; the optimality-seeking mode runs the whole iteration budget and keeps
the cheapest solution in flight energy (V.A.2). The path is traced back from the solution, consecutive
hops are merged into one flight, and its energy is that of the straight distances flown (IV.14).

Readings of the listing (stated here and in the README):

- Costs of rewired nodes propagate to all descendants; the listing's update loop stops with an error
  (swallowed by its ``try``) as soon as a node has two children.
- A rewire that would make a node its own ancestor (a loop, the failure of its Fig. 49) is skipped.
- Optimality-seeking mode: the listing's loop without the ``break``: a solution node stays in the tree
  and the drift continues from it; every solution is traced and the cheapest kept.
- HDOP and costs of drift nodes are evaluated in one batch per drift chain (they are only read at the
  next hop), which gives the same tree as evaluating them one by one.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from oceanloc.errors import ConfigError
from oceanloc.models.currents import is_steady
from oceanloc.models.paths import DriftPath
from oceanloc.planning.drift_rrt.direct import prefer_direct
from oceanloc.planning.drift_rrt.nearest import GrowingNearest
from oceanloc.planning.drift_rrt.objective import ThesisCost
from oceanloc.planning.drift_rrt.problem import (
    DriftPlanResult,
    DriftProblem,
    PlanBudget,
    PlanStatus,
    SearchTree,
    arrived_result,
)
from oceanloc.planning.drift_rrt.resimulate import resimulate_plan

ThesisMode = Literal["single", "optimality-seeking"]
THESIS_MODES: tuple[str, ...] = ("single", "optimality-seeking")


@dataclass(frozen=True, slots=True, kw_only=True)
class ThesisOptions:
    """Parameters of DR-RRT* (Table 3 and Appendix C).

    Attributes
    ----------
    mode : {"single", "optimality-seeking"}
        Stop at the first solution, or run the whole budget and keep the cheapest.
    goal_probability : float
        Probability that the hop target is the goal (0.05).
    n_nearest : int
        N nearest nodes evaluated as hop parent and for rewiring (5).
    gradient_threshold_mps : float
        A drift step counts as "not approaching" when the range to the goal falls slower than this (0.1 m/s).
    trigger_count : int
        Hop after this many consecutive non-approaching or blocked drift steps (10).
    rewire_radius_m : float
        Rewiring radius (``SF / 4 = 2500 m``).
    hop_m : float or None
        Hop length; ``None`` takes ``max_flight_time x flight_speed`` from the problem's energy budget.
    cost : ThesisCost
        The weights of (IV.15).
    prevent_cycles : bool
        Skip rewires that would create a loop.
    keep_tree : bool
        Return the search tree (for figures).
    compare_direct : bool
        Return the direct flight instead of a solution that costs more flight energy than flying straight
        (where the straight flight is feasible), saying so in the message; ``False`` returns DR-RRT*'s own
        solution whatever it costs.
    """

    mode: ThesisMode = "single"
    goal_probability: float = 0.05
    n_nearest: int = 5
    gradient_threshold_mps: float = 0.1
    trigger_count: int = 10
    rewire_radius_m: float = 2500.0
    hop_m: float | None = None
    cost: ThesisCost = field(default_factory=ThesisCost)
    prevent_cycles: bool = True
    keep_tree: bool = False
    compare_direct: bool = True

    def __post_init__(self) -> None:
        if self.mode not in THESIS_MODES:
            raise ConfigError(f"DR-RRT* mode must be one of {', '.join(THESIS_MODES)}; got '{self.mode}'")
        if not 0.0 <= self.goal_probability <= 1.0:
            raise ConfigError(f"goal_probability must be within [0, 1], got {self.goal_probability}")
        if self.n_nearest < 1 or self.trigger_count < 1:
            raise ConfigError("n_nearest and trigger_count must be at least 1")
        if not self.rewire_radius_m >= 0:
            raise ConfigError(f"rewire_radius_m must not be negative, got {self.rewire_radius_m}")
        if self.hop_m is not None and not self.hop_m > 0:
            raise ConfigError(f"hop_m must be positive, got {self.hop_m}")


DEFAULT_ITERATIONS = {"single": 10_000, "optimality-seeking": 25_000}
"""The listing's 10,000 iterations for one solution; 25,000 in the optimality-seeking runs (V.A.2)."""


def plan_thesis(
    problem: DriftProblem,
    rng: np.random.Generator,
    budget: PlanBudget | None = None,
    options: ThesisOptions | None = None,
) -> DriftPlanResult:
    """Run DR-RRT* on ``problem``.

    Parameters
    ----------
    problem : DriftProblem
        Needs an HDOP term (``problem.hdop``) for the cost (IV.15).
    rng : numpy.random.Generator
        Hop targets.
    budget : PlanBudget, optional
        Iterations (default 10,000 single / 25,000 optimality-seeking) and/or seconds.
    options : ThesisOptions, optional

    Returns
    -------
    DriftPlanResult
        EXACT with the (cheapest) solution path; APPROXIMATE with the path to the node closest to the goal
        when the budget runs out first; FAILED if the start is invalid.
    """
    opts = options or ThesisOptions()
    budget = budget or PlanBudget(max_iterations=DEFAULT_ITERATIONS[opts.mode])
    if problem.hdop is None:
        raise ConfigError("DR-RRT* needs the flock geometry for its HDOP term (problem.hdop)")
    tic = time.perf_counter()
    direct = problem.direct_flight_wh
    invalid = problem.validate_endpoints()
    if invalid is not None:
        return DriftPlanResult(
            status=PlanStatus.FAILED,
            path=None,
            flight_energy_wh=math.inf,
            direct_flight_wh=direct,
            compute_s=0.0,
            message=invalid,
        )
    if problem.starts_in_goal:
        return arrived_result(problem)
    result = _DrRrtStar(problem, rng, budget, opts, tic).run()
    if not opts.compare_direct:
        return result
    return prefer_direct(problem, result, replace_unsolved=False)


class _DrRrtStar:
    """State of one DR-RRT* run (private; ``plan_thesis`` is the interface)."""

    def __init__(
        self,
        problem: DriftProblem,
        rng: np.random.Generator,
        budget: PlanBudget,
        opts: ThesisOptions,
        tic: float,
    ) -> None:
        self.p = problem
        self.rng = rng
        self.opts = opts
        self.tic = tic
        self.max_iter = budget.max_iterations if budget.max_iterations is not None else 10**9
        self.deadline = tic + budget.max_seconds if budget.max_seconds is not None else math.inf
        self.hop_m = opts.hop_m if opts.hop_m is not None else problem.energy.max_hop_m
        cost = opts.cost
        x0, x1, y0, y1 = problem.space.bounds_m
        self.cost = ThesisCost(
            k_hdop=cost.k_hdop,
            k_goal=cost.k_goal,
            k_flight=cost.k_flight,
            k_solar=cost.k_solar,
            hdop_max=cost.hdop_max,
            distance_max_m=cost.distance_max_m,
            dt_s=problem.propagator.dt_s,
        )
        self.half_span = (0.5 * (x0 + x1), 0.5 * (x1 - x0), 0.5 * (y0 + y1), 0.5 * (y1 - y0))
        sx, sy = (float(v) for v in problem.start_m)
        cap = min(self.max_iter, 200_000) + 16
        self.index = GrowingNearest(2 * cap)
        self.index.add(sx, sy)
        self.X = [sx]
        self.Y = [sy]
        self.T = [problem.t0_s]
        self.steady = is_steady(problem.propagator.field)
        self.parent = [0]
        self.hop = [False]
        self.branch = [0.0]
        self.cum = [0.0]
        self.pcost: list[float] = []
        self.children: list[list[int]] = [[]]

    # -- tree bookkeeping -------------------------------------------------------------------------------
    def _add(self, x: float, y: float, t: float, parent: int, is_hop: bool, branch: float, cum: float) -> int:
        i = self.index.add(x, y)
        self.X.append(x)
        self.Y.append(y)
        self.T.append(t)
        self.parent.append(parent)
        self.hop.append(is_hop)
        self.branch.append(branch)
        self.cum.append(cum)
        self.children.append([])
        self.children[parent].append(i)
        return i

    def _evaluate_pending(self) -> None:
        """Position costs of new nodes and costs of new drift branches, in one batch."""
        start = len(self.pcost)
        n = len(self.X)
        if start >= n:
            return
        pts = self.index.points_m[start:n]
        gx, gy = self.p.goal_m
        hd = self.p.hdop(pts)  # type: ignore[misc]
        pc = self.cost.position_cost(hd, np.hypot(pts[:, 0] - gx, pts[:, 1] - gy)).tolist()
        self.pcost.extend(pc)
        dcost = self.cost.drift_cost(np.asarray(pc)).tolist()
        parent, hop, cum, branch = self.parent, self.hop, self.cum, self.branch
        for j in range(n - start):
            i = start + j
            if not hop[i] and i != 0:
                branch[i] = dcost[j]
                cum[i] = cum[parent[i]] + dcost[j]

    def _is_ancestor(self, a: int, node: int) -> bool:
        parent = self.parent
        while node != 0:
            if node == a:
                return True
            node = parent[node]
        return a == 0

    def _reparent(self, j: int, new: int, branch: float) -> None:
        delta = self.cum[new] + branch - self.cum[j]
        self.children[self.parent[j]].remove(j)
        self.parent[j] = new
        self.children[new].append(j)
        self.branch[j] = branch
        self.hop[j] = True
        stack = [j]
        cum, children = self.cum, self.children
        while stack:
            q = stack.pop()
            cum[q] += delta
            stack.extend(children[q])

    # -- the loop ---------------------------------------------------------------------------------------
    def run(self) -> DriftPlanResult:
        p, o = self.p, self.opts
        gx, gy = (float(v) for v in p.goal_m)
        tol = p.goal_tolerance_m
        dt = p.propagator.dt_s
        step = p.propagator.step_xy
        valid = p.space.is_valid_xy
        hop_m = self.hop_m
        single = o.mode == "single"
        speed = p.energy.flight_speed_mps
        counter = 0
        last_d: float | None = None
        grad: float | None = None
        best_wh = math.inf
        best_path: DriftPath | None = None
        best_cost = math.nan
        solutions = 0
        closest = (math.hypot(self.X[0] - gx, self.Y[0] - gy), 0)
        it = 0
        while it < self.max_iter:
            it += 1
            if (it & 255) == 0 and time.perf_counter() > self.deadline:
                break
            cur = len(self.X) - 1
            x, y, t = self.X[cur], self.Y[cur], self.T[cur]
            xn, yn = step(x, y, t)
            ok = xn == xn and yn == yn and valid(xn, yn)
            if ok:
                d = math.hypot(gx - xn, gy - yn)
                node = self._add(xn, yn, t + dt, cur, False, 0.0, 0.0)
                if d < closest[0]:
                    closest = (d, node)
                if d < tol:
                    solutions += 1
                    self._evaluate_pending()
                    path = self._flown(node)
                    wh = self._energy(path)
                    if wh < best_wh:
                        best_wh, best_path, best_cost = wh, path, self.cum[node]
                    if single:
                        break
                if last_d is not None:
                    grad = (last_d - d) / dt
                last_d = d
            if it != 1 and (not ok or (grad is not None and grad <= o.gradient_threshold_mps)):
                counter += 1
            else:
                counter = 0
            if counter < o.trigger_count:
                continue
            counter = 0
            self._evaluate_pending()
            if self.rng.random() < o.goal_probability:
                tx, ty = gx, gy
            else:
                cx, hx, cy, hy = self.half_span
                u = self.rng.uniform(-1.0, 1.0, 2)
                tx, ty = cx + hx * float(u[0]), cy + hy * float(u[1])
            _, near = self.index.query(tx, ty, o.n_nearest)
            pcost = self.pcost
            par = int(min(near.tolist(), key=lambda j: pcost[j]))
            px, py = self.X[par], self.Y[par]
            dg = math.hypot(gx - px, gy - py)
            if dg <= hop_m:
                nx, ny = gx, gy
                branch = float(self.cost.hop_cost(dg / hop_m))
                dist = dg
            else:
                dxt, dyt = tx - px, ty - py
                norm = math.hypot(dxt, dyt)
                if norm == 0.0:
                    continue
                nx, ny = px + hop_m * dxt / norm, py + hop_m * dyt / norm
                if not (
                    valid(nx, ny)
                    and (
                        not p.space.flights_avoid_obstacles or bool(p.space.flight_valid((px, py), (nx, ny)))
                    )
                ):
                    continue
                branch = float(self.cost.k_flight)
                dist = hop_m
            new = self._add(nx, ny, self.T[par] + dist / speed, par, True, branch, self.cum[par] + branch)
            dnew = math.hypot(nx - gx, ny - gy)
            if dnew < closest[0]:
                closest = (dnew, new)
            if dnew < tol or (nx == gx and ny == gy):
                solutions += 1
                path = self._flown(new)
                wh = self._energy(path)
                if wh < best_wh:
                    best_wh, best_path, best_cost = wh, path, self.cum[new]
                if single:
                    break
            self._rewire(new)
        return self._result(best_path, best_wh, best_cost, closest[1], it, solutions)

    def _rewire(self, new: int) -> None:
        o = self.opts
        dist, near = self.index.query(self.X[new], self.Y[new], o.n_nearest, exclude=new)
        k3, hop_m = self.cost.k_flight, self.hop_m
        cum, hop, parent = self.cum, self.hop, self.parent
        for d, j in zip(dist.tolist(), near.tolist(), strict=True):
            branch = d / hop_m * k3
            if not (cum[new] + branch < cum[j] and d <= o.rewire_radius_m and (hop[j] or hop[parent[j]])):
                continue
            if o.prevent_cycles and self._is_ancestor(j, new):
                continue
            if self.p.space.flights_avoid_obstacles and not bool(
                self.p.space.flight_valid((self.X[new], self.Y[new]), (self.X[j], self.Y[j]))
            ):
                continue
            self._reparent(j, new, branch)

    def _branch_to(self, node: int) -> list[int]:
        seq = [node]
        parent = self.parent
        while seq[-1] != 0:
            seq.append(parent[seq[-1]])
            if len(seq) > len(parent):
                raise RuntimeError("DR-RRT* tree has a loop")  # cannot happen with prevent_cycles
        seq.reverse()
        return seq

    def _path(self, node: int) -> DriftPath:
        seq = self._branch_to(node)
        pts = np.column_stack([[self.X[i] for i in seq], [self.Y[i] for i in seq]])
        flight = np.array([self.hop[i] for i in seq[1:]], dtype=bool)
        times = np.array([self.T[0]] + [0.0] * (len(seq) - 1))
        step_len = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        dts = np.where(flight, step_len / self.p.energy.flight_speed_mps, self.p.propagator.dt_s)
        times[1:] = self.T[0] + np.cumsum(dts)
        path = DriftPath(points_m=pts, times_s=times, flight=flight)
        # The thesis merges consecutive hops into one flight; over no-fly zones the chain must stay.
        return path if self.p.space.flights_avoid_obstacles else path.merged()

    def _flown(self, node: int) -> DriftPath:
        """The solution path through ``node`` as flown.

        In a steady field the tree's own path. In a time-varying field the tree's drift branches were
        integrated from their nodes' times, but rewiring and merging hops change when the vehicle reaches
        a node, so the path is re-simulated from the start time (each drift from its own start time) and,
        if it then misses the goal disk, finished with a straight flight to the goal.
        """
        path = self._path(node)
        if self.steady:
            return path
        return resimulate_plan(self.p, path, finish_to_goal=True).path

    def _energy(self, path: DriftPath) -> float:
        return float(self.p.energy.flight_energy_wh(path.flight_distance_m))

    def _result(
        self,
        best: DriftPath | None,
        best_wh: float,
        best_cost: float,
        closest: int,
        iterations: int,
        solutions: int,
    ) -> DriftPlanResult:
        """The cheapest solution as it was when found (later rewiring may change the tree behind it)."""
        elapsed = time.perf_counter() - self.tic
        self._evaluate_pending()
        tree = None
        if self.opts.keep_tree:
            tree = SearchTree(
                positions_m=np.column_stack([self.X, self.Y]),
                parent=np.asarray(self.parent, dtype=np.int64),
                hop=np.asarray(self.hop, dtype=bool),
                cost=np.asarray(self.cum),
                branch_cost=np.asarray(self.branch),
            )
        if best is not None:
            return DriftPlanResult(
                status=PlanStatus.EXACT,
                path=best,
                flight_energy_wh=best_wh,
                direct_flight_wh=self.p.direct_flight_wh,
                compute_s=elapsed,
                iterations=iterations,
                solutions=solutions,
                cost=best_cost,
                tree=tree,
                message=f"{solutions} solution(s) in {iterations} iterations, {len(self.X)} nodes",
            )
        path = self._path(closest)
        if not self.steady:
            path = resimulate_plan(self.p, path).path
        return DriftPlanResult(
            status=PlanStatus.APPROXIMATE,
            path=path,
            flight_energy_wh=float(self.p.energy.flight_energy_wh(path.flight_distance_m)),
            direct_flight_wh=self.p.direct_flight_wh,
            compute_s=elapsed,
            iterations=iterations,
            solutions=0,
            cost=self.cum[closest],
            tree=tree,
            message=f"goal not reached in {iterations} iterations; closest node "
            f"{math.hypot(self.X[closest] - self.p.goal_m[0], self.Y[closest] - self.p.goal_m[1]):.0f} m "
            "from the goal",
        )
