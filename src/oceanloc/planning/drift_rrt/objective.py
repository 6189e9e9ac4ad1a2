"""Objectives of drift planning: the thesis' weighted cost (IV.15) and its HDOP term.

The thesis scores every tree branch with (IV.15), a weighted sum of normalized terms integrated over the
60 s step (Appendix C)::

    J = ( K1 HDOP / HDOP_max + K2 d_goal / d_max + K3 E_flight / E_flight,max - K4 P_solar / P_solar,max ) dt

with Table 3's gains ``K1 = K2 = 0.0225``, ``K3 = 0.95``, ``K4 = 0.005``, ``HDOP_max = 9000`` ("assumed"),
``d_max`` the map diagonal, ``E_flight,max`` the energy of one 2-minute flight and ``P_solar / P_solar,max``
identically one (the listing's own comment: "this essentially undoes the whole point of this
calculation"). A drift branch has ``K3 = 0``; a hop costs ``K3`` (a full hop) or ``K3 d / d_hop`` (the final
hop to the goal, and rewired hops); the cheapest of the N nearest nodes is chosen with the full expression
for a nominal 2-minute flight, which ranks candidates by ``K1 HDOP / HDOP_max + K2 d_goal / d_max`` only.

HDOP is the flock's horizontal dilution of precision with the planning node as one member (IV.A,
bearing-only by default as in the thesis' ``HDOP_Calc``, computed by the flock-tracking DOP functions
:func:`oceanloc.planning.dop.hdop`). :class:`HdopTerm` takes the HDOP function as a parameter, so range or
TDOA HDOP (or any other figure of merit) can be injected.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.planning.dop import hdop

HdopFunction = Callable[[FloatArray, FloatArray], FloatArray]
"""``hdop(nodes_m (..., n, 2), target_m (..., 2)) -> (...)``."""


def bearing_hdop(nodes_m: ArrayLike, target_m: ArrayLike) -> FloatArray:
    """Bearing-only HDOP with unit noise (IV.6; the thesis' ``HDOP_Calc``), from :func:`planning.dop.hdop`.

    Parameters
    ----------
    nodes_m : (..., n, 2) float
    target_m : (..., 2) float

    Returns
    -------
    (...) float
        m/rad; ``inf`` for singular geometry.
    """
    return hdop(nodes_m, target_m, "bearing", 1.0)


@dataclass(frozen=True, slots=True, kw_only=True)
class HdopTerm:
    """HDOP of the flock when the planning node is at a given position.

    Attributes
    ----------
    others_m : (n, 2) float
        Positions of the other flock members (the thesis: (5, 5), (5, -5), (-5, -5) km).
    target_m : (2,) float
        Assumed target position (the thesis: the goal offset by (100, 100) m to avoid the singularity).
    hdop_fn : callable
        ``hdop(nodes (..., n + 1, 2), target (..., 2)) -> (...)``; bearing-only with unit noise by default.
    """

    others_m: FloatArray
    target_m: FloatArray
    hdop_fn: HdopFunction = bearing_hdop
    _others: tuple = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        others = np.asarray(self.others_m, dtype=float).reshape(-1, 2)
        target = np.asarray(self.target_m, dtype=float).reshape(2)
        object.__setattr__(self, "others_m", others)
        object.__setattr__(self, "target_m", target)
        object.__setattr__(self, "_others", others)

    def __call__(self, positions_m: ArrayLike) -> FloatArray:
        """``(P, 2) -> (P,)`` HDOP with the node at each position."""
        p = np.asarray(positions_m, dtype=float).reshape(-1, 2)
        nodes = np.concatenate(
            [p[:, None, :], np.broadcast_to(self._others, (p.shape[0], *self._others.shape))], axis=1
        )
        return np.asarray(self.hdop_fn(nodes, np.broadcast_to(self.target_m, (p.shape[0], 2))), dtype=float)


@dataclass(frozen=True, slots=True, kw_only=True)
class ThesisCost:
    """The weighted cost (IV.15) with Table 3's gains and the listing's normalizations.

    Attributes
    ----------
    k_hdop, k_goal, k_flight, k_solar : float
        ``K1, K2, K3, K4`` (Table 3).
    hdop_max : float
        HDOP normalization (9000, "assumed" in the listing).
    distance_max_m : float
        Distance normalization: the map diagonal.
    dt_s : float
        Branch duration multiplying the bracket (the 60 s step).
    """

    k_hdop: float = 0.0225
    k_goal: float = 0.0225
    k_flight: float = 0.95
    k_solar: float = 0.005
    hdop_max: float = 9000.0
    distance_max_m: float = math.hypot(10_000.0, 10_000.0)
    dt_s: float = 60.0

    def position_cost(self, hdop: ArrayLike, goal_distance_m: ArrayLike) -> FloatArray:
        """``K1 HDOP / HDOP_max + K2 d_goal / d_max`` (the position-dependent part of the bracket)."""
        return (
            self.k_hdop * np.asarray(hdop) / self.hdop_max
            + self.k_goal * np.asarray(goal_distance_m) / self.distance_max_m
        )

    def drift_cost(self, position_cost: ArrayLike) -> FloatArray:
        """Cost of one drift branch ending where the position cost is ``position_cost`` (K3 = 0)."""
        return (np.asarray(position_cost) - self.k_solar) * self.dt_s

    def hop_cost(self, fraction: ArrayLike = 1.0) -> FloatArray:
        """Cost of a hop of ``fraction`` of the maximum hop length (``K3 d / d_hop``)."""
        return self.k_flight * np.asarray(fraction, dtype=float)
