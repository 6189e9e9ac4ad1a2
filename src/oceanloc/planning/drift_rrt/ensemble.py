"""Drift planning on an ensemble forecast: the plan with the least expected cost, and each plan's spread.

An ensemble gives ``M`` equally likely currents. A plan is a list of instructions (drift ``n`` steps, then
fly to a point); flown in member ``m`` it drifts elsewhere than planned, flies from wherever its drift ended
to the planned landing points, and, if the last drift misses the goal disk, flies straight to the goal
(:func:`~oceanloc.planning.drift_rrt.resimulate.resimulate_plan` with ``finish_to_goal``). Its expected
objective is the mean over the members.

:func:`plan_for_ensemble` plans in the ensemble mean and in every member, flies every candidate in every
member, and returns the candidate of least expected objective, with the objective and flight energy of
every candidate in every member (the spread). Choosing among the members' own optima is the
sample-average approximation restricted to plans that are optimal for some member (or for the mean): it is
exact when one of them is the best open-loop plan, and never worse than planning on the mean alone.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.errors import ConfigError
from oceanloc.models.currents import CurrentField
from oceanloc.planning.drift_rrt.problem import DriftPlanResult, DriftProblem
from oceanloc.planning.drift_rrt.resimulate import resimulate_plan

__all__ = ["EnsemblePlan", "plan_for_ensemble"]

Planner = Callable[[DriftProblem, np.random.Generator], DriftPlanResult]


@dataclass(frozen=True, slots=True, kw_only=True)
class EnsemblePlan:
    """Candidate plans flown in every member.

    Attributes
    ----------
    result : DriftPlanResult
        The chosen plan (least mean objective); its ``cost`` is that mean.
    labels : tuple of str
        ``"mean"`` and ``"member k"``: where each candidate was planned.
    objective : (C, M) float
        Each candidate's objective flown in each member (the problem's unit).
    energy_wh : (C, M) float
        Each candidate's flight energy in each member, Wh.
    chosen : int
        Index of the chosen candidate.
    unit : str
        Unit of ``objective``.
    """

    result: DriftPlanResult
    labels: tuple[str, ...]
    objective: FloatArray
    energy_wh: FloatArray
    chosen: int
    unit: str

    @property
    def n_members(self) -> int:
        return int(self.objective.shape[1])

    def spread(self) -> list[dict[str, Any]]:
        """Per candidate: mean, standard deviation, min and max over the members of the objective and of
        the flight energy."""
        out = []
        for i, label in enumerate(self.labels):
            e, o = self.energy_wh[i], self.objective[i]
            out.append(
                {
                    "candidate": label,
                    "chosen": i == self.chosen,
                    "objective_mean": float(np.mean(o)),
                    "objective_std": float(np.std(o, ddof=1)) if o.size > 1 else 0.0,
                    "energy_wh_mean": float(np.mean(e)),
                    "energy_wh_std": float(np.std(e, ddof=1)) if e.size > 1 else 0.0,
                    "energy_wh_min": float(np.min(e)),
                    "energy_wh_max": float(np.max(e)),
                }
            )
        return out

    def to_record(self) -> dict[str, Any]:
        return {
            "members": self.n_members,
            "unit": self.unit,
            "chosen": self.labels[self.chosen],
            "candidates": self.spread(),
            "objective": self.objective.tolist(),
            "energy_wh": self.energy_wh.tolist(),
        }


def plan_for_ensemble(
    problem: DriftProblem,
    members: Sequence[CurrentField],
    planner: Planner,
    rng: np.random.Generator,
) -> EnsemblePlan:
    """Plan for the least expected objective over ``members`` (see the module docstring).

    Parameters
    ----------
    problem : DriftProblem
        The problem in the ensemble's mean current.
    members : sequence of CurrentField
        At least two members, on the problem's frame and clock.
    planner : callable
        ``planner(problem, rng) -> DriftPlanResult``.
    rng : numpy.random.Generator
    """
    if len(members) < 2:
        raise ConfigError(f"an ensemble needs at least two members, got {len(members)}")
    in_member = [
        dataclasses.replace(problem, propagator=dataclasses.replace(problem.propagator, field=m))
        for m in members
    ]
    labels = ["mean", *(f"member {k}" for k in range(len(members)))]
    plans = [planner(p, rng) for p in [problem, *in_member]]
    objective = np.full((len(plans), len(members)), np.inf)
    energy = np.full((len(plans), len(members)), np.inf)
    for i, plan in enumerate(plans):
        if plan.path is None:
            continue
        for m, pm in enumerate(in_member):
            flown = resimulate_plan(pm, plan.path, finish_to_goal=True)
            energy[i, m] = flown.flight_energy_wh
            objective[i, m] = pm.objective_of(flown.path)
    mean = np.mean(objective, axis=1)
    if not np.isfinite(mean).any():
        return EnsemblePlan(
            result=plans[0],
            labels=tuple(labels),
            objective=objective,
            energy_wh=energy,
            chosen=0,
            unit=problem.objective_unit,
        )
    chosen = int(np.argmin(mean))
    best = plans[chosen]
    note = (
        f"ensemble of {len(members)}: the plan made in the {labels[chosen]} has the least expected objective "
        f"({mean[chosen]:.4g} {problem.objective_unit}; flight energy {np.mean(energy[chosen]):.2f} "
        f"+- {np.std(energy[chosen], ddof=1):.2f} Wh across the members)"
    )
    result = dataclasses.replace(
        best,
        cost=float(mean[chosen]) if math.isfinite(mean[chosen]) else best.cost,
        message=f"{note}; {best.message}",
    )
    return EnsemblePlan(
        result=result,
        labels=tuple(labels),
        objective=objective,
        energy_wh=energy,
        chosen=chosen,
        unit=problem.objective_unit,
    )
