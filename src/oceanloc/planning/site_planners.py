"""One vocabulary for measurement-site planners: their names, one parser, one label and one factory.

Every command, table, figure and record that names a measurement-site planner goes through this module:

* :data:`SitePlannerKind` - the four kinds (``random-yaw``, ``random-disk``, ``greedy``, ``lookahead``);
* :class:`PlannerSettings` - a kind and its parameters (look-ahead horizon ``k``, reach ``d_max``);
* :func:`parse_site_planner` - text such as ``k0``, ``k2``, ``greedy`` or ``random`` -> settings;
* :func:`site_planner_name` - the canonical short name (``k0``, ``k2``, ``greedy``, ``random-disk``),
  which :func:`parse_site_planner` reads back;
* :func:`site_planner_label` - the one label of tables and figures (``k = 0 (random yaw)``, ``k = 2``);
* :func:`make_site_planner` - settings plus vehicle and sensor parameters -> a planner object.

The journal (Garcia et al. 2019) numbers its planners by look-ahead ``k``: ``k = 0`` is its random
baseline (a yaw rate uniform in ``[-w_max, w_max]``), ``k >= 1`` the D-optimal look-ahead (eqs. 28-40).
The PLANS 2018 paper and the thesis compare a greedy D-optimal point within ``d_max`` (eqs. 18-29) with
a point uniform in the ``d_max`` disk.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, get_args

from oceanloc.errors import ConfigError
from oceanloc.planning.measurement_sites import (
    GreedyPlanner,
    LookaheadPlanner,
    MeasurementSitePlanner,
    RandomDiskPlanner,
    RandomYawPlanner,
)

SitePlannerKind = Literal["random-yaw", "random-disk", "greedy", "lookahead"]
SITE_PLANNER_KINDS: tuple[str, ...] = get_args(SitePlannerKind)

MAX_HORIZON = 10
"""Largest look-ahead ``k`` the parser accepts (``k1`` .. ``k10``)."""

_ACCEPTED = (
    f"k0 (random yaw), k1..k{MAX_HORIZON} (look-ahead k), random-yaw, lookahead, greedy, "
    "random-disk, random (= random-disk)"
)


@dataclass(frozen=True, slots=True, kw_only=True)
class PlannerSettings:
    """Which measurement-site planner to run and its parameters.

    Attributes
    ----------
    kind : {"random-yaw", "random-disk", "greedy", "lookahead"}
        ``random-yaw``: yaw rate uniform in ``[-w_max, w_max]`` (the journal's k = 0);
        ``random-disk``: a point uniform in the disk of radius ``max_distance_m`` (the thesis' baseline);
        ``greedy``: D-optimal point within ``max_distance_m`` (PLANS 2018 eqs. 18-29);
        ``lookahead``: D-optimal yaw-rate sequence over ``horizon`` steps (journal eqs. 28-40).
    horizon : int
        Look-ahead steps ``k``.
    max_distance_m : float
        Reach ``d_max`` between epochs for the point planners, metres.
    """

    kind: SitePlannerKind = "lookahead"
    horizon: int = 1
    max_distance_m: float = 5.0

    def __post_init__(self) -> None:
        if self.kind not in SITE_PLANNER_KINDS:
            raise ConfigError(
                f"planner kind must be one of {', '.join(SITE_PLANNER_KINDS)}; got '{self.kind}'"
            )
        if self.horizon < 1:
            raise ConfigError(f"planner horizon must be at least 1, got {self.horizon}")
        if not self.max_distance_m > 0:
            raise ConfigError(f"planner max_distance_m must be positive, got {self.max_distance_m}")


def parse_site_planner(text: str, *, horizon: int = 1, max_distance_m: float = 5.0) -> PlannerSettings:
    """Settings from a planner name (case-insensitive).

    Accepted: ``k0`` (= ``random-yaw``), ``k1`` .. ``k10`` (``lookahead`` with that horizon),
    ``random-yaw``, ``lookahead`` (with ``horizon``), ``greedy``, ``random-disk`` and ``random`` (an alias
    of ``random-disk``). ``max_distance_m`` (metres) is the reach of the point planners.

    Raises
    ------
    ConfigError
        For any other name; the message lists the accepted names.
    """
    name = text.strip().lower()
    if name in ("k0", "random-yaw"):
        return PlannerSettings(kind="random-yaw", horizon=horizon, max_distance_m=max_distance_m)
    if name == "lookahead":
        return PlannerSettings(kind="lookahead", horizon=horizon, max_distance_m=max_distance_m)
    if name == "greedy":
        return PlannerSettings(kind="greedy", horizon=horizon, max_distance_m=max_distance_m)
    if name in ("random-disk", "random"):
        return PlannerSettings(kind="random-disk", horizon=horizon, max_distance_m=max_distance_m)
    digits = name[1:]
    if name.startswith("k") and digits.isdigit() and 1 <= int(digits) <= MAX_HORIZON:
        return PlannerSettings(kind="lookahead", horizon=int(digits), max_distance_m=max_distance_m)
    raise ConfigError(f"unknown planner '{text}': use {_ACCEPTED}")


def site_planner_name(settings: PlannerSettings) -> str:
    """Canonical short name: ``k0`` (random yaw), ``k<horizon>`` (look-ahead), ``greedy``, ``random-disk``."""
    if settings.kind == "random-yaw":
        return "k0"
    if settings.kind == "lookahead":
        return f"k{settings.horizon}"
    return settings.kind


def site_planner_label(settings: PlannerSettings) -> str:
    """The label of a planner in every table and figure: ``k = 0 (random yaw)``, ``k = 2``, ``greedy``,
    ``random disk``."""
    if settings.kind == "random-yaw":
        return "k = 0 (random yaw)"
    if settings.kind == "lookahead":
        return f"k = {settings.horizon}"
    if settings.kind == "random-disk":
        return "random disk"
    return "greedy"


def make_site_planner(
    settings: PlannerSettings,
    *,
    max_yaw_rate_rad_s: float,
    speed_mps: float,
    period_s: float,
    sigma_range_m: float,
) -> MeasurementSitePlanner:
    """The planner ``settings`` names, with the vehicle (``w_max`` rad/s, speed m/s, period s) and the
    range noise (metres)."""
    if settings.kind == "lookahead":
        return LookaheadPlanner(
            horizon=settings.horizon,
            max_yaw_rate_rad_s=max_yaw_rate_rad_s,
            speed_mps=speed_mps,
            period_s=period_s,
            sigma_range_m=sigma_range_m,
        )
    if settings.kind == "greedy":
        return GreedyPlanner(max_distance_m=settings.max_distance_m, sigma_range_m=sigma_range_m)
    if settings.kind == "random-yaw":
        return RandomYawPlanner(
            max_yaw_rate_rad_s=max_yaw_rate_rad_s,
            speed_mps=speed_mps,
            period_s=period_s,
            sigma_range_m=sigma_range_m,
        )
    return RandomDiskPlanner(max_distance_m=settings.max_distance_m, sigma_range_m=sigma_range_m)
