"""Record sets for replays (:mod:`oceanloc.field.replay`) from field data: GNSS-A pings and GPS + USBL logs.

* **GNSS-A** (:func:`gnssa_records`): one record per ping that the reference solution
  (:func:`oceanloc.estimation.gnssa.localize_gnssa` over all pings) used; its outliers are left out. The
  measurement is the two-way path ``c(t_i) TWTT_i`` with ``c(t_i)`` the reference's sound speed at that
  ping (its piecewise-linear estimate, whose prior is the published harmonic mean) and the reference's
  per-ping sigma, less the reference's horizontal-gradient and refraction terms at its position (the
  replay's model is the straight two-leg path); the record's location is the transmit position. The
  reference position is the "truth" replayed errors are measured against, so a replay that used every
  ping would return it.
* **GPS + USBL logs** (:func:`range_log_records`): ranges to the beacons with the journal's total sigma
  ``sigma_eps`` (1.006 m, Section VI-B). One beacon: one record per range. Several beacons: the SeaTrac
  interrogates them in turn, so a record is a group of consecutive ranges, one to each beacon, within
  ``group_gap_s``; each range keeps its own antenna position and the record's location is their mean.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from oceanloc._typing import ArrayLike, BoolArray
from oceanloc.errors import DataError
from oceanloc.estimation.gnssa import GnssaOptions, GnssaResult, hat_basis, localize_gnssa
from oceanloc.estimation.range_logs import BeaconEstimate, localize_beacons
from oceanloc.field.replay import RecordSet
from oceanloc.io.gnssa import GnssaSurvey
from oceanloc.io.usbl import AlignedRanges
from oceanloc.models.acoustics import gradient_path_m2, refraction_shortening_m

SIGMA_EPS_M = 1.006
"""The journal's total range sigma for the pier experiment (USBL 113 mm and GPS 1 m, Section VI-B)."""


def gnssa_records(survey: GnssaSurvey, reference: GnssaResult, turnaround_s: float = 0.0) -> RecordSet:
    """The pings the reference solution used, as a two-way record set (see the module docstring)."""
    used = np.asarray(reference.used, dtype=bool)
    if used.shape != (survey.n_pings,):
        raise DataError(f"{survey.path}: the reference solution is for another survey")
    if not used.any():
        raise DataError(f"{survey.path}: no ping left to replay")
    t_mid = 0.5 * (survey.t_transmit_s + survey.t_receive_s)
    if reference.knot_times_s.size:
        speed = hat_basis(t_mid, reference.knot_times_s) @ reference.sound_speed_knots_mps
    else:
        speed = np.full(survey.n_pings, reference.sound_speed_mps)
    tx, rx = survey.transmit_enu_m, survey.receive_enu_m
    # The reference's horizontal gradient and refraction terms, evaluated at its position, turn each
    # c TWTT into the straight two-leg path the replay's model predicts.
    ref = reference.position_enu_m
    correction = sum(
        gradient_path_m2(ref, leg) @ (1e-3 * reference.gradient_per_km)
        - 1e-6 * reference.refraction_ppm * refraction_shortening_m(ref, leg)
        for leg in (tx, rx)
    )
    path = speed * (survey.twtt_s - turnaround_s) - correction
    return RecordSet(
        name=survey.name,
        location_enu_m=tx[used].copy(),
        time_s=survey.t_transmit_s[used].copy(),
        transmit_enu_m=tx[used][:, None, :].copy(),
        receive_enu_m=rx[used][:, None, :].copy(),
        value_m=path[used][:, None],
        sigma_m=reference.sigma_m[used][:, None],
        reference_enu_m=reference.position_enu_m[None, :].copy(),
        surface_z_m=float(np.min(np.concatenate([tx[:, 2], rx[:, 2]]))),
    )


def gnssa_replay_records(survey: GnssaSurvey, options: GnssaOptions) -> tuple[RecordSet, GnssaResult]:
    """Localize a survey over all its pings (the reference) and build its record set."""
    reference = localize_gnssa(survey, options)
    return gnssa_records(survey, reference, options.turnaround_s), reference


