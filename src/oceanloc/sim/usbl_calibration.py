"""Synthetic USBL calibration surveys: a head with a hidden misalignment pinging a seabed beacon.

:class:`UsblTruth` holds what the calibration must find (beacon positions, misalignment, lever arm,
sound-speed scale, turn-around delay, range bias). :func:`simulate_pings` takes the vessel's true track
(positions and headings per ping) and draws, per ping and in this order from each run's generator:
the vessel's roll and pitch (sea state: Gaussian, ``sway_rad``), the range noise, the two direction
noises (isotropic on the sphere: elevation ``sigma``, azimuth ``sigma / cos el``), then the recorded
antenna position's and attitude's errors (GNSS and attitude noise). The measurements come from the true
pose; the pings record the noisy pose, as a real log does, so the estimator meets the GNSS and attitude
noise it folds.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from oceanloc._random import BatchRng, standard_normal
from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.errors import ConfigError
from oceanloc.estimation.usbl_calibration import (
    CalibrationOptions,
    UsblNoise,
    UsblPings,
    beacon_block,
    calibration_layout,
)
from oceanloc.models.usbl import DEFAULT_SOUND_SPEED_MPS, usbl_direction_rad, usbl_range_m
from oceanloc.units import DEG


@dataclass(frozen=True, slots=True, kw_only=True)
class UsblTruth:
    """The hidden values of a simulated calibration.

    Attributes
    ----------
    beacon_ids : (M,) int
    beacon_enu_m : (M, 3) float
    misalignment_rad : (3,) float
        Head roll, pitch, heading in the vessel frame.
    lever_arm_m : (3,) float
    scale : float
    delay_s : float
    bias_m : float
    """

    beacon_ids: FloatArray
    beacon_enu_m: FloatArray
    misalignment_rad: FloatArray = field(default_factory=lambda: np.array([1.0, -0.7, 2.0]) * DEG)
    lever_arm_m: FloatArray = field(default_factory=lambda: np.array([0.3, -0.1, 0.6]))
    scale: float = 1.003
    delay_s: float = 2e-4
    bias_m: float = 0.0

    def state(self, options: CalibrationOptions) -> FloatArray:
        """The truth as a state vector ``(d,)`` in the order of
        :func:`~oceanloc.estimation.usbl_calibration.calibration_layout`."""
        layout = calibration_layout(self.beacon_ids, options)
        x = np.zeros(layout.dim)
        for i, b in enumerate(np.asarray(self.beacon_ids)):
            x[layout.index(beacon_block(int(b)))] = self.beacon_enu_m[i]
        x[layout.index("misalignment")] = self.misalignment_rad
        x[layout.index("lever_arm")] = self.lever_arm_m
        x[layout.index("scale")] = self.scale
        if "delay" in layout.names:
            x[layout.index("delay")] = self.delay_s
        if "bias" in layout.names:
            x[layout.index("bias")] = self.bias_m
        return x


def simulate_pings(
    pos_enu_m: ArrayLike,
    heading_rad: ArrayLike,
    beacon: ArrayLike,
    truth: UsblTruth,
    noise: UsblNoise,
    rng: BatchRng,
    *,
    batch: int | None = None,
    sway_rad: tuple[float, float] = (1.0 * DEG, 0.5 * DEG),
    t_s: ArrayLike | None = None,
    sound_speed_mps: float = DEFAULT_SOUND_SPEED_MPS,
) -> UsblPings:
    """Pings of ``B`` runs along true tracks (module docstring).

    Parameters
    ----------
    pos_enu_m : (n, 3) or (B, n, 3) float
        True vessel reference (antenna) positions at the pings.
    heading_rad : (n,) or (B, n) float
        True headings, clockwise from north.
    beacon : (n,) int
        Beacon pinged at each ping.
    truth : UsblTruth
    noise : UsblNoise
    rng : Generator or sequence of B generators
    batch : int, optional
        Number of runs when the track has no batch axis (default: one per generator, or 1).
    sway_rad : (roll, pitch)
        Standard deviations of the vessel's roll and pitch at the pings.
    t_s : (n,) float, optional
    sound_speed_mps : float
        The configured ``c_0``.
    """
    pos = np.asarray(pos_enu_m, dtype=float)
    hdg = np.asarray(heading_rad, dtype=float)
    ids = np.asarray(beacon, dtype=np.int64).ravel()
    n = ids.size
    b = batch or (
        pos.shape[0] if pos.ndim == 3 else (1 if isinstance(rng, np.random.Generator) else len(rng))
    )
    pos = np.broadcast_to(pos, (b, n, 3))
    hdg = np.broadcast_to(hdg, (b, n))
    known = {int(i): k for k, i in enumerate(np.asarray(truth.beacon_ids).ravel())}
    if any(int(i) not in known for i in np.unique(ids)):
        raise ConfigError(f"pings to beacons {sorted(set(ids.tolist()) - set(known))} not in the truth")
    target = np.asarray(truth.beacon_enu_m, dtype=float)[[known[int(i)] for i in ids]]  # (n, 3)
    sway = standard_normal(rng, b, (n, 2)) * np.asarray(sway_rad)
    att = np.stack([sway[..., 0], sway[..., 1], hdg], axis=-1)
    draws = standard_normal(rng, b, (n, 3))
    rng_true = usbl_range_m(
        target, pos, att, truth.lever_arm_m, truth.scale, truth.delay_s, truth.bias_m, sound_speed_mps
    )
    dirs = usbl_direction_rad(target, pos, att, truth.lever_arm_m, truth.misalignment_rad)
    cos_el = np.maximum(np.cos(dirs[..., 1]), noise.min_cos_elevation)
    measured_dir = np.stack(
        [
            dirs[..., 0] + noise.sigma_angle_rad / cos_el * draws[..., 1],
            dirs[..., 1] + noise.sigma_angle_rad * draws[..., 2],
        ],
        axis=-1,
    )
    measured_dir[..., 0] = np.angle(np.exp(1j * measured_dir[..., 0]))
    pose_err = standard_normal(rng, b, (n, 6))
    g = np.array([noise.sigma_horizontal_m, noise.sigma_horizontal_m, noise.sigma_vertical_m])
    a = np.array([noise.sigma_roll_pitch_rad, noise.sigma_roll_pitch_rad, noise.sigma_heading_rad])
    return UsblPings.build(
        beacon=ids,
        antenna_enu_m=pos + pose_err[..., :3] * g,
        attitude_rad=att + pose_err[..., 3:] * a,
        range_m=rng_true + noise.sigma_range_m * draws[..., 0],
        direction_rad=measured_dir,
        t_s=t_s,
    )
