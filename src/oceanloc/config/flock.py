"""Flock-tracking scenarios: TOML file -> validated, frozen :class:`FlockScenario`.

A scenario describes the sensor nodes, the target's motion, the measurements, the filters' settings and the
Monte Carlo defaults. The AquaQuad thesis' scenarios ship as ``dillard-*.toml`` in
``oceanloc/config/scenarios/flock`` and are addressed by name (``dillard-filters``, ``dillard-lab-tdoa``)::

    [scenario]
    name = "my-flock"
    dt_s = 0.005                     # filter step = measurement interval
    duration_s = 350.0

    [nodes]
    layout = "ring"                  # ring (drifting on a circle) | y (three nodes) | fixed
    count = 4                        # ring
    radius_m = 200.0                 # ring, y
    drift_speed_mps = 0.5            # ring: speed along the circle
    phase_deg = 45.0                 # ring: node 0's polar angle; y: the first arm's (ccw from east)
    center_m = [0.0, 0.0]
    # positions_m = [x0, y0, x1, y1, ...]   # fixed

    [target]
    motion = "straight"              # straight | stop-and-go
    start_m = [0.0, 0.0]
    velocity_mps = [10.0, 1.0]       # straight
    # half_width_m, speed_mps, mean_pause_s   (stop-and-go)

    [measurement]
    kind = "bearing"                 # bearing | range | tdoa
    sigma_true = 0.0316              # simulated noise standard deviation (rad | m | s)
    sound_speed_mps = 1500.0         # tdoa
    pairs = "all"                    # tdoa: all | reference

    [filters]
    initial_state = [100.0, 100.0, 20.0, 20.0, 0.0, 0.0]
    initial_sigma = [100.0, 100.0, 20.0, 20.0, 1.0, 1.0]     # P0 = diag(sigma^2)
    process_noise = [1e-5, 1e-5, 1e-6, 1e-6, 1e-6, 1e-6]     # Q = diag(...), per step
    measurement_sigma = 1e-3                                 # R = sigma^2 I
    ekf_motion = "constant-acceleration"                     # or "listing"
    ukf_motion = "listing"
    ukf_alpha = 1e-3
    ukf_beta = 2.0
    ukf_kappa = 0.0
    gate_probability = 0.999         # NIS gate (chi-square probability); 0 turns gating off
    divergence_epochs = 20           # consecutive epochs beyond the gate that flag a divergence

    [montecarlo]
    runs = 100
    seed = 2014

Motion models: ``constant-acceleration`` is ``Phi = exp(A dt)`` of the full position-velocity-acceleration
chain (the thesis' EKF, Figure 21); ``listing`` is the transition of the thesis' UKF listing (Appendix B),
which advances the position by the velocity and leaves velocity and acceleration unchanged (the
acceleration states are carried but do not drive the motion); ``constant-velocity`` is the 4-state CV model
(state ``[X, Y, u, v]``; initial state, sigma and process noise then have four entries).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Literal, TypeAlias

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.config.builtin import builtin_folder, builtin_names, resolve_scenario
from oceanloc.config.toml_fields import Table
from oceanloc.errors import ConfigError
from oceanloc.models.measurements import MEASUREMENT_KINDS, MeasurementKind
from oceanloc.models.motion import LinearMotionModel, constant_acceleration, constant_velocity
from oceanloc.units import DEG

MotionKind: TypeAlias = Literal["constant-acceleration", "listing", "constant-velocity"]
MOTION_KINDS: tuple[str, ...] = ("constant-acceleration", "listing", "constant-velocity")
NodeLayout: TypeAlias = Literal["ring", "y", "fixed"]
TargetMotion: TypeAlias = Literal["straight", "stop-and-go"]


@dataclass(frozen=True, slots=True, kw_only=True)
class NodeSettings:
    """Where the sensor nodes are (see the module docstring)."""

    layout: NodeLayout
    count: int
    radius_m: float
    drift_speed_mps: float
    phase_rad: float
    center_m: FloatArray
    positions_m: FloatArray | None = None


@dataclass(frozen=True, slots=True, kw_only=True)
class TargetSettings:
    """How the target moves."""

    motion: TargetMotion
    start_m: FloatArray
    velocity_mps: FloatArray
    half_width_m: float = 2.0
    speed_mps: float = 0.5
    mean_pause_s: float = 10.0


@dataclass(frozen=True, slots=True, kw_only=True)
class FilterSettings:
    """The filters' prior, noise model, motion models and UKF parameters."""

    initial_state: FloatArray
    initial_cov: FloatArray
    process_noise: FloatArray
    measurement_sigma: float
    ekf_motion: MotionKind
    ukf_motion: MotionKind
    ukf_alpha: float
    ukf_beta: float
    ukf_kappa: float
    gate_probability: float = 0.999
    divergence_epochs: int = 20

    def motion_model(self, kind: MotionKind, dt_s: float) -> LinearMotionModel:
        """The transition of ``kind`` at step ``dt_s`` with this scenario's ``Q``."""
        return motion_model(kind, dt_s, self.process_noise)


