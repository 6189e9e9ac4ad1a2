"""Readers and writers of GNATSS's file formats (the seafloor-geodesy community's GNSS-A package).

Formats (as GNATSS's documentation and loaders describe them; every time is in **J2000 seconds**,
seconds after 2000-01-01 12:00:00 in the files' own time scale without leap seconds, as GNATSS counts
them):

- ``pxp_tt`` travel times: one interrogation per line, ``DD-MON-YY HH:MM:SS.ss`` (or one J2000 time
  column, ``pxp_tt_j2k``), then one two-way travel time per transponder in **microseconds**, the
  transponder's internal delay included; ``0`` means no reply.
- ``POS_FREED_TRANS_TWTT`` transducer positions: ``time X Y Z`` (Earth-fixed, metres) and the nine
  entries of the 3x3 XYZ covariance (m^2), one line at each interrogation and each reply epoch (the
  reply epoch is the interrogation time plus that transponder's travel time).
- The sound-speed profile: two columns, depth (m, negative down) and sound speed (m/s).
- The Level-2 per-ping CSV (the "community standard" GNSS-A format GNATSS's solver reads and its
  posfilter writes, ``gps_solution.csv``): one row per reply with ``MT_ID``, ``TravelTime`` (s),
  ``T_transmit``, ``T_receive``, ``X/Y/Z_transmit``, ``X/Y/Z_receive`` and the covariances
  ``ant_cov_XX0 ... ant_cov_ZZ0`` (transmit) and ``ant_cov_XX1 ... ant_cov_ZZ1`` (receive).
- Its outputs: ``residuals.csv`` and ``outliers.csv`` (``time, iso_string, <transponder id>...``,
  one-way residuals in centimetres at 1500 m/s), ``deletions.csv`` (``starttime, endtime`` in J2000
  seconds) and the legacy manual deletion file ``deletns.dat`` (``DD-MON-YY HH:MM:SS DD-MON-YY
  HH:MM:SS ...``, extra columns ignored).
- Its configuration YAML (site, array centre, transponders with a-priori position and internal delay,
  solver limits and input paths).

Every reader follows the project's bad-input rules: a malformed line is skipped and recorded in a
:class:`~oceanloc.io.qc.QcReport` with ``file:line`` and a reason; a file with a wrong unit (travel
times in seconds instead of microseconds, positions not Earth-fixed metres, a sound speed in ft/s) or
without one usable record raises a one-line :class:`~oceanloc.errors.DataError`.
"""

from __future__ import annotations

import csv
import datetime as dt
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from oceanloc._typing import BoolArray, FloatArray, IntArray
from oceanloc.errors import DataError
from oceanloc.geo.enu import EnuOrigin
from oceanloc.io.qc import QcReport, read_lines

J2000_EPOCH = dt.datetime(2000, 1, 1, 12, 0, 0)
"""Origin of GNATSS's J2000 seconds (2000-01-01 12:00:00, no leap seconds counted)."""

J2000_UNIX_S = 946_728_000.0
"""The J2000 origin as a Unix time (naive calendar arithmetic, as GNATSS's files count)."""

PXP_DATETIME_FORMAT = "%d-%b-%y %H:%M:%S.%f"
DELETION_DATETIME_FORMAT = "%d-%b-%y %H:%M:%S"

EARTH_RADIUS_RANGE_M: tuple[float, float] = (6.30e6, 6.42e6)
"""Distances from the Earth's centre an Earth-fixed (ECEF) surface position may have, metres."""

SOUND_SPEED_RANGE_MPS: tuple[float, float] = (1300.0, 1700.0)
"""Sound speeds sea water may have, m/s (outside: a wrong unit or a corrupt value)."""

MAX_TWTT_S = 60.0
"""Longest two-way travel time accepted, seconds (beyond: a corrupt field or a wrong unit)."""

RESIDUAL_SPEED_MPS = 1500.0
"""GNATSS converts travel-time residuals to one-way centimetres at this speed (quality control only)."""

LEVEL2_COLUMNS: tuple[str, ...] = (
    "T_receive",
    "MT_ID",
    "TravelTime",
    "T_transmit",
    *(f"ant_cov_{a}{b}1" for a in "XYZ" for b in "XYZ"),
    "X_receive",
    "Y_receive",
    "Z_receive",
    *(f"ant_cov_{a}{b}0" for a in "XYZ" for b in "XYZ"),
    "X_transmit",
    "Y_transmit",
    "Z_transmit",
)
"""Columns of the Level-2 CSV in the order GNATSS's posfilter writes them."""


def j2000_from_datetime(stamp: dt.datetime) -> float:
    """J2000 seconds of a naive date-time (the file's time scale; no leap seconds)."""
    return (stamp - J2000_EPOCH).total_seconds()


def datetime_from_j2000(t_s: float) -> dt.datetime:
    """The naive date-time of J2000 seconds."""
    return J2000_EPOCH + dt.timedelta(seconds=float(t_s))


def j2000_iso(t_s: float) -> str:
    """J2000 seconds as ``YYYY-MM-DDTHH:MM:SS.ffffff`` (GNATSS's ``iso_string`` column)."""
    return datetime_from_j2000(t_s).strftime("%Y-%m-%dT%H:%M:%S.%f")


def _pxp_stamp(t_s: float) -> str:
    """J2000 seconds as a pxp_tt date-time: ``26-JUN-23 00:00:07.00``."""
    stamp = datetime_from_j2000(round(float(t_s), 2))
    return stamp.strftime("%d-%b-%y %H:%M:%S.").upper() + f"{stamp.microsecond // 10_000:02d}"


def _floats(fields: Sequence[str], p: Path, number: int, qc: QcReport, first: int = 1) -> list[float] | None:
    """The fields as finite floats, or None after recording why not (``first``: 1-based field offset)."""
    try:
        values = [float(f) for f in fields]
    except ValueError:
        bad = next(i for i, f in enumerate(fields) if not _is_float(f))
        qc.add(p, number, "non-numeric field", f"field {bad + first}: {fields[bad]!r}")
        return None
    if not all(math.isfinite(v) for v in values):
        qc.add(p, number, "NaN or infinite value")
        return None
    return values


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _no_records(p: Path, qc: QcReport, what: str) -> DataError:
    detail = "; ".join(str(i) for i in qc.issues[:3])
    return DataError(f"{p}: no valid {what}" + (f" ({detail})" if detail else ""))


# --------------------------------------------------------------------------------------------- pxp_tt


