"""Fly a plan: step-by-step re-simulation of a drift plan in the problem's own (possibly time-varying) field.

A plan is a sequence of instructions: drift for ``n`` steps, then fly to a landing point. Re-simulating it
starts at the problem's start (and start time ``problem.t0_s``), drifts each run of drift edges for its
number of steps *from the time the run begins* (the clock advances by ``dt_s`` per drift step and by
``distance / flight speed`` per flight), and flies from wherever the drift really ended to the planned
landing point. The flight energy of the re-simulated path (IV.14) is what the plan costs when flown;
a planner that is honest about a time-varying field reports exactly that energy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.models.paths import DriftPath
from oceanloc.planning.drift_rrt.problem import DriftProblem

__all__ = ["Resimulation", "resimulate_plan"]


@dataclass(frozen=True, slots=True, kw_only=True)
class Resimulation:
    """What a plan costs when flown.

    Attributes
    ----------
    path : DriftPath
        The re-simulated path (vertex times follow the clock: drift steps and flight distance / speed).
    flight_distance_m : float
    flight_energy_wh : float
        Energy of the flights (IV.14); in the water, the power times the powered time.
    arrival_s : float
        Time at the end of the path, seconds (same time frame as ``problem.t0_s``).
    end_m : (2,) float
    reaches_goal : bool
        The re-simulated path ends inside the goal disk.
    max_deviation_m : float
        Largest distance between a planned vertex and its re-simulated counterpart (0 for a plan drifted
        in time correctly).
    blocked : bool
        A drift left the valid space (or the field's span) before its planned number of steps, or (in the
        water) the current did not let a powered leg hold its course.
    finished_by_flight : bool
        A straight flight to the goal was appended because the re-simulated path missed the goal disk.
    """

    path: DriftPath
    flight_distance_m: float
    flight_energy_wh: float
    arrival_s: float
    end_m: FloatArray
    reaches_goal: bool
    max_deviation_m: float
    blocked: bool
    finished_by_flight: bool = False

    def to_record(self) -> dict[str, Any]:
        """Plain JSON-ready summary (distances m, energy Wh, time s)."""
        return {
            "flight_distance_m": self.flight_distance_m,
            "flight_energy_wh": self.flight_energy_wh,
            "arrival_s": self.arrival_s,
            "end_m": [float(v) for v in self.end_m],
            "reaches_goal": self.reaches_goal,
            "max_deviation_m": self.max_deviation_m,
            "blocked": self.blocked,
            "finished_by_flight": self.finished_by_flight,
        }


def _runs(flight: np.ndarray) -> list[tuple[int, int, bool]]:
    """``(first edge, last edge + 1, is_flight)`` of every run of equal edges."""
    out: list[tuple[int, int, bool]] = []
    i = 0
    n = flight.size
    while i < n:
        j = i
        while j < n and flight[j] == flight[i]:
            j += 1
        out.append((i, j, bool(flight[i])))
        i = j
    return out


def resimulate_plan(problem: DriftProblem, path: DriftPath, *, finish_to_goal: bool = False) -> Resimulation:
    """Fly ``path``'s instructions step by step from ``problem.start_m`` at ``problem.t0_s``.

    Parameters
    ----------
    problem : DriftProblem
        Field, integrator, step, space and flight speed of the simulation.
    path : DriftPath
        The plan: its drift runs give step counts, its flight vertices the landing points.
    finish_to_goal : bool
        If the re-simulated path misses the goal disk, append a straight flight to the goal (what a
        vehicle would do) and count it.

    Returns
    -------
    Resimulation
    """
    prop, space = problem.propagator, problem.space
    speed = problem.energy.flight_speed_mps
    pos = np.asarray(problem.start_m, dtype=float)
    t = float(problem.t0_s)
    points: list[FloatArray] = [pos[None]]
    times: list[float] = [t]
    flags: list[bool] = []
    dev = float(np.linalg.norm(path.start_m - pos)) if path.n_points else 0.0
    blocked = False
    planned = path.points_m
    for a, b, is_flight in _runs(path.flight):
        if is_flight:
            for k in range(a + 1, b + 1):
                target = planned[k]
                if problem.propulsion == "air":
                    t += float(np.linalg.norm(target - pos)) / speed
                else:
                    tau, ok = problem.leg_times_s(pos, target, t)
                    blocked = blocked or not bool(ok)
                    t += float(tau) if bool(ok) else 0.0
                pos = target.copy()
                points.append(pos[None])
                times.append(t)
                flags.append(True)
            continue
        n = b - a
        poly = prop.drift_polyline(space, pos, n, t0_s=t)
        m = poly.shape[0] - 1
        blocked = blocked or m < n
        if m:
            dev = max(dev, float(np.max(np.linalg.norm(poly[1:] - planned[a + 1 : a + 1 + m], axis=1))))
            points.append(poly[1:])
            times.extend((t + prop.dt_s * np.arange(1, m + 1)).tolist())
            flags.extend([False] * m)
            t += prop.dt_s * m
            pos = poly[-1].copy()
    goal = problem.goal_m
    reaches = bool(np.linalg.norm(pos - goal) < problem.goal_tolerance_m or np.allclose(pos, goal))
    finished = False
    if finish_to_goal and not reaches:
        tau, ok = problem.leg_times_s(pos, goal, t)
        t += float(tau) if bool(ok) else float(np.linalg.norm(goal - pos)) / speed
        pos = goal.copy()
        points.append(pos[None])
        times.append(t)
        flags.append(True)
        reaches, finished = True, True
    out = DriftPath(
        points_m=np.concatenate(points), times_s=np.asarray(times), flight=np.asarray(flags, bool)
    )
    flown = out.flight_distance_m
    return Resimulation(
        path=out,
        flight_distance_m=flown,
        flight_energy_wh=problem.powered_energy_wh(out),
        arrival_s=t,
        end_m=pos,
        reaches_goal=reaches,
        max_deviation_m=dev if math.isfinite(dev) else math.inf,
        blocked=blocked,
        finished_by_flight=finished,
    )
