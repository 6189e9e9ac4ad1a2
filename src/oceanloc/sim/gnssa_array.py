"""Synthetic GNSS-A array surveys with a known truth: a platform circling (or holding station over) an
array of seafloor transponders, a GNSS antenna with attitude and a lever arm, travel times ray-traced
through a sound-speed profile whose speed drifts in time, partial replies, GNSS and timing noise.

Travel times are the ray-traced ones (straight leg at the leg's harmonic mean plus the tabulated bending
correction of :func:`~oceanloc.models.sound_profile.bending_table`, within 3e-8 s of the exact layered
ray), scaled by the profile's relative speed change ``1 + drift_ppm_per_h (t - t0) / 3600 s``, plus a
horizontal slowness gradient (:func:`~oceanloc.models.acoustics.gradient_path_m2`). GNSS noise is drawn
with the reported covariances at every transmit and receive instant; the estimator sees the noisy antenna
positions, the true attitude and the nominal lever arm.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.io.gnssa_array import AntennaTrack, GnssaArraySurvey, array_survey_from_track
from oceanloc.models.acoustics import gradient_path_m2
from oceanloc.models.attitude import rotation_enu_from_body, transducer_enu_m
from oceanloc.models.sound_profile import SoundSpeedProfile, bending_table


def example_profile(depth_m: float = 3000.0, n: int = 61) -> SoundSpeedProfile:
    """A warm mixed layer over a thermocline and the deep isothermal gradient (about 1540 m/s at the
    surface, a minimum near 1000 m): an open-ocean shape for tests and examples."""
    z = np.linspace(0.0, depth_m + 200.0, n)
    c = 1485.0 + 0.017 * z + 45.0 * np.exp(-z / 500.0) - 12.0 * np.exp(-(((z - 1000.0) / 600.0) ** 2))
    return SoundSpeedProfile(depth_m=z, speed_mps=c, source="example")


@dataclass(frozen=True, slots=True, kw_only=True)
class ArrayTruth:
    """What generated a synthetic survey."""

    positions_enu_m: FloatArray
    lever_arm_body_m: FloatArray
    drift_ppm_per_h: float
    gradient_per_km: FloatArray
    profile: SoundSpeedProfile


def simulate_gnssa_array(
    rng: np.random.Generator,
    *,
    positions_enu_m: ArrayLike,
    n_pings: int = 600,
    ping_interval_s: float = 15.0,
    pattern: str = "rosette",
    radius_m: float | None = None,
    profile: SoundSpeedProfile | None = None,
    drift_ppm_per_h: float = 0.0,
    gradient_per_km: ArrayLike = (0.0, 0.0),
    lever_arm_body_m: ArrayLike = (0.0, 0.0, 0.0),
    attitude_amplitude_deg: tuple[float, float] = (4.0, 2.0),
    gnss_sigma_enu_m: ArrayLike = (0.02, 0.02, 0.04),
    twtt_sigma_s: float = 2e-5,
    reply_probability: float = 1.0,
    turnaround_s: ArrayLike | None = None,
    surface_m: float = 0.0,
) -> tuple[GnssaArraySurvey, ArrayTruth]:
    """A synthetic array survey and its truth (see the module docstring).

    Parameters
    ----------
    rng : numpy Generator
    positions_enu_m : (J, 3) float
        True transponder positions (U negative: below the surface at ``surface_m``), metres.
    n_pings, ping_interval_s : int, float
    pattern : str
        ``rosette`` (three petals of ``radius_m`` through the array centre, ``rho = R cos 3 theta``: near
        and far pings, every heading), ``circle`` (a circle of ``radius_m`` about the array centre, heading
        along the track: every ping at about one incidence, so depth and sound speed are hard to separate)
        or ``station`` (holding station over the centre, constant heading, small
        wander).
    radius_m : float, optional
        Circle radius (default: the mean depth, 45 deg incidence).
    drift_ppm_per_h : float
        Relative change of the whole profile's speed per hour, ppm.
    gradient_per_km : (2,) float
        Horizontal slowness gradient (east, north) per km.
    lever_arm_body_m : (3,) float
        True antenna-to-transducer lever arm (forward, starboard, down).
    attitude_amplitude_deg : (2,) float
        Roll and pitch amplitudes (sinusoids of 9 s and 7 s), degrees.
    gnss_sigma_enu_m : (3,) float
        Antenna 1-sigma, metres.
    twtt_sigma_s : float
        Travel-time noise, seconds.
    reply_probability : float
        Probability that a transponder answers a ping (at least one answers each ping).
    turnaround_s : (J,) float, optional
        Turn-around delays (default 0.2 s each).
    """
    truth_pos = np.asarray(positions_enu_m, dtype=float).reshape(-1, 3)
    n_t = truth_pos.shape[0]
    prof = profile or example_profile(float(surface_m - truth_pos[:, 2].min()) + 200.0)
    tau = np.full(n_t, 0.2) if turnaround_s is None else np.asarray(turnaround_s, dtype=float)
    lever = np.asarray(lever_arm_body_m, dtype=float)
    grad = 1e-3 * np.asarray(gradient_per_km, dtype=float)
    sig = np.asarray(gnss_sigma_enu_m, dtype=float)
    centre = truth_pos.mean(axis=0)
    depth = float(surface_m - centre[2])
    radius = depth if radius_m is None else float(radius_m)
    duration = n_pings * ping_interval_s
    t_track = np.arange(0.0, duration + 60.0, 1.0)
    if pattern == "circle":
        ang = 2.0 * np.pi * t_track / duration
        east = centre[0] + radius * np.sin(ang)
        north = centre[1] + radius * np.cos(ang)
        heading = np.mod(np.rad2deg(ang) + 90.0, 360.0)
    elif pattern == "rosette":
        theta = np.pi * t_track / duration
        rho = radius * np.cos(3.0 * theta)
        east = centre[0] + rho * np.sin(theta)
        north = centre[1] + rho * np.cos(theta)
        heading = np.mod(np.rad2deg(np.arctan2(np.gradient(east), np.gradient(north))), 360.0)
    elif pattern == "station":
        east = centre[0] + 20.0 * np.sin(2.0 * np.pi * t_track / 1800.0)
        north = centre[1] + 15.0 * np.sin(2.0 * np.pi * t_track / 2300.0)
        heading = np.full(t_track.size, 30.0)
    else:
        raise ValueError(f"pattern {pattern!r} is none of rosette, circle, station")
    heave = 0.3 * np.sin(2.0 * np.pi * t_track / 11.0)
    up = np.full(t_track.size, surface_m + 1.5) + heave
    roll = attitude_amplitude_deg[0] * np.sin(2.0 * np.pi * t_track / 9.0)
    pitch = attitude_amplitude_deg[1] * np.sin(2.0 * np.pi * t_track / 7.0)
    track = AntennaTrack(
        t_s=t_track,
        position_enu_m=np.stack([east, north, up], axis=1),
        covariance_enu_m2=np.broadcast_to(np.diag(sig**2), (t_track.size, 3, 3)).copy(),
        attitude_deg=np.stack([roll, pitch, heading], axis=1),
    )
    t_tx = np.arange(n_pings) * ping_interval_s + 5.0
    answers = rng.random((n_pings, n_t)) < reply_probability
    answers[np.arange(n_pings), rng.integers(0, n_t, n_pings)] = True
    ping, trans = np.nonzero(answers)

    def transducer(t: FloatArray) -> FloatArray:
        pos, _, att = track.at(t)
        return transducer_enu_m(pos, rotation_enu_from_body(att[:, 0], att[:, 1], att[:, 2]), lever)

    a = transducer(t_tx)[ping]
    p = truth_pos[trans]
    tables = {}
    za_all = surface_m - np.concatenate([up - 1.0, up + 4.0])
    for j in range(n_t):
        reach = radius + 100.0 + float(np.max(np.hypot(*(truth_pos[:, :2] - centre[:2]).T)))
        tables[j] = bending_table(
            prof, float(surface_m - truth_pos[j, 2]), (za_all.min(), za_all.max()), 1.3 * reach
        )

    def one_way(leg: FloatArray) -> FloatArray:
        za = surface_m - leg[:, 2]
        zb = surface_m - p[:, 2]
        horiz = np.hypot(leg[:, 0] - p[:, 0], leg[:, 1] - p[:, 1])
        t = np.hypot(horiz, zb - za) * prof.harmonic_slowness_spm(za, zb)
        for j in range(n_t):
            sel = trans == j
            t[sel] += tables[j].correction_s(za[sel], horiz[sel])
        return t

    t_a = one_way(a)
    scale = 1.0 + 1e-6 * drift_ppm_per_h * (t_tx[ping] - t_tx[0]) / 3600.0
    c_ref = float(prof.harmonic_mean_mps(0.0, depth))
    twtt = 2.0 * t_a / scale + tau[trans]
    for _ in range(3):  # the receive instant depends on the travel time
        b = transducer(t_tx[ping] + twtt)
        slow = (t_a + one_way(b)) / scale
        slow += (gradient_path_m2(p, a) + gradient_path_m2(p, b)) @ grad / c_ref
        twtt = slow + tau[trans]
    twtt = twtt + twtt_sigma_s * rng.standard_normal(twtt.size)
    survey = array_survey_from_track(
        name=f"synthetic-{pattern}-{n_t}",
        track=track,
        t_transmit_s=t_tx,
        reply_ping=ping,
        reply_transponder=trans,
        twtt_s=twtt,
        turnaround_s=tau,
        transponder_ids=tuple(f"T{j + 1}" for j in range(n_t)),
        lever_arm_body_m=lever,
        line=np.arange(ping.size) + 1,
    )
    noisy = dataclasses.replace(
        survey,
        transmit_antenna_enu_m=survey.transmit_antenna_enu_m + sig * rng.standard_normal((n_pings, 3)),
        receive_antenna_enu_m=survey.receive_antenna_enu_m + sig * rng.standard_normal((ping.size, 3)),
    )
    truth = ArrayTruth(
        positions_enu_m=truth_pos,
        lever_arm_body_m=lever,
        drift_ppm_per_h=drift_ppm_per_h,
        gradient_per_km=np.asarray(gradient_per_km, dtype=float),
        profile=prof,
    )
    return noisy, truth