@dataclass(frozen=True, slots=True, kw_only=True)
class PxpTravelTimes:
    """A ``pxp_tt`` file: ``n`` interrogations, ``m`` transponder columns.

    Attributes
    ----------
    path : str
    t_transmit_s : (n,) float
        Interrogation times, J2000 seconds.
    twtt_s : (n, m) float
        Two-way travel times (internal delays included), seconds; NaN where a transponder did not
        reply (a 0 in the file).
    line : (n,) int
        Line of each interrogation in the file.
    qc : QcReport
    """

    path: str
    t_transmit_s: FloatArray
    twtt_s: FloatArray
    line: IntArray
    qc: QcReport

    @property
    def n_transponders(self) -> int:
        return int(self.twtt_s.shape[1])


def read_pxp_tt(path: str | Path, n_transponders: int | None = None) -> PxpTravelTimes:
    """Read a GNATSS ``pxp_tt`` (date and time columns) or ``pxp_tt_j2k`` (one J2000 column) file.

    The layout is recognised per file from its first data line. With ``n_transponders``, extra travel
    time columns are ignored (as GNATSS does) and a line with fewer is skipped; without it the first
    data line sets the count. A line is skipped (and recorded) if a field is not a number or a date, a
    travel time is negative, above 60 s, or every travel time is 0 (no reply), or its time is not
    after the previous line's.

    Raises
    ------
    DataError
        If the file cannot be read, holds no valid interrogation, or its travel times are clearly not
        microseconds (all below 100 us: seconds were written).
    """
    p = Path(path)
    qc = QcReport()
    times: list[float] = []
    rows: list[list[float]] = []
    lines: list[int] = []
    layout: str | None = None
    m = n_transponders
    last_t = -math.inf
    for number, text in read_lines(p, qc):
        if text.startswith("#"):
            qc.lines_read -= 1
            continue
        fields = text.split()
        if layout is None:
            layout = "j2k" if _is_float(fields[0]) else "date"
        lead = 1 if layout == "j2k" else 2
        if m is None:
            m = len(fields) - lead
            if m < 1:
                qc.add(p, number, "truncated sentence", f"{len(fields)} fields: no travel time")
                m = None
                continue
        if len(fields) < lead + m:
            qc.add(p, number, "truncated sentence", f"{len(fields)} fields, expected {lead + m}")
            continue
        if layout == "j2k":
            t_val = _floats(fields[:1], p, number, qc)
            if t_val is None:
                continue
            t = t_val[0]
        else:
            try:
                t = j2000_from_datetime(dt.datetime.strptime(f"{fields[0]} {fields[1]}", PXP_DATETIME_FORMAT))
            except ValueError:
                qc.add(
                    p,
                    number,
                    "non-numeric field",
                    f"date-time {fields[0]} {fields[1]!r}: not DD-MON-YY HH:MM:SS.ss",
                )
                continue
        us = _floats(fields[lead : lead + m], p, number, qc, first=lead + 1)
        if us is None:
            continue
        if min(us) < 0.0 or max(us) > MAX_TWTT_S * 1e6:
            bad = min(us) if min(us) < 0.0 else max(us)
            qc.add(p, number, "negative or absurd range", f"travel time {bad:g} us")
            continue
        if max(us) == 0.0:
            qc.add(p, number, "negative or absurd range", "no transponder replied (all travel times 0)")
            continue
        if t <= last_t:
            qc.add(p, number, "time going backwards", f"{t:.6f} s after {last_t:.6f} s")
            continue
        last_t = t
        times.append(t)
        rows.append(us)
        lines.append(number)
    if not rows:
        raise _no_records(p, qc, "interrogation")
    us_arr = np.asarray(rows, dtype=float)
    positive = us_arr[us_arr > 0.0]
    if positive.size and float(np.max(positive)) < 100.0:
        raise DataError(
            f"{p}: travel times are at most {float(np.max(positive)):g}, not microseconds (pxp_tt holds "
            "two-way travel times in us; were seconds written?)"
        )
    qc.records_kept = len(rows)
    return PxpTravelTimes(
        path=str(p),
        t_transmit_s=np.asarray(times, dtype=float),
        twtt_s=np.where(us_arr > 0.0, us_arr * 1e-6, np.nan),
        line=np.asarray(lines, dtype=np.int64),
        qc=qc,
    )


def write_pxp_tt(path: str | Path, t_transmit_s: FloatArray, twtt_s: FloatArray) -> Path:
    """Write a ``pxp_tt`` file (date-time columns; NaN travel times as 0: no reply).

    Times are rounded to 10 ms and travel times to 1 us, the file's resolution.
    """
    p = Path(path)
    us = np.where(np.isfinite(twtt_s), np.rint(np.nan_to_num(twtt_s) * 1e6), 0).astype(np.int64)
    with p.open("w", encoding="utf-8") as fh:
        for t, row in zip(t_transmit_s, us, strict=True):
            fh.write(_pxp_stamp(t) + "".join(f" {v:9d}" for v in row) + "\n")
    return p


# ------------------------------------------------------------------------------ POS_FREED_TRANS_TWTT


@dataclass(frozen=True, slots=True, kw_only=True)
class TransducerPositions:
    """A ``POS_FREED_TRANS_TWTT`` file: ``k`` transducer positions with covariance.

    Attributes
    ----------
    path : str
    t_s : (k,) float
        Epochs, J2000 seconds (interrogation and reply epochs).
    xyz_m : (k, 3) float
        Earth-fixed transducer positions, metres.
    cov_m2 : (k, 3, 3) float
        Their XYZ covariance, m^2.
    line : (k,) int
    qc : QcReport
    """

    path: str
    t_s: FloatArray
    xyz_m: FloatArray
    cov_m2: FloatArray
    line: IntArray
    qc: QcReport


def _check_ecef(xyz: Sequence[float], p: Path, number: int, qc: QcReport) -> bool:
    r = math.sqrt(sum(v * v for v in xyz))
    lo, hi = EARTH_RADIUS_RANGE_M
    if not lo <= r <= hi:
        qc.add(p, number, "out of range", f"|XYZ| {r:.1f} m is not an Earth-fixed surface position (metres)")
        return False
    return True


Why = list[tuple[str, str] | None]


def _cov_why(cov: FloatArray, what: str = "covariance") -> Why:
    """Per matrix of ``(k, 3, 3)``: None if usable (as :func:`_check_cov`), else ``(reason, detail)``."""
    k = cov.shape[0]
    d = np.diagonal(cov, axis1=1, axis2=2)
    nonpos = np.any(d <= 0.0, axis=1)
    big = ~nonpos & np.any(d > 100.0, axis=1)
    scale = np.maximum(np.abs(cov), np.abs(np.swapaxes(cov, 1, 2)))
    asym = np.any(np.abs(cov - np.swapaxes(cov, 1, 2)) > 1e-12 + 1e-6 * scale, axis=(1, 2))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.sqrt(np.maximum(d[:, :, None] * d[:, None, :], 1e-300))
    high = np.any(np.abs(corr) > 1.0 + 1e-6, axis=(1, 2))
    out: Why = [None] * k
    for i in np.flatnonzero(nonpos | big | asym | high):
        if nonpos[i]:
            out[i] = ("non-numeric field", f"{what} diagonal {d[i].tolist()} m^2 is not positive")
        elif big[i]:
            out[i] = ("out of range", f"{what} diagonal {d[i].max():g} m^2 > 100 m^2 (units: m^2?)")
        elif asym[i]:
            out[i] = ("non-numeric field", f"{what} is not symmetric")
        else:
            out[i] = ("non-numeric field", f"{what} has a correlation above 1")
    return out