def range_log_inliers(aligned: AlignedRanges, estimates: Sequence[BeaconEstimate]) -> BoolArray:
    """``(m,)`` mask over the aligned ranges: those the robust estimator kept (True) per beacon."""
    keep = np.zeros(aligned.range_m.size, dtype=bool)
    for est in estimates:
        keep[np.flatnonzero(aligned.select(est.beacon))[est.used]] = True
    return keep


def log_reference(
    aligned: AlignedRanges, sigma_range_m: float = SIGMA_EPS_M
) -> tuple[dict[int, np.ndarray], BoolArray]:
    """Robust MAP beacon positions over all ranges (:func:`localize_beacons`) and its inlier mask."""
    estimates = localize_beacons(aligned, sigma_range_m=sigma_range_m)
    return {e.beacon: e.position_enu_m for e in estimates}, range_log_inliers(aligned, estimates)


def range_log_records(
    aligned: AlignedRanges,
    beacons: Sequence[int],
    reference_enu_m: ArrayLike,
    *,
    keep: ArrayLike | None = None,
    sigma_range_m: float = SIGMA_EPS_M,
    group_gap_s: float = 3.0,
    name: str | None = None,
) -> RecordSet:
    """Ranges to ``beacons`` as a one-way record set (see the module docstring).

    Parameters
    ----------
    aligned : AlignedRanges
        Ranges with the antenna position at each (:func:`oceanloc.io.usbl.align_ranges`).
    beacons : sequence of int
        Beacon ids, in the order of ``reference_enu_m``.
    reference_enu_m : (M, 3) float
        Their positions (truth or a reference solution) in the frame of ``aligned``.
    keep : (m,) bool, optional
        Ranges to use (e.g. :func:`range_log_inliers`); all by default.
    sigma_range_m : float
        ``sigma_eps`` of every range.
    group_gap_s : float
        Longest span of one record's ranges when there are several beacons, seconds.
    name : str, optional

    Raises
    ------
    DataError
        If a beacon has no range, or no complete group of ranges exists.
    """
    ids = [int(b) for b in beacons]
    ref = np.asarray(reference_enu_m, dtype=float).reshape(len(ids), 3)
    use = np.ones(aligned.range_m.size, bool) if keep is None else np.asarray(keep, dtype=bool)
    label = name or ("beacon " + ", ".join(map(str, ids)))
    for b in ids:
        if not np.any(use & aligned.select(b)):
            raise DataError(f"{label}: no usable range to beacon {b} in the log")
    rows = np.flatnonzero(use & np.isin(aligned.beacon, ids))
    groups = _groups(aligned, rows, ids, group_gap_s) if len(ids) > 1 else rows[:, None]
    if groups.shape[0] == 0:
        raise DataError(f"{label}: no ranges to all of beacons {ids} within {group_gap_s} s of each other")
    ant = aligned.vehicle_enu_m[groups]
    return RecordSet(
        name=label,
        location_enu_m=ant.mean(axis=1),
        time_s=aligned.t_unix_s[groups].mean(axis=1),
        transmit_enu_m=ant,
        receive_enu_m=None,
        value_m=aligned.range_m[groups],
        sigma_m=np.full(groups.shape, float(sigma_range_m)),
        reference_enu_m=ref,
        surface_z_m=float(np.median(aligned.vehicle_enu_m[:, 2])),
    )


def _groups(aligned: AlignedRanges, rows: np.ndarray, ids: list[int], gap_s: float) -> np.ndarray:
    """``(P, M)`` indices: consecutive ranges, one per beacon (in ``ids`` order), spanning <= ``gap_s``.

    One pass over the log in time order (data preparation, not a hot path): a range to a beacon already
    in the open group, or too late for it, starts a new group; a group is kept once complete.
    """
    column = {b: j for j, b in enumerate(ids)}
    out: list[list[int]] = []
    group: dict[int, int] = {}
    t0 = 0.0
    for i in rows:
        b, t = int(aligned.beacon[i]), float(aligned.t_unix_s[i])
        if not group or b in group or t - t0 > gap_s:
            group, t0 = {}, t
        group[b] = int(i)
        if len(group) == len(ids):
            out.append([group[b] for b in sorted(group, key=column.__getitem__)])
            group = {}
    return np.asarray(out, dtype=np.int64).reshape(-1, len(ids))
