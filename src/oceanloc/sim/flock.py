"""Flock-tracking simulation: drifting sensor nodes, target trajectories and noisy measurements.

Scenario builders for the AquaQuad thesis:

- :func:`ring_drift_nodes` and :func:`straight_target`: Chapter III.E (four nodes drifting slowly on a circle
  around a target that starts at the centre and moves outward, Figure 25);
- :func:`y_nodes` and :func:`stop_and_go_target`: Chapter V.C (three nodes in a Y around a target that moves
  at random, stopping and starting, inside the lab's 8 m x 8 m Vicon volume).

Everything is vectorized over Monte Carlo runs; every random draw takes the caller's generator(s), one per
run (:func:`oceanloc._random.run_generators`), so a run's draws do not depend on how runs are batched.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from oceanloc._random import BatchRng, run_generators, standard_normal, uniform
from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.config.flock import FlockScenario
from oceanloc.errors import ConfigError
from oceanloc.estimation.tracking import FlockSensorModel
from oceanloc.io.wav import EXAMPLE_FILES, write_wav
from oceanloc.models.measurements import wrap_angle_rad


def epoch_times(dt_s: float, duration_s: float) -> FloatArray:
    """Measurement times ``t_k = k dt``, ``k = 1 .. round(duration / dt)`` (``t_0 = 0`` is the prior)."""
    if not (dt_s > 0 and duration_s >= dt_s):
        raise ConfigError(f"need 0 < dt <= duration; got dt={dt_s}, duration={duration_s}")
    return dt_s * np.arange(1, round(duration_s / dt_s) + 1)


def ring_drift_nodes(
    times_s: ArrayLike,
    n_nodes: int,
    radius_m: float,
    drift_speed_mps: float,
    *,
    center_m: ArrayLike = (0.0, 0.0),
    phase_rad: float = np.pi / 4,
) -> FloatArray:
    """Nodes evenly spaced on a circle, drifting along it (counter-clockwise for positive speed).

    Parameters
    ----------
    times_s : (T,) float
    n_nodes : int
    radius_m : float
    drift_speed_mps : float
        Speed along the circle, m/s.
    center_m : (2,) float
    phase_rad : float
        Angle of node 0 at ``t = 0``.

    Returns
    -------
    (T, N, 2) float
    """
    t = np.asarray(times_s, dtype=float)
    angles = phase_rad + 2 * np.pi * np.arange(n_nodes) / n_nodes + (drift_speed_mps / radius_m) * t[:, None]
    return np.asarray(center_m, dtype=float) + radius_m * np.stack([np.cos(angles), np.sin(angles)], axis=-1)


def y_nodes(
    radius_m: float, *, center_m: ArrayLike = (0.0, 0.0), heading_rad: float = np.pi / 2
) -> FloatArray:
    """Three nodes in a Y (120 degrees apart) around a centre, one on ``heading_rad``; ``(3, 2)``."""
    a = heading_rad + 2 * np.pi * np.arange(3) / 3
    return np.asarray(center_m, dtype=float) + radius_m * np.stack([np.cos(a), np.sin(a)], axis=-1)


def straight_target(times_s: ArrayLike, start_m: ArrayLike, velocity_mps: ArrayLike) -> FloatArray:
    """Constant-velocity truth in the 6-state layout ``[X, Y, u, v, ax, ay]`` (accelerations zero).

    Returns
    -------
    (T, 6) float
    """
    t = np.asarray(times_s, dtype=float)[:, None]
    v = np.asarray(velocity_mps, dtype=float)
    pos = np.asarray(start_m, dtype=float) + v * t
    return np.concatenate([pos, np.broadcast_to(v, pos.shape), np.zeros_like(pos)], axis=-1)


def stop_and_go_target(
    times_s: ArrayLike,
    start_m: ArrayLike,
    rng: BatchRng,
    runs: int,
    *,
    half_width_m: float,
    speed_mps: float,
    mean_pause_s: float,
    smoothing_s: float = 0.5,
) -> FloatArray:
    """Random stop-and-go motion: pause, walk straight to a random waypoint, pause, ...

    A person carrying the target in the thesis' lab test (Figure 61) walks between spots and stands still.
    Waypoints are uniform in the square ``[-w, w]^2``, pauses exponential with mean ``mean_pause_s``, walking
    at ``speed_mps``. Velocity is low-pass filtered (time constant ``smoothing_s``) so that starts and stops
    are not instantaneous; velocity and acceleration of the 6-state follow from finite differences.

    Parameters
    ----------
    times_s : (T,) float
        Equally spaced times.
    start_m : (2,) float
    rng : Generator or sequence of ``runs`` generators
    runs : int

    Returns
    -------
    (runs, T, 6) float
    """
    t = np.asarray(times_s, dtype=float)
    dt = float(t[1] - t[0]) if t.size > 1 else 1.0
    n_legs = int(np.ceil((t[-1] - t[0] + dt) / max(mean_pause_s, 1e-3))) + 4
    waypoints = half_width_m * (2 * uniform(rng, runs, (n_legs, 2)) - 1)
    pauses = -mean_pause_s * np.log1p(-uniform(rng, runs, (n_legs,)))
    pos = np.tile(np.asarray(start_m, dtype=float), (runs, 1))
    vel = np.zeros((runs, 2))
    leg = np.zeros(runs, dtype=np.int64)
    pause_left = pauses[:, 0].copy()
    out = np.empty((runs, t.size, 6))
    alpha = dt / (smoothing_s + dt)
    rows = np.arange(runs)
    for k in range(t.size):
        target = waypoints[rows, np.minimum(leg, n_legs - 1)]
        to_go = target - pos
        dist = np.linalg.norm(to_go, axis=-1)
        walking = pause_left <= 0
        arrived = walking & (dist < speed_mps * dt)
        leg = np.where(arrived, leg + 1, leg)
        pause_left = np.where(arrived, pauses[rows, np.minimum(leg, n_legs - 1)], pause_left - dt)
        direction = np.divide(to_go, dist[:, None], out=np.zeros_like(to_go), where=dist[:, None] > 0)
        wanted = np.where((walking & ~arrived)[:, None], speed_mps * direction, 0.0)
        new_vel = vel + alpha * (wanted - vel)
        acc = (new_vel - vel) / dt
        vel = new_vel
        pos = pos + vel * dt
        out[:, k, :2] = pos
        out[:, k, 2:4] = vel
        out[:, k, 4:] = acc
    return out


def simulate_measurements(
    sensor_model: FlockSensorModel,
    truth: ArrayLike,
    sensors_m: ArrayLike,
    sigma_true: float | ArrayLike,
    rng: BatchRng,
    *,
    dropout_probability: float = 0.0,
) -> FloatArray:
    """Noisy measurements ``z = h(x) + v`` of ``B`` runs, with optional random dropouts (``NaN``).

    Parameters
    ----------
    sensor_model : FlockSensorModel
        Measurement kind, pairs and sound speed (its ``R`` is the filter's; the truth uses ``sigma_true``).
    truth : (B, T, n) or (T, n) float
        True states; a 2-D truth is shared by all runs.
    sensors_m : (T, N, 2) or (B, T, N, 2) float
    sigma_true : float or (m,) float
        Standard deviation of the simulated noise (rad, m or s).
    rng : Generator or sequence of B generators
        The batch size ``B`` is ``len(rng)`` for a sequence, else the truth's first axis.
    dropout_probability : float
        Probability that a measurement is missing.

    Returns
    -------
    (B, T, m) float
        Bearings are wrapped to ``(-pi, pi]``.
    """
    x = np.asarray(truth, dtype=float)
    batch = len(rng) if isinstance(rng, Sequence) else (x.shape[0] if x.ndim == 3 else 1)
    clean = sensor_model.measure(x, sensors_m)
    clean = np.broadcast_to(clean, (batch, *clean.shape[-2:]))
    noise = standard_normal(rng, batch, clean.shape[1:])
    z = clean + np.asarray(sigma_true, dtype=float) * noise
    if sensor_model.kind == "bearing":
        z = wrap_angle_rad(z)
    if dropout_probability > 0:
        z = np.where(uniform(rng, batch, clean.shape[1:]) < dropout_probability, np.nan, z)
    return z


def scenario_nodes(scenario: FlockScenario, times_s: ArrayLike) -> FloatArray:
    """Node positions of a scenario at the given times, ``(T, N, 2)``."""
    t = np.asarray(times_s, dtype=float)
    nodes = scenario.nodes
    if nodes.layout == "ring":
        return ring_drift_nodes(
            t,
            nodes.count,
            nodes.radius_m,
            nodes.drift_speed_mps,
            center_m=nodes.center_m,
            phase_rad=nodes.phase_rad,
        )
    if nodes.layout == "y":
        fixed = y_nodes(nodes.radius_m, center_m=nodes.center_m, heading_rad=nodes.phase_rad)
    else:
        assert nodes.positions_m is not None
        fixed = nodes.positions_m
    return np.broadcast_to(fixed, (t.size, *fixed.shape)).copy()


def scenario_truth(scenario: FlockScenario, times_s: ArrayLike, rng: BatchRng, runs: int) -> FloatArray:
    """True 6-state trajectories: ``(T, 6)`` shared by all runs (straight) or ``(runs, T, 6)``."""
    t = np.asarray(times_s, dtype=float)
    target = scenario.target
    if target.motion == "straight":
        return straight_target(t, target.start_m, target.velocity_mps)
    return stop_and_go_target(
        t,
        target.start_m,
        rng,
        runs,
        half_width_m=target.half_width_m,
        speed_mps=target.speed_mps,
        mean_pause_s=target.mean_pause_s,
    )


def scenario_sensor_model(scenario: FlockScenario) -> FlockSensorModel:
    """The filters' measurement model: the scenario's kind, pairs and sound speed with ``R = sigma^2 I``."""
    return FlockSensorModel.build(
        scenario.kind,
        scenario.nodes.count,
        scenario.filters.measurement_sigma,
        pairs=scenario.pairs,
        sound_speed_mps=scenario.sound_speed_mps,
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class FlockSimulation:
    """Simulated runs of a scenario.

    Attributes
    ----------
    times_s : (T,) float
    nodes_m : (T, N, 2) float
    truth : (T, 6) or (R, T, 6) float
        Shared by all runs for a straight target.
    sensor_model : FlockSensorModel
        The filters' measurement model.
    clean : (R, T, m) or (T, m) float
        Noise-free measurements.
    measurements : (R, T, m) float
        Noisy measurements.
    """

    times_s: FloatArray
    nodes_m: FloatArray
    truth: FloatArray
    sensor_model: FlockSensorModel
    clean: FloatArray
    measurements: FloatArray


def simulate_scenario(scenario: FlockScenario, run_indices: ArrayLike) -> FlockSimulation:
    """Simulate the given Monte Carlo runs of a scenario (each run from its own ``(seed, run)`` generator)."""
    runs = np.asarray(run_indices)
    times = epoch_times(scenario.dt_s, scenario.duration_s)
    rngs = run_generators(scenario.seed, runs)
    nodes = scenario_nodes(scenario, times)
    truth = scenario_truth(scenario, times, rngs, runs.size)
    model = scenario_sensor_model(scenario)
    return FlockSimulation(
        times_s=times,
        nodes_m=nodes,
        truth=truth,
        sensor_model=model,
        clean=model.measure(truth, nodes),
        measurements=simulate_measurements(model, truth, nodes, scenario.sigma_true, rngs),
    )


EXAMPLE_RATE_HZ = 16_000
EXAMPLE_DELAY_S = 1.2345e-3
"""Arrival at hydrophone A minus arrival at B in the shipped sample pair (19.752 samples at 16 kHz)."""


def sweep_recordings(
    *,
    sample_rate_hz: int = EXAMPLE_RATE_HZ,
    delay_s: float = EXAMPLE_DELAY_S,
    duration_s: float = 0.5,
    onset_s: float = 0.1,
    sweep_s: float = 0.05,
    band_hz: tuple[float, float] = (1000.0, 6000.0),
    echo_delay_s: float = 4e-3,
    echo_gain: float = 0.4,
    snr_db: float = 20.0,
    seed: int = 2014,
) -> tuple[FloatArray, FloatArray]:
    """Two hydrophone recordings of one up-sweep (thesis Chapter II.E.3, Figures 16-17), ``(n,)`` each.

    A Hann-tapered linear sweep over ``band_hz`` arrives at B at ``onset_s`` and at A ``delay_s`` later (a
    fractional delay applied in the frequency domain, exact for the band-limited sweep); A also hears a
    surface echo ``echo_delay_s`` after its direct arrival, ``echo_gain`` as strong. White noise at
    ``snr_db`` (relative to the sweep's power) from ``numpy.random.default_rng(seed)``. Peak amplitude 0.5.
    """
    n = round(duration_s * sample_rate_hz)
    t = np.arange(round(sweep_s * sample_rate_hz)) / sample_rate_hz
    f0, f1 = band_hz
    sweep = np.sin(2 * np.pi * (f0 * t + 0.5 * (f1 - f0) / sweep_s * t**2)) * np.hanning(t.size)
    base = np.zeros(n)
    start = round(onset_s * sample_rate_hz)
    base[start : start + t.size] = sweep
    freqs = np.fft.rfftfreq(n, 1.0 / sample_rate_hz)
    spectrum = np.fft.rfft(base)

    def shifted(delay: float) -> FloatArray:
        return np.fft.irfft(spectrum * np.exp(-2j * np.pi * freqs * delay), n)

    b = base
    a = shifted(delay_s) + echo_gain * shifted(delay_s + echo_delay_s)
    rng = np.random.default_rng(seed)
    noise_sd = np.sqrt(np.mean(sweep**2) * 10 ** (-snr_db / 10))
    a = a + noise_sd * rng.standard_normal(n)
    b = b + noise_sd * rng.standard_normal(n)
    scale = 0.5 / max(np.max(np.abs(a)), np.max(np.abs(b)))
    return scale * a, scale * b


def write_example_recordings(folder: str | Path) -> tuple[Path, Path]:
    """Write :func:`sweep_recordings` (defaults) as the 16-bit PCM pair shipped in ``oceanloc/data``."""
    a, b = sweep_recordings()
    out = Path(folder)
    return (
        write_wav(out / EXAMPLE_FILES[0], a, EXAMPLE_RATE_HZ),
        write_wav(out / EXAMPLE_FILES[1], b, EXAMPLE_RATE_HZ),
    )