def _ecef_why(xyz: FloatArray) -> Why:
    """Per position of ``(k, 3)``: None if on the Earth's surface in metres, else ``(reason, detail)``."""
    r = np.linalg.norm(xyz, axis=1)
    lo, hi = EARTH_RADIUS_RANGE_M
    out: Why = [None] * xyz.shape[0]
    for i in np.flatnonzero((r < lo) | (r > hi)):
        out[i] = ("out of range", f"|XYZ| {r[i]:.1f} m is not an Earth-fixed surface position (metres)")
    return out


def _first(*whys: Why) -> Why:
    """The first problem of each row among several checks."""
    return [next((w for w in ws if w is not None), None) for ws in zip(*whys, strict=True)]


def _sort_issues(qc: QcReport) -> None:
    qc.issues.sort(key=lambda i: (i.file, i.line))


def read_pos_freed_trans_twtt(path: str | Path) -> TransducerPositions:
    """Read a ``POS_FREED_TRANS_TWTT`` file (13 columns: J2000 time, X Y Z in m, 9 covariance entries).

    A line is skipped (and recorded) if it has not 13 fields, a field is not a number, the position is
    not on the Earth's surface in metres (distance from the centre outside 6,300-6,420 km), the
    covariance diagonal is not positive, above 100 m^2 or the matrix not symmetric, or its time repeats
    or goes backwards.

    Raises
    ------
    DataError
        If the file cannot be read or holds no valid position.
    """
    p = Path(path)
    qc = QcReport()
    parsed: list[list[float]] = []
    numbers: list[int] = []
    for number, text in read_lines(p, qc):
        if text.startswith("#"):
            qc.lines_read -= 1
            continue
        fields = text.split()
        if len(fields) != 13:
            reason = "truncated sentence" if len(fields) < 13 else "wrong field count"
            qc.add(p, number, reason, f"{len(fields)} fields, expected 13 (time, X, Y, Z, 9 covariance)")
            continue
        values = _floats(fields, p, number, qc)
        if values is not None:
            parsed.append(values)
            numbers.append(number)
    a = np.asarray(parsed, dtype=float).reshape(-1, 13)
    why = _first(_ecef_why(a[:, 1:4]), _cov_why(a[:, 4:].reshape(-1, 3, 3)))
    keep: list[int] = []
    last_t = -math.inf
    for i, w in enumerate(why):
        if w is not None:
            qc.add(p, numbers[i], *w)
        elif a[i, 0] <= last_t:
            qc.add(p, numbers[i], "time going backwards", f"{a[i, 0]:.6f} s after {last_t:.6f} s")
        else:
            last_t = a[i, 0]
            keep.append(i)
    _sort_issues(qc)
    if not keep:
        raise _no_records(p, qc, "transducer position")
    a = a[keep]
    lines = [numbers[i] for i in keep]
    qc.records_kept = len(keep)
    return TransducerPositions(
        path=str(p),
        t_s=a[:, 0],
        xyz_m=a[:, 1:4],
        cov_m2=a[:, 4:].reshape(-1, 3, 3),
        line=np.asarray(lines, dtype=np.int64),
        qc=qc,
    )


def write_pos_freed_trans_twtt(
    path: str | Path, t_s: FloatArray, xyz_m: FloatArray, cov_m2: FloatArray
) -> Path:
    """Write a ``POS_FREED_TRANS_TWTT`` file (rows sorted by time as given)."""
    p = Path(path)
    flat = np.asarray(cov_m2, dtype=float).reshape(-1, 9)
    with p.open("w", encoding="utf-8") as fh:
        for t, xyz, c in zip(t_s, xyz_m, flat, strict=True):
            fh.write(
                f"{t:20.7f} {xyz[0]:17.4f} {xyz[1]:17.4f} {xyz[2]:17.4f} "
                + " ".join(f"{v:17.10E}" for v in c)
                + "\n"
            )
    return p


# ------------------------------------------------------------------------------- sound-speed profile


@dataclass(frozen=True, slots=True, kw_only=True)
class SoundSpeedProfile:
    """A sound-speed profile: depth (positive down) and sound speed.

    Attributes
    ----------
    path : str
    depth_m : (L,) float
        Depths below the surface, metres, strictly increasing.
    speed_mps : (L,) float
        Sound speed at each depth, m/s.
    qc : QcReport
    """

    path: str
    depth_m: FloatArray
    speed_mps: FloatArray
    qc: QcReport

    def harmonic_mean_mps(self, start_depth_m: float, end_depth_m: float) -> float:
        """Harmonic-mean sound speed between two depths (m, positive down), m/s.

        The speed is linear between the profile's levels, so the slowness integral of each layer is
        exact: ``int dz / c = ln(c2 / c1) / b`` with ``b = (c2 - c1) / (z2 - z1)`` (``dz / c`` where
        ``b = 0``); beyond the last level the speed is held constant. This is the harmonic mean
        GNATSS's solver uses as each transponder's sound speed (its start depth and the transponder's
        depth).
        """
        z0, z1 = sorted((abs(start_depth_m), abs(end_depth_m)))
        if z1 <= z0:
            return float(np.interp(z0, self.depth_m, self.speed_mps))
        z = np.concatenate([[z0], self.depth_m[(self.depth_m > z0) & (self.depth_m < z1)], [z1]])
        c = np.interp(z, self.depth_m, self.speed_mps)
        dz = np.diff(z)
        dc = np.diff(c)
        with np.errstate(divide="ignore", invalid="ignore"):
            layer = np.where(
                np.abs(dc) > 1e-12, dz * np.log(c[1:] / c[:-1]) / np.where(dc == 0, 1, dc), dz / c[:-1]
            )
        return float((z1 - z0) / np.sum(layer))


