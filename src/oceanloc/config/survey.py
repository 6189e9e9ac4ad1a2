"""Transponder-survey scenarios: TOML file -> validated, frozen :class:`SurveyScenario`.

A scenario describes the world (transponders), the vehicle, the range sensor, the prior, the
estimator's stopping rules, a default planner and Monte Carlo settings. The papers' scenarios ship as
TOML files in ``oceanloc/config/scenarios/survey`` and are addressed by name (``garcia2019-m4``)::

    [scenario]
    name = "my-survey"
    epochs = 50                       # measurement epochs N

    [vehicle]
    start_enu_m = [-3.0, 9.0, 0.0]
    start_yaw_deg = -30.0             # counter-clockwise from east
    speed_mps = 3.0
    period_s = 1.0
    max_yaw_rate_deg_s = 30.0

    [sensor]
    sigma_range_m = 0.12

    [prior]
    sigma_enu_m = [100.0, 100.0, 2.0] # 0P_T = diag(sigma^2)

    [[transponders]]
    enu_m = [17.0, 15.0, -6.0]

    [planner]                          # optional
    kind = "lookahead"                 # random-yaw | random-disk | greedy | lookahead
    horizon = 2                        # look-ahead steps k (lookahead)
    max_distance_m = 5.0               # reach d_max (greedy, random-disk)

    [estimator]                        # optional
    delta_min_m = 1e-6
    max_iterations = 200

    [montecarlo]                       # optional
    runs = 1000
    seed = 2019
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.config.builtin import builtin_names, read_scenario
from oceanloc.config.toml_fields import Table
from oceanloc.errors import ConfigError
from oceanloc.planning.site_planners import (
    SITE_PLANNER_KINDS,
    PlannerSettings,
    parse_site_planner,
    site_planner_name,
)
from oceanloc.units import DEG

MAX_RUNS = 10_000_000
"""Most Monte Carlo runs a scenario may ask for."""
MAX_RESULT_BYTES = 4 * 2**30
"""Most memory the results of one Monte Carlo may take, bytes (checked before it starts)."""


@dataclass(frozen=True, slots=True, kw_only=True)
class EstimatorSettings:
    """Stopping rules of the MAP Gauss-Newton estimator (the papers' ``delta_min`` and ``J_max``)."""

    delta_min_m: float = 1e-6
    max_iterations: int = 200


@dataclass(frozen=True, slots=True, kw_only=True)
class SurveyScenario:
    """A validated transponder-survey scenario.

    Attributes
    ----------
    name, description : str
    transponders_enu_m : (M, 3) float
        True transponder positions, metres (z negative below the surface).
    start_enu_m : (3,) float
        Vehicle position at epoch 1, metres.
    start_yaw_rad : float
        Vehicle heading at epoch 1, radians counter-clockwise from east.
    speed_mps : float
        Forward speed (body velocity ``[speed, 0, 0]``), m/s.
    period_s : float
        Sampling period ``T``, s.
    max_yaw_rate_rad_s : float
        Yaw-rate limit ``w_max``, rad/s.
    sigma_range_m : float
        Range noise standard deviation, metres.
    prior_cov_m2 : (3, 3) float
        Prior covariance ``0P_T``, square metres.
    epochs : int
        Number of measurement epochs ``N``.
    planner : PlannerSettings
    estimator : EstimatorSettings
    runs : int
        Default number of Monte Carlo runs.
    seed : int
        Default master seed.
    toml_text : str
        The TOML text the scenario was read from (empty if built in code); its SHA-256 goes into the
        provenance of every record made from the scenario.
    """

    name: str
    description: str = ""
    transponders_enu_m: FloatArray
    start_enu_m: FloatArray
    start_yaw_rad: float
    speed_mps: float
    period_s: float
    max_yaw_rate_rad_s: float
    sigma_range_m: float
    prior_cov_m2: FloatArray
    epochs: int
    planner: PlannerSettings = dataclasses.field(default_factory=PlannerSettings)
    estimator: EstimatorSettings = dataclasses.field(default_factory=EstimatorSettings)
    runs: int = 100
    seed: int = 0
    toml_text: str = dataclasses.field(default="", repr=False, compare=False)

    @property
    def n_transponders(self) -> int:
        return int(self.transponders_enu_m.shape[0])

    def bytes_per_run(self) -> int:
        """Memory a Monte Carlo run of this scenario needs, bytes (an upper estimate): per epoch the
        sites, RMSEE, log det and, per transponder, the estimate, its 3x3 covariance and NEES (float64)."""
        return 8 * (self.epochs + 1) * (5 + self.n_transponders * (3 + 9 + 1))

    def check_runs(self, runs: int, *, max_bytes: int = MAX_RESULT_BYTES) -> None:
        """Raise ConfigError if ``runs`` exceeds :data:`MAX_RUNS` or would need more than ``max_bytes``.

        Checked before anything is allocated; the message says how much memory and what to change.
        """
        need = runs * self.bytes_per_run()
        if runs > MAX_RUNS or need > max_bytes:
            fit = max(1, min(MAX_RUNS, max_bytes // self.bytes_per_run()))
            raise ConfigError(
                f"--runs {runs}: {runs} runs of {self.name!r} ({self.epochs} epochs, {self.n_transponders} "
                f"transponders) need about {need / 2**30:.3g} GiB of results (limit {max_bytes / 2**30:.3g} "
                f"GiB, at most {MAX_RUNS} runs); use --runs {fit} or fewer, or fewer --epochs"
            )

    def with_planner(self, planner: PlannerSettings) -> SurveyScenario:
        """The same scenario with another planner."""
        return dataclasses.replace(self, planner=planner)

    def with_overrides(
        self, *, planner: str | None = None, horizon: int | None = None, epochs: int | None = None
    ) -> SurveyScenario:
        """The scenario with a planner named as :func:`parse_site_planner` reads it (``k0``, ``k2``,
        ``greedy``, ...), another look-ahead ``horizon`` and/or another number of ``epochs``.

        ``horizon`` alone changes the look-ahead of a look-ahead planner (and is kept for the others).
        """
        scen = self
        if planner is not None or horizon is not None:
            cur = self.planner
            keep = "lookahead" if cur.kind == "lookahead" else site_planner_name(cur)
            scen = scen.with_planner(
                parse_site_planner(
                    planner or keep, horizon=horizon or cur.horizon, max_distance_m=cur.max_distance_m
                )
            )
        if epochs is not None:
            if epochs < 1:
                raise ConfigError(f"epochs must be at least 1, got {epochs}")
            scen = dataclasses.replace(scen, epochs=epochs)
        return scen


MIN_PRIOR_SIGMA_M = 1e-3
"""Smallest prior 1-sigma per axis, metres (below it the prior information overflows: 5e-324 m gives inf)."""
MAX_PRIOR_SIGMA_M = 1e5
"""Largest prior 1-sigma per axis, metres (far beyond any acoustic range; 1e160 m squares to inf)."""
MAX_EXTENT_M = 1e5
"""Largest horizontal coordinate of a start or transponder position (and reach), metres from the origin."""
MAX_DEPTH_M = 11_000.0
"""Deepest transponder, metres below the surface (the deepest ocean)."""
MAX_TRANSPONDERS = 64
"""Most transponders in one survey scenario."""


def builtin_survey_scenarios() -> list[str]:
    """Names of the survey scenarios shipped with oceanloc."""
    return builtin_names("survey")


def load_survey_scenario(name_or_path: str | Path) -> SurveyScenario:
    """Load a built-in survey scenario by name or a scenario TOML file by path."""
    root, _, text = read_scenario(name_or_path, "survey")
    return dataclasses.replace(survey_scenario_from_table(root), toml_text=text)


def survey_scenario_from_table(root: Table) -> SurveyScenario:
    """Validate a parsed scenario file; every error names the file, table and field."""
    head = root.table("scenario")
    name = head.str("name")
    description = head.str("description", "")
    epochs = head.int("epochs", lo=1, hi=100_000)
    head.check_unknown()

    veh = root.table("vehicle")
    start = veh.vector("start_enu_m", 3, lo=-MAX_EXTENT_M, hi=MAX_EXTENT_M)
    start_yaw = veh.float("start_yaw_deg", 0.0, lo=-360.0, hi=360.0) * DEG
    speed = veh.float("speed_mps", 3.0, lo=1e-3, hi=100.0)
    period = veh.float("period_s", 1.0, lo=1e-3, hi=3600.0)
    w_max = veh.float("max_yaw_rate_deg_s", 30.0, lo=1e-3, hi=3600.0) * DEG
    veh.check_unknown()

    sensor = root.table("sensor")
    sigma = sensor.float("sigma_range_m", lo=1e-6, hi=1e3)
    sensor.check_unknown()

    prior = root.table("prior")
    prior_sigma = prior.vector("sigma_enu_m", 3, lo=MIN_PRIOR_SIGMA_M, hi=MAX_PRIOR_SIGMA_M)
    prior.check_unknown()

    tables = root.tables("transponders", min_count=1)
    if len(tables) > MAX_TRANSPONDERS:
        raise root.error("transponders", f"at most {MAX_TRANSPONDERS} transponders, got {len(tables)}")
    positions = []
    for t in tables:
        pos = t.vector("enu_m", 3, lo=-MAX_EXTENT_M, hi=MAX_EXTENT_M)
        if not -MAX_DEPTH_M <= pos[2] < 0.0:
            raise t.error(
                "enu_m", f"transponders lie below the surface, z in [-{MAX_DEPTH_M:g}, 0) m, got z = {pos[2]}"
            )
        positions.append(pos)
        t.check_unknown()

    plan_t = root.table("planner", required=False)
    planner = PlannerSettings(
        kind=plan_t.str("kind", "lookahead", choices=SITE_PLANNER_KINDS),  # type: ignore[arg-type]
        horizon=plan_t.int("horizon", 1, lo=1, hi=10),
        max_distance_m=plan_t.float("max_distance_m", 5.0, lo=0.0, lo_open=True, hi=MAX_EXTENT_M),
    )
    plan_t.check_unknown()

    est_t = root.table("estimator", required=False)
    estimator = EstimatorSettings(
        delta_min_m=est_t.float("delta_min_m", 1e-6, lo=1e-12, hi=1.0),
        max_iterations=est_t.int("max_iterations", 200, lo=1, hi=10_000),
    )
    est_t.check_unknown()

    mc = root.table("montecarlo", required=False)
    runs = mc.int("runs", 100, lo=1, hi=MAX_RUNS)
    seed = mc.int("seed", 0, lo=0, hi=2**63 - 1)
    mc.check_unknown()
    root.check_unknown()

    return SurveyScenario(
        name=name,
        description=description,
        transponders_enu_m=np.array(positions),
        start_enu_m=start,
        start_yaw_rad=start_yaw,
        speed_mps=speed,
        period_s=period,
        max_yaw_rate_rad_s=w_max,
        sigma_range_m=sigma,
        prior_cov_m2=np.diag(prior_sigma**2),
        epochs=epochs,
        planner=planner,
        estimator=estimator,
        runs=runs,
        seed=seed,
    )
