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

Physical ranges: every field is checked against a range a real flock can have (positions within 1000 km,
speeds up to 100 m/s, accelerations up to 100 m/s^2, prior sigmas from 1 um to 1000 km, measurement sigmas
from a picosecond, a nanoradian or a micrometre up to a second, pi rad or 10 km, ``dt`` from 1 us to an
hour, at most 10 million steps), so that a typo gives an error naming file, table, field and range instead
of NaN results or a LinAlgError; and the memory a Monte Carlo would hold (:func:`memory_estimate_bytes`)
is checked before anything is allocated (:func:`check_memory`).

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

MAX_POSITION_M = 1e6
MAX_SPEED_MPS = 100.0
MAX_ACCEL_MPS2 = 100.0
MAX_STEPS = 10_000_000
MEMORY_LIMIT_BYTES = 8 * 2**30
"""Largest Monte Carlo working set a scenario may ask for (8 GiB)."""
SIGMA_RANGE: dict[str, tuple[float, float, str]] = {
    "bearing": (1e-9, np.pi, "rad"),
    "range": (1e-6, 1e4, "m"),
    "tdoa": (1e-12, 1.0, "s"),
}
"""Measurement standard deviations allowed per kind: (lowest, highest, unit)."""

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


def _bounded(t: Table, key: str, values: FloatArray, limits: FloatArray | float, unit: str, lo=None):
    """Every ``|value| <= limit`` (and ``>= lo`` if given), else an error naming the field and range."""
    lim = np.broadcast_to(np.asarray(limits, dtype=float), values.shape)
    bad = np.abs(values) > lim
    if lo is not None:
        bad |= values < np.broadcast_to(np.asarray(lo, dtype=float), values.shape)
    if np.any(bad):
        i = int(np.argmax(bad))
        low = -lim[i] if lo is None else np.broadcast_to(lo, values.shape)[i]
        raise t.error(key, f"entry {i} must be within [{low:g}, {lim[i]:g}] {unit}, got {values[i]:g}")
    return values


def memory_estimate_bytes(epochs: int, runs: int, n_nodes: int, n_meas: int, n_state: int) -> int:
    """Bytes a flock Monte Carlo chunk of ``runs`` holds at once (the tracking experiment, the larger).

    Per epoch: the node positions and, per run, the truth, clean and noisy measurements, estimates,
    innovations, residuals, HDOP and flags (``3 m + 2 n + 8`` floats), 8 bytes each.
    """
    return int(8 * epochs * (2 * n_nodes + runs * (3 * n_meas + 2 * n_state + 8)))