def read_sound_speed_profile(path: str | Path) -> SoundSpeedProfile:
    """Read a two-column sound-speed profile (depth in m, negative or positive down; speed in m/s).

    Whitespace or comma separated; a header line of names (``depth,speed``) is allowed. Repeated depths
    keep their first value (as GNATSS does). A line is skipped (and recorded) if it has not two
    numbers or its speed is outside 1300-1700 m/s; levels are sorted by depth.

    Raises
    ------
    DataError
        If fewer than two levels remain, or most speeds are outside 1300-1700 m/s (a wrong unit, e.g.
        ft/s, or the columns swapped).
    """
    p = Path(path)
    qc = QcReport()
    depths: list[float] = []
    speeds: list[float] = []
    out_of_range = 0
    for number, text in read_lines(p, qc):
        if text.startswith("#"):
            qc.lines_read -= 1
            continue
        fields = text.replace(",", " ").split()
        if len(fields) < 2:
            qc.add(p, number, "truncated sentence", f"{len(fields)} field, expected depth and speed")
            continue
        if not _is_float(fields[0]) and not depths and not qc.issues:
            qc.lines_read -= 1  # a header line of column names
            continue
        values = _floats(fields[:2], p, number, qc)
        if values is None:
            continue
        lo, hi = SOUND_SPEED_RANGE_MPS
        if not lo <= values[1] <= hi:
            out_of_range += 1
            qc.add(p, number, "out of range", f"sound speed {values[1]:g} m/s outside [{lo:g}, {hi:g}] m/s")
            continue
        depths.append(abs(values[0]))
        speeds.append(values[1])
    if out_of_range and out_of_range >= len(speeds):
        raise DataError(
            f"{p}: {out_of_range} of {out_of_range + len(speeds)} sound speeds are outside 1300-1700 m/s: "
            "expected depth (m) then sound speed (m/s)"
        )
    z = np.asarray(depths, dtype=float)
    c = np.asarray(speeds, dtype=float)
    _, first = np.unique(z, return_index=True)
    first = np.sort(first)
    z, c = z[first], c[first]
    order = np.argsort(z, kind="stable")
    if z.size < 2:
        raise DataError(f"{p}: a sound-speed profile needs at least two depths, got {z.size}")
    qc.records_kept = int(z.size)
    return SoundSpeedProfile(path=str(p), depth_m=z[order], speed_mps=c[order], qc=qc)


def write_sound_speed_profile(path: str | Path, depth_m: FloatArray, speed_mps: FloatArray) -> Path:
    """Write a GNATSS sound-speed profile (depth negative down, speed)."""
    p = Path(path)
    with p.open("w", encoding="utf-8") as fh:
        for z, c in zip(depth_m, speed_mps, strict=True):
            fh.write(f"{-abs(z):.4f} {c:.4f}\n")
    return p


# ------------------------------------------------------------------------------------ Level-2 CSV


@dataclass(frozen=True, slots=True, kw_only=True)
class ArrayPings:
    """Per-reply GNSS-A data of an array survey (Earth-fixed), whatever file it came from.

    ``n`` replies; the same interrogation appears once per transponder that replied.

    Attributes
    ----------
    path : str
        Travel-time (or Level-2) file.
    ids : tuple of str
        Transponder ids; ``transponder`` indexes them.
    transponder : (n,) int
    t_transmit_s : (n,) float
        Interrogation time, J2000 seconds.
    twtt_s : (n,) float
        Measured two-way travel time, internal delay included, seconds.
    transmit_xyz_m, receive_xyz_m : (n, 3) float
        Transducer positions at interrogation and at reply, Earth-fixed, metres.
    transmit_cov_m2, receive_cov_m2 : (n, 3, 3) float
        Their covariances, m^2.
    line : (n,) int
        Line of each reply's record in ``path``.
    qc : QcReport
    """

    path: str
    ids: tuple[str, ...]
    transponder: IntArray
    t_transmit_s: FloatArray
    twtt_s: FloatArray
    transmit_xyz_m: FloatArray
    receive_xyz_m: FloatArray
    transmit_cov_m2: FloatArray
    receive_cov_m2: FloatArray
    line: IntArray
    qc: QcReport

    @property
    def n_replies(self) -> int:
        return int(self.twtt_s.size)

    @property
    def t_receive_s(self) -> FloatArray:
        return self.t_transmit_s + self.twtt_s

    def select(self, keep: BoolArray) -> ArrayPings:
        """The replies where ``keep`` is True."""
        return ArrayPings(
            path=self.path,
            ids=self.ids,
            transponder=self.transponder[keep],
            t_transmit_s=self.t_transmit_s[keep],
            twtt_s=self.twtt_s[keep],
            transmit_xyz_m=self.transmit_xyz_m[keep],
            receive_xyz_m=self.receive_xyz_m[keep],
            transmit_cov_m2=self.transmit_cov_m2[keep],
            receive_cov_m2=self.receive_cov_m2[keep],
            line=self.line[keep],
            qc=self.qc,
        )


def read_level2_csv(path: str | Path, ids: Sequence[str] | None = None) -> ArrayPings:
    """Read GNATSS's Level-2 per-reply CSV (``gps_solution.csv``, the community standard GNSS-A format).

    Columns are found by name (any order; extra columns ignored). ``TravelTime`` must equal
    ``T_receive - T_transmit`` within 1 ms (else the row is skipped: a time column in another unit or
    epoch). With ``ids``, rows of other transponders are recorded as ``unknown beacon id``; without,
    the ids are those found, in order of appearance.

    Raises
    ------
    DataError
        If a required column is missing, or no row is valid.
    """
    p = Path(path)
    qc = QcReport()
    header: list[str] | None = None
    rows: list[tuple[int, list[str]]] = []
    for number, text in read_lines(p, qc):
        if text.startswith("#"):
            qc.lines_read -= 1
            continue
        cells = next(csv.reader([text]))
        if header is None:
            header = [c.strip() for c in cells]
            qc.lines_read -= 1
            missing = [c for c in LEVEL2_COLUMNS if c not in header]
            if missing:
                raise DataError(
                    f"{p}:{number}: Level-2 CSV header lacks column(s) {', '.join(missing[:4])}"
                    + (f" and {len(missing) - 4} more" if len(missing) > 4 else "")
                )
            continue
        rows.append((number, cells))
    if header is None:
        raise _no_records(p, qc, "row (no header)")
    numeric = [c for c in LEVEL2_COLUMNS if c != "MT_ID"]
    num_idx = [header.index(c) for c in numeric]
    mt_idx = header.index("MT_ID")
    known = list(ids) if ids is not None else []
    values: list[list[float]] = []
    numbers: list[int] = []
    tps: list[int] = []
    for number, cells in rows:
        if len(cells) != len(header):
            qc.add(p, number, "wrong field count", f"{len(cells)} fields, header has {len(header)}")
            continue
        v = _floats([cells[i] for i in num_idx], p, number, qc)
        if v is None:
            continue
        mt = cells[mt_idx].strip()
        if mt not in known:
            if ids is not None:
                qc.add(p, number, "unknown beacon id", f"MT_ID {mt!r} not in {list(ids)}")
                continue
            known.append(mt)
        values.append(v)
        numbers.append(number)
        tps.append(known.index(mt))
    a = np.asarray(values, dtype=float).reshape(-1, len(numeric))

    def cols(*names: str) -> FloatArray:
        return a[:, [numeric.index(n) for n in names]]

    tx = cols("X_transmit", "Y_transmit", "Z_transmit")
    rx = cols("X_receive", "Y_receive", "Z_receive")
    ctx = cols(*(f"ant_cov_{x}{y}0" for x in "XYZ" for y in "XYZ")).reshape(-1, 3, 3)
    crx = cols(*(f"ant_cov_{x}{y}1" for x in "XYZ" for y in "XYZ")).reshape(-1, 3, 3)
    t_rx, tt, t_tx = cols("T_receive", "TravelTime", "T_transmit").T
    bad_tt: Why = [None] * a.shape[0]
    for i in np.flatnonzero(~((tt > 0.0) & (tt < MAX_TWTT_S))):
        bad_tt[i] = ("negative or absurd range", f"TravelTime {tt[i]:g} s")
    bad_sum: Why = [None] * a.shape[0]
    for i in np.flatnonzero(np.abs(t_rx - t_tx - tt) > 1e-3):
        bad_sum[i] = (
            "out of range",
            f"T_receive - T_transmit = {t_rx[i] - t_tx[i]:.6f} s, TravelTime {tt[i]:.6f} s",
        )
    covs = (_cov_why(ctx, "transmit covariance"), _cov_why(crx, "receive covariance"))
    why = _first(_ecef_why(tx), _ecef_why(rx), *covs, bad_tt, bad_sum)
    for i, w in enumerate(why):
        if w is not None:
            qc.add(p, numbers[i], *w)
    _sort_issues(qc)
    keep = np.array([w is None for w in why], dtype=bool)
    if not keep.any():
        raise _no_records(p, qc, "reply")
    qc.records_kept = int(keep.sum())
    return ArrayPings(
        path=str(p),
        ids=tuple(known),
        transponder=np.asarray(tps, dtype=np.int64)[keep],
        t_transmit_s=t_tx[keep],
        twtt_s=tt[keep],
        transmit_xyz_m=tx[keep],
        receive_xyz_m=rx[keep],
        transmit_cov_m2=ctx[keep],
        receive_cov_m2=crx[keep],
        line=np.asarray(numbers, dtype=np.int64)[keep],
        qc=qc,
    )