@dataclass(frozen=True, slots=True, kw_only=True)
class FlockScenario:
    """A validated flock-tracking scenario."""

    name: str
    description: str
    dt_s: float
    duration_s: float
    nodes: NodeSettings
    target: TargetSettings
    kind: MeasurementKind
    sigma_true: float
    sound_speed_mps: float
    pairs: str
    filters: FilterSettings
    runs: int
    seed: int

    @property
    def epochs(self) -> int:
        return round(self.duration_s / self.dt_s)

    def with_overrides(self, **changes: object) -> FlockScenario:
        """A copy with top-level fields replaced (e.g. ``runs``, ``duration_s``, ``seed``)."""
        return dataclasses.replace(self, **changes)  # type: ignore[arg-type]


def motion_model(kind: MotionKind, dt_s: float, process_noise: FloatArray) -> LinearMotionModel:
    """Transition matrix of a named motion model with a given per-step ``Q``."""
    q = np.asarray(process_noise, dtype=float)
    if kind == "constant-acceleration":
        return constant_acceleration(dt_s).with_process_noise(q)
    if kind == "constant-velocity":
        return constant_velocity(dt_s).with_process_noise(q)
    if kind == "listing":
        f = np.eye(6)
        f[0, 2] = f[1, 3] = dt_s
        return LinearMotionModel(transition=f, process_noise=q, dt_s=dt_s)
    raise ConfigError(f"motion model must be one of {', '.join(MOTION_KINDS)}; got {kind!r}")


def builtin_flock_scenarios() -> list[str]:
    """Names of the flock scenarios shipped with oceanloc."""
    return builtin_names("flock")


def load_flock_scenario(name_or_path: str | Path) -> FlockScenario:
    """Load a built-in flock scenario by name or a scenario TOML file by path."""
    root, _ = resolve_scenario(name_or_path, "flock")
    return flock_scenario_from_table(root)


def flock_scenario_toml(name_or_path: str | Path) -> str:
    """The TOML text of a built-in flock scenario or a scenario file (for the provenance's hash)."""
    path = Path(name_or_path)
    if path.suffix == ".toml" or path.exists():
        try:
            return path.read_text(encoding="utf-8")
        except OSError as exc:
            raise ConfigError(f"{path}: cannot read ({exc.strerror or exc})") from None
    load_flock_scenario(name_or_path)  # a ConfigError listing the built-in names if there is none
    return builtin_folder("flock").joinpath(f"{name_or_path}.toml").read_text(encoding="utf-8")


def _nodes(t: Table) -> NodeSettings:
    layout = t.str("layout", choices=("ring", "y", "fixed"))
    center = t.vector("center_m", 2, [0.0, 0.0])
    positions = None
    count = 3
    if layout == "ring":
        count = t.int("count", 4, lo=2, hi=1000)
    if layout == "fixed":
        flat = t.vector("positions_m")
        if flat.size < 4 or flat.size % 2:
            raise t.error("positions_m", f"needs x, y pairs of at least two nodes, got {flat.size} numbers")
        positions = flat.reshape(-1, 2)
        count = positions.shape[0]
    radius = t.float("radius_m", 100.0, lo=0.0, lo_open=True) if layout != "fixed" else 0.0
    drift = t.float("drift_speed_mps", 0.0, lo=-100.0, hi=100.0) if layout == "ring" else 0.0
    phase = t.float("phase_deg", 45.0 if layout == "ring" else 90.0, lo=-360.0, hi=360.0) * DEG
    t.check_unknown()
    return NodeSettings(
        layout=layout,  # type: ignore[arg-type]
        count=count,
        radius_m=radius,
        drift_speed_mps=drift,
        phase_rad=phase,
        center_m=center,
        positions_m=positions,
    )