def check_memory(scenario: FlockScenario, runs_at_once: int | None = None, where: str = "") -> None:
    """Raise a ConfigError if the Monte Carlo would hold more than :data:`MEMORY_LIMIT_BYTES`."""
    sc = scenario
    runs = max(1, -(-sc.runs // 2)) if runs_at_once is None else runs_at_once
    n_meas = sc.nodes.count * (sc.nodes.count - 1) // 2 if sc.kind == "tdoa" else sc.nodes.count
    if sc.kind == "tdoa" and sc.pairs == "reference":
        n_meas = sc.nodes.count - 1
    need = memory_estimate_bytes(sc.epochs, runs, sc.nodes.count, n_meas, sc.filters.initial_state.size)
    if need > MEMORY_LIMIT_BYTES:
        raise ConfigError(
            f"{where or sc.name}: {sc.epochs} epochs x {runs} run(s) at once need about"
            f" {need / 2**30:.1f} GiB (limit {MEMORY_LIMIT_BYTES / 2**30:.0f} GiB); use a longer dt_s,"
            " a shorter duration_s, fewer nodes or fewer runs"
        )


def _nodes(t: Table) -> NodeSettings:
    layout = t.str("layout", choices=("ring", "y", "fixed"))
    center = _bounded(t, "center_m", t.vector("center_m", 2, [0.0, 0.0]), MAX_POSITION_M, "m")
    positions = None
    count = 3
    if layout == "ring":
        count = t.int("count", 4, lo=2, hi=1000)
    if layout == "fixed":
        flat = t.vector("positions_m")
        if flat.size < 4 or flat.size % 2:
            raise t.error("positions_m", f"needs x, y pairs of at least two nodes, got {flat.size} numbers")
        _bounded(t, "positions_m", flat, MAX_POSITION_M, "m")
        positions = flat.reshape(-1, 2)
        count = positions.shape[0]
        if count > 1000:
            raise t.error("positions_m", f"at most 1000 nodes, got {count}")
        gaps = np.linalg.norm(positions[:, None] - positions[None], axis=-1) + np.diag(np.full(count, np.inf))
        if gaps.min() < 1e-3:
            i, j = np.unravel_index(int(np.argmin(gaps)), gaps.shape)
            raise t.error(
                "positions_m", f"nodes {i} and {j} are less than 1 mm apart (they must be distinct)"
            )
    radius = t.float("radius_m", 100.0, lo=1e-3, hi=MAX_POSITION_M) if layout != "fixed" else 0.0
    drift = t.float("drift_speed_mps", 0.0, lo=-MAX_SPEED_MPS, hi=MAX_SPEED_MPS) if layout == "ring" else 0.0
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
    start = _bounded(t, "start_m", t.vector("start_m", 2), MAX_POSITION_M, "m")
    if motion == "straight":
        velocity = _bounded(t, "velocity_mps", t.vector("velocity_mps", 2), MAX_SPEED_MPS, "m/s")
        settings = TargetSettings(motion="straight", start_m=start, velocity_mps=velocity)
    else:
        settings = TargetSettings(
            motion="stop-and-go",
            start_m=start,
            velocity_mps=np.zeros(2),
            half_width_m=t.float("half_width_m", 2.0, lo=1e-3, hi=1e5),
            speed_mps=t.float("speed_mps", 0.5, lo=1e-3, hi=MAX_SPEED_MPS),
            mean_pause_s=t.float("mean_pause_s", 10.0, lo=1e-3, hi=1e6),
        )
    t.check_unknown()
    return settings


def _filters(t: Table, kind: str) -> FilterSettings:
    sig_lo, sig_hi_m, _unit = SIGMA_RANGE[kind]
    ekf_motion = t.str("ekf_motion", "constant-acceleration", choices=MOTION_KINDS)
    ukf_motion = t.str("ukf_motion", "constant-acceleration", choices=MOTION_KINDS)
    n = 4 if "constant-velocity" in (ekf_motion, ukf_motion) else 6
    if n == 4 and ekf_motion != ukf_motion:
        raise t.error("ukf_motion", "constant-velocity (4 states) cannot be mixed with a 6-state model")
    kin = np.array(
        [MAX_POSITION_M, MAX_POSITION_M, MAX_SPEED_MPS, MAX_SPEED_MPS, MAX_ACCEL_MPS2, MAX_ACCEL_MPS2]
    )
    units = "m, m/s, m/s^2 (x, y, u, v, ax, ay)"
    x0 = _bounded(t, "initial_state", t.vector("initial_state", n), kin[:n], units)
    # Prior sigmas from 1 um (or um/s, um/s^2) to 1000 km (1000 m/s, 1000 m/s^2): their squares stay
    # normal floats and the filters' covariances invertible.
    sig_hi = np.array([1e6, 1e6, 1e3, 1e3, 1e3, 1e3])[:n]
    sig0 = _bounded(t, "initial_sigma", t.vector("initial_sigma", n), sig_hi, units, lo=1e-6)
    q_hi = np.array([1e6, 1e6, 1e4, 1e4, 1e4, 1e4])[:n]
    q = _bounded(t, "process_noise", t.vector("process_noise", n), q_hi, "m^2, (m/s)^2, (m/s^2)^2", lo=0.0)
    settings = FilterSettings(
        initial_state=x0,
        initial_cov=np.diag(sig0**2),
        process_noise=np.diag(q),
        measurement_sigma=t.float("measurement_sigma", lo=sig_lo, hi=sig_hi_m),
        ekf_motion=ekf_motion,  # type: ignore[arg-type]
        ukf_motion=ukf_motion,  # type: ignore[arg-type]
        ukf_alpha=t.float("ukf_alpha", 1e-3, lo=0.0, lo_open=True, hi=1.0),
        ukf_beta=t.float("ukf_beta", 2.0, lo=0.0, hi=100.0),
        ukf_kappa=t.float("ukf_kappa", 0.0, lo=-float(n) + 1e-9, hi=100.0),
        gate_probability=t.float("gate_probability", 0.999, lo=0.0, hi=1.0, hi_open=True),
        divergence_epochs=t.int("divergence_epochs", 20, lo=1, hi=1_000_000),
    )
    t.check_unknown()
    return settings


def flock_scenario_from_table(root: Table) -> FlockScenario:
    """Validate a parsed flock scenario; every error names the file, table and field."""
    head = root.table("scenario")
    name = head.str("name")
    if not name.strip():
        raise head.error("name", "must not be empty")
    description = head.str("description", "")
    dt = head.float("dt_s", lo=1e-6, hi=3600.0)
    duration = head.float("duration_s", lo=dt, hi=1e7)
    if duration / dt > MAX_STEPS:
        raise head.error(
            "duration_s",
            f"{duration / dt:.3g} steps of {dt} s; at most {MAX_STEPS:,} (raise dt_s or shorten it)",
        )
    head.check_unknown()

    nodes = _nodes(root.table("nodes"))
    target = _target(root.table("target"))

    meas = root.table("measurement")
    kind = meas.str("kind", choices=MEASUREMENT_KINDS)
    hi_sig = SIGMA_RANGE[kind][1]
    sigma_true = meas.float("sigma_true", lo=0.0, hi=hi_sig)
    sound_speed = meas.float("sound_speed_mps", 1500.0, lo=1000.0, hi=2000.0)
    pairs = meas.str("pairs", "all", choices=("all", "reference"))
    meas.check_unknown()
    if kind == "tdoa" and nodes.count < 2:
        raise meas.error("kind", "TDOA needs at least two nodes")

    filters = _filters(root.table("filters"), kind)

    mc = root.table("montecarlo", required=False)
    runs = mc.int("runs", 100, lo=1, hi=1_000_000)
    seed = mc.int("seed", 0, lo=0, hi=2**63 - 1)
    mc.check_unknown()
    root.check_unknown()
    scenario = FlockScenario(
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
    # One run must fit (the step, the duration and the node count); the Monte Carlo checks its chunks.
    check_memory(scenario, 1, where=f"{root.source}: [scenario] field 'dt_s'")
    return scenario