def write_level2_csv(path: str | Path, pings: ArrayPings) -> Path:
    """Write replies as GNATSS's Level-2 CSV (columns :data:`LEVEL2_COLUMNS`, sorted by receive time)."""
    p = Path(path)
    order = np.argsort(pings.t_receive_s, kind="stable")
    with p.open("w", encoding="utf-8", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(LEVEL2_COLUMNS)
        for i in order:
            crx = pings.receive_cov_m2[i].ravel()
            ctx = pings.transmit_cov_m2[i].ravel()
            rx, tx = pings.receive_xyz_m[i], pings.transmit_xyz_m[i]
            w.writerow(
                [
                    f"{pings.t_transmit_s[i] + pings.twtt_s[i]:.6f}",
                    pings.ids[pings.transponder[i]],
                    f"{pings.twtt_s[i]:.6f}",
                    f"{pings.t_transmit_s[i]:.6f}",
                    *(f"{v:.10g}" for v in crx),
                    *(f"{v:.8f}" for v in rx),
                    *(f"{v:.10g}" for v in ctx),
                    *(f"{v:.8f}" for v in tx),
                ]
            )
    return p


def join_pxp_positions(
    travel: PxpTravelTimes, positions: TransducerPositions, ids: Sequence[str], tolerance_s: float = 5e-6
) -> ArrayPings:
    """Join ``pxp_tt`` travel times with ``POS_FREED_TRANS_TWTT`` positions into per-reply data.

    Each interrogation needs a position at its time and each reply one at ``time + travel time``
    (within ``tolerance_s``; the files carry 1 us). A reply without its positions is recorded in the
    travel-time file's QC (``file:line``, which epoch is missing) and skipped; the interrogation's
    other replies are kept.

    Raises
    ------
    DataError
        If ``ids`` does not match the file's transponder columns, or no reply has both positions.
    """
    if len(ids) != travel.n_transponders:
        raise DataError(
            f"{travel.path}: {travel.n_transponders} travel-time columns, {len(ids)} transponders configured"
        )
    qc = travel.qc
    t_pos = positions.t_s

    def lookup(t: FloatArray) -> IntArray:
        j = (
            np.clip(np.searchsorted(t_pos, t), 1, t_pos.size - 1)
            if t_pos.size > 1
            else np.zeros(t.shape, np.int64)
        )
        j = np.where(np.abs(t_pos[j - 1] - t) < np.abs(t_pos[j] - t), j - 1, j) if t_pos.size > 1 else j
        return np.where(np.abs(t_pos[j] - t) <= tolerance_s, j, -1)

    n, m = travel.twtt_s.shape
    i_tx = lookup(travel.t_transmit_s)
    replied = np.isfinite(travel.twtt_s)
    i_rx = np.full((n, m), -1, dtype=np.int64)
    t_rx = travel.t_transmit_s[:, None] + np.nan_to_num(travel.twtt_s)
    i_rx[replied] = lookup(t_rx[replied])
    for i in np.flatnonzero(i_tx < 0):
        qc.add(
            travel.path,
            int(travel.line[i]),
            "invalid fix",
            f"no transducer position at the interrogation {travel.t_transmit_s[i]:.6f} s",
        )
    bad_rx = replied & (i_rx < 0) & (i_tx >= 0)[:, None]
    for i, k in zip(*np.nonzero(bad_rx), strict=True):
        qc.add(
            travel.path,
            int(travel.line[i]),
            "invalid fix",
            f"no transducer position at {ids[k]}'s reply {t_rx[i, k]:.6f} s",
        )
    ok = replied & (i_rx >= 0) & (i_tx >= 0)[:, None]
    rows, tps = np.nonzero(ok)
    if rows.size == 0:
        raise DataError(f"{travel.path}: no reply has transducer positions in {positions.path} at its epochs")
    j_tx, j_rx = i_tx[rows], i_rx[rows, tps]
    qc.records_kept = int(np.unique(rows).size)
    return ArrayPings(
        path=travel.path,
        ids=tuple(ids),
        transponder=tps.astype(np.int64),
        t_transmit_s=travel.t_transmit_s[rows],
        twtt_s=travel.twtt_s[rows, tps],
        transmit_xyz_m=positions.xyz_m[j_tx],
        receive_xyz_m=positions.xyz_m[j_rx],
        transmit_cov_m2=positions.cov_m2[j_tx],
        receive_cov_m2=positions.cov_m2[j_rx],
        line=travel.line[rows],
        qc=qc,
    )


# ------------------------------------------------------------------------------------- deletions


def read_deletions(path: str | Path) -> FloatArray:
    """Time windows to delete, ``(k, 2)`` J2000 seconds (start, end), from a deletion file.

    Three layouts: GNATSS's ``deletions.csv`` (header ``starttime,endtime``, J2000 seconds), its
    ``quality_controls`` CSV (``starttime,endtime,notes``, J2000 seconds or ISO date-times) and the legacy
    manual ``deletns.dat`` (``DD-MON-YY HH:MM:SS DD-MON-YY HH:MM:SS`` then anything). A line
    whose end is before its start, or that does not parse, is recorded and skipped.

    Raises
    ------
    DataError
        If the file cannot be read or holds no valid window.
    """
    p = Path(path)
    qc = QcReport()
    windows: list[tuple[float, float]] = []
    for number, text in read_lines(p, qc):
        if text.startswith("#"):
            qc.lines_read -= 1
            continue
        cells = [c.strip() for c in next(csv.reader([text]))] if "," in text else text.split()
        if cells[0] == "starttime":
            qc.lines_read -= 1
            continue
        if "," in text and len(cells) >= 2:
            try:
                t0, t1 = _qc_time(cells[0]), _qc_time(cells[1])
            except ValueError:
                qc.add(
                    p, number, "non-numeric field", "expected J2000 seconds or ISO date-times (start, end)"
                )
                continue
        elif len(cells) >= 4 and not _is_float(cells[0]):
            try:
                t0 = j2000_from_datetime(
                    dt.datetime.strptime(f"{cells[0]} {cells[1]}", DELETION_DATETIME_FORMAT)
                )
                t1 = j2000_from_datetime(
                    dt.datetime.strptime(f"{cells[2]} {cells[3]}", DELETION_DATETIME_FORMAT)
                )
            except ValueError:
                qc.add(p, number, "non-numeric field", "expected DD-MON-YY HH:MM:SS DD-MON-YY HH:MM:SS")
                continue
        elif len(cells) >= 2:
            values = _floats(cells[:2], p, number, qc)
            if values is None:
                continue
            t0, t1 = values
        else:
            qc.add(p, number, "truncated sentence", "expected a start and an end time")
            continue
        if t1 < t0:
            qc.add(p, number, "time going backwards", "deletion ends before it starts")
            continue
        windows.append((t0, t1))
    if not windows:
        raise _no_records(p, qc, "deletion window")
    if qc.issues:
        raise DataError(
            f"{p}: {qc.issues[0]}" + (f" (and {len(qc.issues) - 1} more)" if len(qc.issues) > 1 else "")
        )
    return np.asarray(windows, dtype=float)


def _qc_time(text: str) -> float:
    """J2000 seconds from a number or an ISO date-time (GNATSS's ``quality_controls`` CSV)."""
    return float(text) if _is_float(text) else j2000_from_datetime(dt.datetime.fromisoformat(text))


def in_windows(t_s: FloatArray, windows: FloatArray) -> BoolArray:
    """True where a time lies in any ``[start, end]`` window (inclusive, as GNATSS cuts)."""
    if windows.size == 0:
        return np.zeros(np.shape(t_s), dtype=bool)
    t = np.asarray(t_s, dtype=float)[..., None]
    return np.any((t >= windows[:, 0]) & (t <= windows[:, 1]), axis=-1)


def write_deletions_csv(path: str | Path, windows: FloatArray) -> Path:
    """Write GNATSS's ``deletions.csv`` (``starttime,endtime`` in J2000 seconds)."""
    p = Path(path)
    with p.open("w", encoding="utf-8") as fh:
        fh.write("starttime,endtime\n")
        for t0, t1 in np.asarray(windows, dtype=float).reshape(-1, 2):
            fh.write(f"{t0:.6f},{t1:.6f}\n")
    return p


# -------------------------------------------------------------------------- residual / outlier CSV


@dataclass(frozen=True, slots=True, kw_only=True)
class EpochResiduals:
    """GNATSS's ``residuals.csv`` or ``outliers.csv``: one row per interrogation.

    Attributes
    ----------
    t_s : (n,) float
        Interrogation times, J2000 seconds.
    ids : tuple of str
    residual_cm : (n, m) float
        One-way residuals, centimetres (GNATSS: travel-time residual x 1500 m/s / 2).
    """

    t_s: FloatArray
    ids: tuple[str, ...]
    residual_cm: FloatArray


def read_epoch_residuals(path: str | Path) -> EpochResiduals:
    """Read GNATSS's ``residuals.csv`` / ``outliers.csv`` (``time, iso_string, <id>...``, centimetres).

    Raises
    ------
    DataError
        If the header does not start with ``time,iso_string`` followed by transponder ids, or a row is
        malformed (``file:line``).
    """
    p = Path(path)
    qc = QcReport()
    header: list[str] | None = None
    t: list[float] = []
    res: list[list[float]] = []
    for number, text in read_lines(p, qc):
        cells = next(csv.reader([text]))
        if header is None:
            header = cells
            if header[:2] != ["time", "iso_string"] or len(header) < 3:
                raise DataError(f"{p}:{number}: expected the header time,iso_string,<transponder id>...")
            continue
        if len(cells) != len(header):
            raise DataError(f"{p}:{number}: {len(cells)} fields, header has {len(header)}")
        values = _floats([cells[0], *cells[2:]], p, number, qc)
        if values is None:
            raise DataError(f"{p}:{number}: {qc.issues[-1].reason} ({qc.issues[-1].detail})")
        t.append(values[0])
        res.append(values[1:])
    if header is None:
        raise _no_records(p, qc, "row (no header)")
    return EpochResiduals(
        t_s=np.asarray(t, dtype=float),
        ids=tuple(header[2:]),
        residual_cm=np.asarray(res, dtype=float).reshape(len(t), -1),
    )


def write_epoch_residuals(path: str | Path, residuals: EpochResiduals) -> Path:
    """Write residuals in GNATSS's ``residuals.csv`` columns (``time, iso_string, <id>...``, cm)."""
    p = Path(path)
    with p.open("w", encoding="utf-8", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["time", "iso_string", *residuals.ids])
        for t, row in zip(residuals.t_s, residuals.residual_cm, strict=True):
            w.writerow([f"{t:.6f}", j2000_iso(t), *(f"{v:.6f}" if np.isfinite(v) else "" for v in row)])
    return p


# ------------------------------------------------------------------------------------- config YAML


@dataclass(frozen=True, slots=True, kw_only=True)
class GnatssTransponder:
    """One transponder of a GNATSS configuration: a-priori position and internal delay."""

    pxp_id: str
    lat_deg: float
    lon_deg: float
    height_m: float
    internal_delay_s: float
    sv_mean_mps: float | None = None


@dataclass(frozen=True, slots=True, kw_only=True)
class GnatssConfig:
    """The parts of a GNATSS configuration YAML that oceanloc uses.

    Attributes
    ----------
    path : str
    site_id : str
    array_center : EnuOrigin
        Array centre (lat, lon, alt): the ENU origin of the survey.
    transponders : tuple of GnatssTransponder
        A-priori positions: ``height_m`` is the orthometric height (negative down); the ellipsoidal
        height is ``height_m + geoid_undulation_m``.
    geoid_undulation_m, harmonic_mean_start_depth_m : float
    travel_times_variance_s2, travel_times_correction_s, transducer_delay_time_s : float
    distance_limit_m, residual_limit_cm, residual_range_limit_cm, gps_sigma_limit_m : float
        GNATSS's solver limits (GNATSS's defaults where the file has none).
    inputs : dict of str to str
        Input paths by GNATSS key (``travel_times``, ``gps_solution``, ``sound_speed``, ``deletions``),
        resolved against the working directory, else the configuration's folder.
    """

    path: str
    site_id: str
    array_center: EnuOrigin
    transponders: tuple[GnatssTransponder, ...]
    geoid_undulation_m: float = 0.0
    harmonic_mean_start_depth_m: float = 0.0
    travel_times_variance_s2: float = 1e-10
    travel_times_correction_s: float = 0.0
    transducer_delay_time_s: float = 0.0
    distance_limit_m: float = 150.0
    residual_limit_cm: float = 10000.0
    residual_range_limit_cm: float = 20000.0
    gps_sigma_limit_m: float = 0.05
    inputs: dict[str, str] = field(default_factory=dict)
    atd_offsets_frd_m: tuple[float, float, float] | None = None

    @property
    def ids(self) -> tuple[str, ...]:
        return tuple(t.pxp_id for t in self.transponders)


def _number(p: Path, where: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(float(value)):
        raise DataError(f"{p}: {where} must be a number, got {value!r}")
    return float(value)


def read_gnatss_config(path: str | Path) -> GnatssConfig:
    """Read a GNATSS configuration YAML (site, array centre, transponders, solver limits, input paths).

    Raises
    ------
    DataError
        If the file is not YAML, or a required entry (``site_id``, ``array_center``, ``transponders``
        with ``lat``, ``lon``, ``height``/``alt``, ``internal_delay``) is missing or not a number.
    """
    import yaml

    p = Path(path)
    try:
        doc = yaml.safe_load(p.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise DataError(f"{p}: file not found") from None
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as exc:
        raise DataError(f"{p}: not a readable YAML file ({str(exc).splitlines()[0]})") from None
    if not isinstance(doc, dict):
        raise DataError(f"{p}: expected a YAML mapping with site_id, array_center and transponders")
    for key in ("site_id", "array_center", "transponders"):
        if key not in doc:
            raise DataError(f"{p}: missing {key!r}")
    ac = doc["array_center"]
    if not isinstance(ac, dict) or "lat" not in ac or "lon" not in ac:
        raise DataError(f"{p}: array_center needs lat and lon")
    center = EnuOrigin(
        lat_deg=_number(p, "array_center.lat", ac["lat"]),
        lon_deg=_number(p, "array_center.lon", ac["lon"]),
        h_m=_number(p, "array_center.alt", ac.get("alt", 0.0)),
    )
    tps = doc["transponders"]
    if not isinstance(tps, list) or not tps:
        raise DataError(f"{p}: transponders must be a non-empty list")
    site = str(doc["site_id"])
    out = []
    for k, tp in enumerate(tps):
        where = f"transponders[{k}]"
        if not isinstance(tp, dict):
            raise DataError(f"{p}: {where} must be a mapping")
        height = tp.get("height", tp.get("alt"))
        for key, value in (
            ("lat", tp.get("lat")),
            ("lon", tp.get("lon")),
            ("height", height),
            ("internal_delay", tp.get("internal_delay")),
        ):
            if value is None:
                raise DataError(f"{p}: {where}.{key} is missing")
        out.append(
            GnatssTransponder(
                pxp_id=str(tp.get("pxp_id") or f"{site}-{k + 1}"),
                lat_deg=_number(p, f"{where}.lat", tp["lat"]),
                lon_deg=_number(p, f"{where}.lon", tp["lon"]),
                height_m=_number(p, f"{where}.height", height),
                internal_delay_s=_number(p, f"{where}.internal_delay", tp["internal_delay"]),
                sv_mean_mps=None
                if tp.get("sv_mean") is None
                else _number(p, f"{where}.sv_mean", tp["sv_mean"]),
            )
        )
    solver = doc.get("solver") or {}
    if not isinstance(solver, dict):
        raise DataError(f"{p}: solver must be a mapping")
    atd = (doc.get("posfilter") or {}).get("atd_offsets") if isinstance(doc.get("posfilter"), dict) else None
    offsets = None
    if atd is not None:
        if not isinstance(atd, dict) or any(k not in atd for k in ("forward", "rightward", "downward")):
            raise DataError(f"{p}: posfilter.atd_offsets needs forward, rightward and downward (m)")
        offsets = tuple(
            _number(p, f"posfilter.atd_offsets.{k}", atd[k]) for k in ("forward", "rightward", "downward")
        )

    def num(section: dict, key: str, default: float) -> float:
        return default if section.get(key) is None else _number(p, key, section[key])

    inputs: dict[str, str] = {}
    for key, spec in (solver.get("input_files") or {}).items():
        if isinstance(spec, dict) and spec.get("path"):
            raw = Path(str(spec["path"]))
            inputs[str(key)] = str(raw if raw.is_absolute() or raw.exists() else p.parent / raw)
    return GnatssConfig(
        path=str(p),
        site_id=site,
        array_center=center,
        transponders=tuple(out),
        geoid_undulation_m=num(solver, "geoid_undulation", 0.0),
        harmonic_mean_start_depth_m=num(solver, "harmonic_mean_start_depth", 0.0),
        travel_times_variance_s2=num(doc, "travel_times_variance", 1e-10),
        travel_times_correction_s=num(doc, "travel_times_correction", 0.0),
        transducer_delay_time_s=num(doc, "transducer_delay_time", 0.0),
        distance_limit_m=num(solver, "distance_limit", 150.0),
        residual_limit_cm=num(solver, "residual_limit", 10000.0),
        residual_range_limit_cm=num(solver, "residual_range_limit", 20000.0),
        gps_sigma_limit_m=num(solver, "gps_sigma_limit", 0.05),
        inputs=inputs,
        atd_offsets_frd_m=offsets,
    )


def write_gnatss_config(path: str | Path, config: dict[str, Any]) -> Path:
    """Write a GNATSS configuration YAML (a plain mapping, as GNATSS's ``config.yaml`` documents it)."""
    import yaml

    p = Path(path)
    p.write_text(yaml.safe_dump(config, sort_keys=False), encoding="utf-8")
    return p


# ------------------------------------------------------------------- antenna positions and attitude


@dataclass(frozen=True, slots=True, kw_only=True)
class AntennaPositions:
    """A GNATSS ``GPS_POS_FREED`` file: GNSS antenna positions with their standard deviations.

    Attributes
    ----------
    t_s : (k,) float
        J2000 seconds.
    xyz_m : (k, 3) float
        Earth-fixed antenna positions, metres.
    sigma_xyz_m : (k, 3) float
        Standard deviations of X, Y, Z, metres.
    """

    path: str
    t_s: FloatArray
    xyz_m: FloatArray
    sigma_xyz_m: FloatArray
    line: IntArray
    qc: QcReport


def read_gps_pos_freed(path: str | Path) -> AntennaPositions:
    """Read a ``GPS_POS_FREED`` file: ``time flag X Y Z sigX sigY sigZ`` (J2000 s, text, m, m).

    A line is skipped (and recorded) without 8 fields, with a non-number, a position off the Earth's
    surface (not metres), a sigma not in (0, 10] m, or a time not after the previous.

    Raises
    ------
    DataError
        If the file cannot be read or holds no valid position.
    """
    p = Path(path)
    qc = QcReport()
    rows: list[list[float]] = []
    lines: list[int] = []
    last_t = -math.inf
    for number, text in read_lines(p, qc):
        if text.startswith("#"):
            qc.lines_read -= 1
            continue
        fields = text.split()
        if len(fields) != 8:
            reason = "truncated sentence" if len(fields) < 8 else "wrong field count"
            qc.add(p, number, reason, f"{len(fields)} fields, expected 8 (time, flag, X, Y, Z, 3 sigmas)")
            continue
        values = _floats([fields[0], *fields[2:]], p, number, qc)
        if values is None or not _check_ecef(values[1:4], p, number, qc):
            continue
        if not all(0.0 < s <= 10.0 for s in values[4:]):
            qc.add(p, number, "out of range", f"sigmas {values[4:]} m not in (0, 10] m")
            continue
        if values[0] <= last_t:
            qc.add(p, number, "time going backwards", f"{values[0]:.6f} s after {last_t:.6f} s")
            continue
        last_t = values[0]
        rows.append(values)
        lines.append(number)
    if not rows:
        raise _no_records(p, qc, "antenna position")
    a = np.asarray(rows, dtype=float)
    qc.records_kept = len(rows)
    return AntennaPositions(
        path=str(p),
        t_s=a[:, 0],
        xyz_m=a[:, 1:4],
        sigma_xyz_m=a[:, 4:7],
        line=np.asarray(lines, dtype=np.int64),
        qc=qc,
    )


def write_gps_pos_freed(
    path: str | Path, t_s: FloatArray, xyz_m: FloatArray, sigma_xyz_m: FloatArray
) -> Path:
    """Write a ``GPS_POS_FREED`` file (flag ``GPSPOS``)."""
    p = Path(path)
    with p.open("w", encoding="utf-8") as fh:
        for t, xyz, s in zip(t_s, xyz_m, sigma_xyz_m, strict=True):
            fh.write(
                f"{t:20.7f}    GPSPOS {xyz[0]:19.4f} {xyz[1]:17.4f} {xyz[2]:17.4f} "
                f"{s[0]:9.4f} {s[1]:9.4f} {s[2]:9.4f}\n"
            )
    return p


@dataclass(frozen=True, slots=True, kw_only=True)
class Attitude:
    """A roll-pitch-heading file: ``time roll pitch heading`` (J2000 s, degrees), optional covariance.

    Attributes
    ----------
    t_s : (k,) float
    rph_deg : (k, 3) float
        Roll, pitch, heading in degrees (heading clockwise from north).
    cov_deg2 : (k, 3, 3) float or None
        Their covariance, deg^2, where the file has the nine extra columns.
    """

    path: str
    t_s: FloatArray
    rph_deg: FloatArray
    cov_deg2: FloatArray | None
    line: IntArray
    qc: QcReport


def read_roll_pitch_heading(path: str | Path) -> Attitude:
    """Read a roll-pitch-heading file (4 columns, or 13 with the 3x3 covariance in deg^2).

    A line is skipped (and recorded) with another field count than the file's first data line, a
    non-number, a roll or pitch outside [-90, 90] deg, a heading outside [-360, 360] deg (radians
    would all be tiny: a file whose angles never exceed 2*pi in magnitude is refused), or a time not
    after the previous.

    Raises
    ------
    DataError
        If the file holds no valid line, or its angles look like radians.
    """
    p = Path(path)
    qc = QcReport()
    rows: list[list[float]] = []
    lines: list[int] = []
    width: int | None = None
    last_t = -math.inf
    for number, text in read_lines(p, qc):
        if text.startswith("#"):
            qc.lines_read -= 1
            continue
        fields = text.split()
        if width is None and len(fields) in (4, 13):
            width = len(fields)
        if len(fields) != width:
            qc.add(p, number, "wrong field count", f"{len(fields)} fields, expected {width or '4 or 13'}")
            continue
        values = _floats(fields, p, number, qc)
        if values is None:
            continue
        r, pitch, h = values[1:4]
        if abs(r) > 90.0 or abs(pitch) > 90.0 or abs(h) > 360.0:
            qc.add(p, number, "out of range", f"roll {r:g}, pitch {pitch:g}, heading {h:g} deg")
            continue
        if values[0] <= last_t:
            qc.add(p, number, "time going backwards", f"{values[0]:.6f} s after {last_t:.6f} s")
            continue
        last_t = values[0]
        rows.append(values)
        lines.append(number)
    if not rows:
        raise _no_records(p, qc, "attitude")
    a = np.asarray(rows, dtype=float)
    if a.shape[0] > 10 and float(np.max(np.abs(a[:, 3]))) <= 2.0 * math.pi:
        raise DataError(f"{p}: every heading is within +-2 pi: angles look like radians, expected degrees")
    qc.records_kept = len(rows)
    return Attitude(
        path=str(p),
        t_s=a[:, 0],
        rph_deg=a[:, 1:4],
        cov_deg2=a[:, 4:].reshape(-1, 3, 3) if a.shape[1] == 13 else None,
        line=np.asarray(lines, dtype=np.int64),
        qc=qc,
    )


def write_roll_pitch_heading(path: str | Path, t_s: FloatArray, rph_deg: FloatArray) -> Path:
    """Write a roll-pitch-heading file (``time roll pitch heading``, degrees)."""
    p = Path(path)
    with p.open("w", encoding="utf-8") as fh:
        for t, (r, pitch, h) in zip(t_s, rph_deg, strict=True):
            fh.write(f"{t:20.7f} {r:11.5f} {pitch:11.5f} {h:11.5f}\n")
    return p