def _target(t: Table) -> TargetSettings:
    motion = t.str("motion", choices=("straight", "stop-and-go"))
    start = t.vector("start_m", 2)
    if motion == "straight":
        settings = TargetSettings(motion="straight", start_m=start, velocity_mps=t.vector("velocity_mps", 2))
    else:
        settings = TargetSettings(
            motion="stop-and-go",
            start_m=start,
            velocity_mps=np.zeros(2),
            half_width_m=t.float("half_width_m", 2.0, lo=0.0, lo_open=True),
            speed_mps=t.float("speed_mps", 0.5, lo=0.0, lo_open=True, hi=100.0),
            mean_pause_s=t.float("mean_pause_s", 10.0, lo=0.0, lo_open=True),
        )
    t.check_unknown()
    return settings


def _filters(t: Table) -> FilterSettings:
    ekf_motion = t.str("ekf_motion", "constant-acceleration", choices=MOTION_KINDS)
    ukf_motion = t.str("ukf_motion", "constant-acceleration", choices=MOTION_KINDS)
    n = 4 if "constant-velocity" in (ekf_motion, ukf_motion) else 6
    if n == 4 and ekf_motion != ukf_motion:
        raise t.error("ukf_motion", "constant-velocity (4 states) cannot be mixed with a 6-state model")
    x0 = t.vector("initial_state", n)
    sig0 = t.vector("initial_sigma", n, positive=True)
    q = t.vector("process_noise", n)
    if np.any(q < 0):
        raise t.error("process_noise", f"variances must be non-negative, got {q.tolist()}")
    settings = FilterSettings(
        initial_state=x0,
        initial_cov=np.diag(sig0**2),
        process_noise=np.diag(q),
        measurement_sigma=t.float("measurement_sigma", lo=0.0, lo_open=True),
        ekf_motion=ekf_motion,  # type: ignore[arg-type]
        ukf_motion=ukf_motion,  # type: ignore[arg-type]
        ukf_alpha=t.float("ukf_alpha", 1e-3, lo=0.0, lo_open=True, hi=1.0),
        ukf_beta=t.float("ukf_beta", 2.0, lo=0.0),
        ukf_kappa=t.float("ukf_kappa", 0.0, lo=-float(n) + 1e-9),
        gate_probability=t.float("gate_probability", 0.999, lo=0.0, hi=1.0, hi_open=True),
        divergence_epochs=t.int("divergence_epochs", 20, lo=1, hi=1_000_000),
    )
    t.check_unknown()
    return settings


def flock_scenario_from_table(root: Table) -> FlockScenario:
    """Validate a parsed flock scenario; every error names the file, table and field."""
    head = root.table("scenario")
    name = head.str("name")
    description = head.str("description", "")
    dt = head.float("dt_s", lo=0.0, lo_open=True, hi=3600.0)
    duration = head.float("duration_s", lo=dt, hi=1e7)
    if duration / dt > 10_000_000:
        raise head.error("duration_s", f"more than 10 million steps of {dt} s")
    head.check_unknown()

    nodes = _nodes(root.table("nodes"))
    target = _target(root.table("target"))

    meas = root.table("measurement")
    kind = meas.str("kind", choices=MEASUREMENT_KINDS)
    sigma_true = meas.float("sigma_true", lo=0.0)
    sound_speed = meas.float("sound_speed_mps", 1500.0, lo=1000.0, hi=2000.0)
    pairs = meas.str("pairs", "all", choices=("all", "reference"))
    meas.check_unknown()
    if kind == "tdoa" and nodes.count < 2:
        raise meas.error("kind", "TDOA needs at least two nodes")

    filters = _filters(root.table("filters"))

    mc = root.table("montecarlo", required=False)
    runs = mc.int("runs", 100, lo=1, hi=1_000_000)
    seed = mc.int("seed", 0, lo=0)
    mc.check_unknown()
    root.check_unknown()
    return FlockScenario(
        name=name,
        description=description,
        dt_s=dt,
        duration_s=duration,
        nodes=nodes,
        target=target,
        kind=kind,  # type: ignore[arg-type]
        sigma_true=sigma_true,
        sound_speed_mps=sound_speed,
        pairs=pairs,
        filters=filters,
        runs=runs,
        seed=seed,
    )
