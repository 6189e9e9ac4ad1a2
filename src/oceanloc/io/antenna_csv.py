"""A generic CSV of GNSS antenna positions with covariance and attitude: read, check, write.

One header line names the columns (case-insensitive, surrounding spaces ignored, the aliases of
:data:`COLUMNS` accepted), then one comma-separated row per epoch; ``#`` lines are comments. Columns:

- **time**, one of: ``time_utc`` (ISO 8601, UTC; a ``Z`` or an offset is honoured, none means UTC),
  ``t_j2000_s`` (seconds after 2000-01-01 12:00:00, GNATSS's base), ``t_unix_s`` (POSIX seconds, UTC)
  or ``t_gps_s`` (seconds of GPS time since 1980-01-06 00:00:00; converted to UTC with the GPS-UTC
  leap-second table :data:`GPS_UTC_LEAPS`). Every form is converted to J2000 seconds counted as GNATSS
  counts them (calendar arithmetic, no leap second inside the count), the base of the ``pxp_tt`` travel
  times (:mod:`oceanloc.io.gnatss`): ``t_j2000 = t_unix - 946728000``.
- **antenna position**, either geodetic ``lat_deg, lon_deg, height_m`` (WGS84, ellipsoidal height) or
  Earth-fixed ``x_m, y_m, z_m`` (WGS84 ECEF), metres.
- **its covariance**, one of: standard deviations ``sd_e_m, sd_n_m, sd_u_m`` (local east, north, up at
  the antenna) or ``sd_x_m, sd_y_m, sd_z_m`` (ECEF, as GNATSS's ``GPS_POS_FREED``), or the upper triangle
  of the full matrix, ``cov_ee_m2, cov_en_m2, cov_eu_m2, cov_nn_m2, cov_nu_m2, cov_uu_m2`` (ENU) or
  ``cov_xx_m2, cov_xy_m2, cov_xz_m2, cov_yy_m2, cov_yz_m2, cov_zz_m2`` (ECEF).
- **attitude**: ``roll_deg, pitch_deg, heading_deg`` (:mod:`oceanloc.models.attitude` conventions: roll
  starboard down, pitch bow up, heading clockwise from north), degrees. Optional as a group: without
  them the attitude comes from a separate file.

The reader returns ECEF positions and ECEF covariances: an ENU covariance ``C_enu`` at a point of
latitude ``phi`` and longitude ``lam`` becomes ``R C_enu R^T`` with ``R = [e n u]`` the local unit
vectors in ECEF at that point (each row its own ``R``).

QC (as :mod:`oceanloc.io.gnatss`): a row is skipped and recorded (``file:line``, reason, the field)
with the wrong number of fields, a field that is not a number (or not an ISO 8601 time), a NaN, a
latitude outside [-90, 90] deg, a longitude outside [-180, 360] deg, a height outside
:data:`~oceanloc.io.qc.HEIGHT_RANGE_M`, an ECEF position off the Earth's surface (not metres), a
standard deviation not in (0, 10] m, a covariance not symmetric positive definite or with a variance
above 100 m^2, a roll or pitch outside [-90, 90] deg, a heading outside [-360, 360] deg, or a time not
after the previous row's. A file without one usable row, without a required column, or with two
forms of one quantity raises a one-line :class:`~oceanloc.errors.DataError` naming the file, the
column and the accepted names.
"""

from __future__ import annotations

import datetime as dt
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pymap3d

from oceanloc._typing import FloatArray, IntArray
from oceanloc.errors import ConfigError, DataError
from oceanloc.geo.ecef import enu_rotation_at
from oceanloc.io.gnatss import EARTH_RADIUS_RANGE_M, J2000_EPOCH, J2000_UNIX_S, datetime_from_j2000
from oceanloc.io.qc import HEIGHT_RANGE_M, QcReport, read_lines

GPS_EPOCH_UNIX_S = 315_964_800.0
"""1980-01-06 00:00:00 UTC, the origin of GPS time, as a Unix time."""

GPS_UTC_LEAPS: tuple[tuple[str, int], ...] = (
    ("1981-07-01", 1), ("1982-07-01", 2), ("1983-07-01", 3), ("1985-07-01", 4), ("1988-01-01", 5),
    ("1990-01-01", 6), ("1991-01-01", 7), ("1992-07-01", 8), ("1993-07-01", 9), ("1994-07-01", 10),
    ("1996-01-01", 11), ("1997-07-01", 12), ("1999-01-01", 13), ("2006-01-01", 14), ("2009-01-01", 15),
    ("2012-07-01", 16), ("2015-07-01", 17), ("2017-01-01", 18),
)  # fmt: skip
"""GPS - UTC in seconds from each UTC date on (IERS Bulletin C; no leap second announced after 2017)."""

TIME_FORMS: tuple[str, ...] = ("iso", "j2000", "unix", "gps")
POSITION_FORMS: tuple[str, ...] = ("geodetic", "ecef")
COVARIANCE_FORMS: tuple[str, ...] = ("sd_enu", "sd_xyz", "cov_enu", "cov_xyz")

COLUMNS: dict[str, tuple[str, ...]] = {
    "time_utc": ("time_utc", "time", "utc", "datetime", "timestamp", "time_iso", "iso_time", "iso_string"),
    "t_j2000_s": ("t_j2000_s", "time_j2000_s", "j2000_s", "t_j2000", "j2000", "time_j2000"),
    "t_unix_s": ("t_unix_s", "time_unix_s", "unix_s", "t_unix", "unix_time", "posix_s"),
    "t_gps_s": ("t_gps_s", "time_gps_s", "gps_s", "t_gps", "gps_time_s", "gps_seconds"),
    "lat_deg": ("lat_deg", "lat", "latitude", "latitude_deg"),
    "lon_deg": ("lon_deg", "lon", "longitude", "longitude_deg", "long_deg"),
    "height_m": ("height_m", "h_m", "height", "ellipsoidal_height_m", "hae_m", "alt_m"),
    **{f"{a}_m": (f"{a}_m", a, f"ecef_{a}_m", f"ecef_{a}") for a in "xyz"},
    **{
        f"sd_{a}_m": (f"sd_{a}_m", f"sd_{a}", f"sigma_{a}_m", f"sigma_{a}", f"std_{a}_m", f"std_{a}")
        for a in "enuxyz"
    },
    **{f"cov_{ab}_m2": (f"cov_{ab}_m2", f"cov_{ab}") for ab in ("ee", "en", "eu", "nn", "nu", "uu")},
    **{f"cov_{ab}_m2": (f"cov_{ab}_m2", f"cov_{ab}") for ab in ("xx", "xy", "xz", "yy", "yz", "zz")},
    "roll_deg": ("roll_deg", "roll"),
    "pitch_deg": ("pitch_deg", "pitch"),
    "heading_deg": ("heading_deg", "heading", "yaw_deg", "yaw", "hdg_deg"),
}
"""Each canonical column and the header names accepted for it (case-insensitive)."""

_TIME_OF_FORM = {"iso": "time_utc", "j2000": "t_j2000_s", "unix": "t_unix_s", "gps": "t_gps_s"}
_POSITION_OF_FORM = {"geodetic": ("lat_deg", "lon_deg", "height_m"), "ecef": ("x_m", "y_m", "z_m")}
_TRIANGLE = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))
_COVARIANCE_OF_FORM = {
    "sd_enu": ("sd_e_m", "sd_n_m", "sd_u_m"),
    "sd_xyz": ("sd_x_m", "sd_y_m", "sd_z_m"),
    "cov_enu": tuple(f"cov_{'enu'[i]}{'enu'[j]}_m2" for i, j in _TRIANGLE),
    "cov_xyz": tuple(f"cov_{'xyz'[i]}{'xyz'[j]}_m2" for i, j in _TRIANGLE),
}
_ATTITUDE = ("roll_deg", "pitch_deg", "heading_deg")
_ALIAS = {alias: name for name, aliases in COLUMNS.items() for alias in aliases}


@dataclass(frozen=True, slots=True, kw_only=True)
class AntennaCsv:
    """An antenna CSV, read: time-ordered antenna positions (ECEF) with covariance, and attitude.

    Attributes
    ----------
    path : str
    t_s : (k,) float
        J2000 seconds (the ``pxp_tt`` travel times' base), strictly increasing.
    xyz_m : (k, 3) float
        WGS84 Earth-fixed antenna positions, metres.
    cov_xyz_m2 : (k, 3, 3) float
        Their ECEF covariance, m^2 (converted from the file's form).
    rph_deg : (k, 3) float or None
        Roll, pitch, heading, degrees (None when the file has no attitude columns).
    line : (k,) int
        Source line of each row.
    forms : tuple of str
        The file's time, position and covariance forms (of :data:`TIME_FORMS`, :data:`POSITION_FORMS`,
        :data:`COVARIANCE_FORMS`).
    qc : QcReport
    """

    path: str
    t_s: FloatArray
    xyz_m: FloatArray
    cov_xyz_m2: FloatArray
    rph_deg: FloatArray | None
    line: IntArray
    forms: tuple[str, str, str]
    qc: QcReport


def _leap_unix_s() -> tuple[tuple[float, int], ...]:
    return tuple(
        (dt.datetime.fromisoformat(day).replace(tzinfo=dt.UTC).timestamp(), n) for day, n in GPS_UTC_LEAPS
    )


_LEAPS_UNIX_S = _leap_unix_s()


def gps_to_unix_s(t_gps_s: float) -> float:
    """GPS seconds (since 1980-01-06, GPS time) to a POSIX (UTC) time, through :data:`GPS_UTC_LEAPS`."""
    leap = 0
    for u, n in _LEAPS_UNIX_S:
        if t_gps_s >= u - GPS_EPOCH_UNIX_S + n:
            leap = n
    return t_gps_s + GPS_EPOCH_UNIX_S - leap


def unix_to_gps_s(t_unix_s: float) -> float:
    """A POSIX (UTC) time to GPS seconds (the inverse of :func:`gps_to_unix_s`)."""
    leap = 0
    for u, n in _LEAPS_UNIX_S:
        if t_unix_s >= u:
            leap = n
    return t_unix_s - GPS_EPOCH_UNIX_S + leap


def _iso_j2000(text: str) -> float | None:
    try:
        stamp = dt.datetime.fromisoformat(text.replace("Z", "+00:00").replace("z", "+00:00"))
    except ValueError:
        return None
    if stamp.tzinfo is not None:
        stamp = stamp.astimezone(dt.UTC).replace(tzinfo=None)
    return (stamp - J2000_EPOCH).total_seconds()


def _header(p: Path) -> tuple[int, list[str]] | None:
    """The first non-comment line's column names, lower-case, or None if the file cannot be read."""
    try:
        with p.open("r", encoding="utf-8-sig", errors="replace") as fh:
            for number, text in enumerate(fh, start=1):
                s = text.strip()
                if s and not s.startswith("#"):
                    return number, [f.strip().lower() for f in s.split(",")]
    except OSError:
        return None
    return None


def is_antenna_csv(path: str | Path) -> bool:
    """Whether a file looks like an antenna CSV: a comma-separated first line naming a time column."""
    head = _header(Path(path))
    if head is None or len(head[1]) < 2:
        return False
    return any(_ALIAS.get(f, "").startswith(("time_", "t_")) for f in head[1])


def _pick(p: Path, index: dict[str, int], forms: dict[str, tuple[str, ...]], what: str, *, required: bool):
    """The one form whose columns are all present (None if none and not required)."""
    full = [f for f, cols in forms.items() if all(c in index for c in cols)]
    if len(full) > 1:
        raise DataError(f"{p}: {what} is given twice ({' and '.join(full)} columns): keep one")
    if full:
        return full[0]
    partial = [(f, cols) for f, cols in forms.items() if any(c in index for c in cols)]
    if partial:
        cols = partial[0][1]
        missing = next(c for c in cols if c not in index)
        raise DataError(
            f"{p}: {what} column {missing!r} missing (accepted names: {', '.join(COLUMNS[missing])})"
        )
    if required:
        accepted = " | ".join(", ".join(cols) for cols in forms.values())
        first = next(iter(forms.values()))[0]
        raise DataError(
            f"{p}: no {what} column (accepted: {accepted}; aliases e.g. {', '.join(COLUMNS[first][1:])})"
        )
    return None


def read_antenna_csv(path: str | Path) -> AntennaCsv:
    """Read an antenna CSV (see the module docstring for the columns, conversions and checks).

    Raises
    ------
    DataError
        Missing file, header without a required column (the message names it and its accepted names),
        or no usable row.
    """
    p = Path(path)
    qc = QcReport()
    lines = list(read_lines(p, qc))
    body = [(n, t) for n, t in lines if not t.startswith("#")]
    qc.lines_read -= len(lines) - len(body)
    if not body:
        raise DataError(f"{p}: no header line (expected column names such as time_utc, lat_deg, ...)")
    head_line, head_text = body[0]
    qc.lines_read -= 1
    names = [f.strip().lower() for f in head_text.split(",")]
    index: dict[str, int] = {}
    for i, name in enumerate(names):
        canon = _ALIAS.get(name)
        if canon is None:
            continue
        if canon in index:
            raise DataError(f"{p}:{head_line}: columns {names[index[canon]]!r} and {name!r} are both {canon}")
        index[canon] = i
    times = {f: (c,) for f, c in _TIME_OF_FORM.items()}
    t_form = _pick(p, index, times, "time", required=True)
    pos_form = _pick(p, index, _POSITION_OF_FORM, "antenna position", required=True)
    cov_form = _pick(p, index, _COVARIANCE_OF_FORM, "position covariance", required=True)
    has_att = _pick(p, index, {"attitude": _ATTITUDE}, "attitude", required=False) is not None
    t_col = index[_TIME_OF_FORM[t_form]]
    num_names = [
        *_POSITION_OF_FORM[pos_form],
        *_COVARIANCE_OF_FORM[cov_form],
        *(_ATTITUDE if has_att else ()),
    ]
    num_cols = [index[c] for c in num_names]
    width = len(names)
    values: list[list[float]] = []
    t_list: list[float] = []
    numbers: list[int] = []
    for number, text in body[1:]:
        fields = [f.strip() for f in text.split(",")]
        if len(fields) != width:
            reason = "truncated sentence" if len(fields) < width else "wrong field count"
            qc.add(p, number, reason, f"{len(fields)} fields, expected {width} (the header's)")
            continue
        t = _time(fields[t_col], t_form)
        if t is None:
            what = "an ISO 8601 time" if t_form == "iso" else "a number"
            qc.add(p, number, "non-numeric field", f"{names[t_col]}: {fields[t_col]!r} is not {what}")
            continue
        row: list[float] = []
        for col in num_cols:
            try:
                row.append(float(fields[col]))
            except ValueError:
                qc.add(p, number, "non-numeric field", f"{names[col]}: {fields[col]!r}")
                break
        else:
            if not all(math.isfinite(v) for v in (t, *row)):
                qc.add(p, number, "NaN or infinite value")
                continue
            t_list.append(t)
            values.append(row)
            numbers.append(number)
    a = np.asarray(values, dtype=float).reshape(-1, len(num_names))
    t_all = np.asarray(t_list, dtype=float)
    xyz, cov, why = _convert(a, pos_form, cov_form)
    if has_att:
        att = a[:, -3:]
        for i in np.flatnonzero(
            (np.abs(att[:, 0]) > 90.0) | (np.abs(att[:, 1]) > 90.0) | (np.abs(att[:, 2]) > 360.0)
        ):
            if why[i] is None:
                r, pt, h = att[i]
                detail = f"roll {r:g}, pitch {pt:g} deg (allowed [-90, 90]), heading {h:g} deg ([-360, 360])"
                why[i] = ("out of range", detail)
    keep: list[int] = []
    last = -math.inf
    for i, w in enumerate(why):
        if w is not None:
            qc.add(p, numbers[i], *w)
        elif t_all[i] <= last:
            qc.add(p, numbers[i], "time going backwards", f"{t_all[i]:.6f} s after {last:.6f} s (J2000)")
        else:
            last = t_all[i]
            keep.append(i)
    qc.issues.sort(key=lambda i: (i.file, i.line))
    if not keep:
        detail = "; ".join(str(i) for i in qc.issues[:3])
        raise DataError(f"{p}: no valid antenna position" + (f" ({detail})" if detail else ""))
    rph = a[keep, -3:] if has_att else None
    if rph is not None and rph.shape[0] > 10 and float(np.max(np.abs(rph[:, 2]))) <= 2.0 * math.pi:
        raise DataError(f"{p}: every heading is within +-2 pi: angles look like radians, expected degrees")
    qc.records_kept = len(keep)
    return AntennaCsv(
        path=str(p),
        t_s=t_all[keep],
        xyz_m=xyz[keep],
        cov_xyz_m2=cov[keep],
        rph_deg=rph,
        line=np.asarray([numbers[i] for i in keep], dtype=np.int64),
        forms=(t_form, pos_form, cov_form),
        qc=qc,
    )


def _time(text: str, form: str) -> float | None:
    if form == "iso":
        return _iso_j2000(text)
    try:
        v = float(text)
    except ValueError:
        return None
    if not math.isfinite(v):
        return v
    if form == "j2000":
        return v
    if form == "unix":
        return v - J2000_UNIX_S
    return gps_to_unix_s(v) - J2000_UNIX_S


Why = list[tuple[str, str] | None]


def _convert(a: FloatArray, pos_form: str, cov_form: str) -> tuple[FloatArray, FloatArray, Why]:
    """ECEF positions and covariances of the parsed rows, and per row the first problem (or None)."""
    k = a.shape[0]
    why: Why = [None] * k

    def flag(mask: np.ndarray, detail: Callable[[int], str]) -> None:
        for i in np.flatnonzero(mask):
            if why[i] is None:
                why[i] = ("out of range", detail(i))

    p3 = a[:, :3]
    if pos_form == "geodetic":
        lat, lon, h = p3.T
        lo, hi = HEIGHT_RANGE_M
        flag(np.abs(lat) > 90.0, lambda i: f"latitude {lat[i]:.12g} deg is outside [-90, 90] deg")
        flag(
            (lon < -180.0) | (lon > 360.0),
            lambda i: f"longitude {lon[i]:.12g} deg is outside [-180, 360] deg",
        )
        flag(
            (h < lo) | (h > hi), lambda i: f"height {h[i]:.12g} m is outside [{lo:g}, {hi:g}] m (ellipsoidal)"
        )
        lat_c, lon_c = np.clip(lat, -90.0, 90.0), lon
        x, y, z = pymap3d.geodetic2ecef(lat_c, lon_c, h)
        xyz = np.stack([x, y, z], axis=-1)
    else:
        xyz = p3.copy()
        r = np.linalg.norm(xyz, axis=1)
        lo, hi = EARTH_RADIUS_RANGE_M
        flag(
            (r < lo) | (r > hi),
            lambda i: f"|XYZ| {r[i]:.1f} m is not an Earth-fixed surface position (metres)",
        )
        with np.errstate(all="ignore"):
            lat_c, lon_c, _ = pymap3d.ecef2geodetic(xyz[:, 0], xyz[:, 1], xyz[:, 2])
    if cov_form.startswith("sd"):
        c = a[:, 3:6]
        flag(
            np.any((c <= 0.0) | (c > 10.0), axis=1),
            lambda i: f"standard deviations {c[i].tolist()} m not in (0, 10] m",
        )
        local = np.einsum("ki,ij->kij", c**2, np.eye(3))
    else:
        local = np.empty((k, 3, 3))
        for col, (i, j) in enumerate(_TRIANGLE):
            local[:, i, j] = local[:, j, i] = a[:, 3 + col]
        d = np.diagonal(local, axis1=1, axis2=2)
        eig = np.linalg.eigvalsh(local) if k else np.zeros((0, 3))
        tol = 1e-12 * np.max(np.abs(d), axis=1) if k else np.zeros(0)
        flag(np.any(d > 100.0, axis=1), lambda i: f"variance {d[i].max():g} m^2 > 100 m^2 (units: m^2?)")
        flag(
            eig[:, 0] <= tol,
            lambda i: f"covariance is not positive definite (smallest eigenvalue {eig[i, 0]:.3g} m^2)",
        )
    if cov_form.endswith("enu"):
        rot = np.swapaxes(enu_rotation_at(lat_c, lon_c), -1, -2)
        cov = rot @ local @ np.swapaxes(rot, -1, -2)
    else:
        cov = local
    return xyz, cov, why


def write_antenna_csv(
    path: str | Path,
    t_s: FloatArray,
    xyz_m: FloatArray,
    cov_xyz_m2: FloatArray,
    rph_deg: FloatArray | None = None,
    *,
    time: str = "j2000",
    position: str = "ecef",
    covariance: str = "cov_xyz",
) -> Path:
    """Write an antenna CSV in any of the reader's forms (canonical column names).

    Parameters
    ----------
    t_s : (k,) float
        J2000 seconds.
    xyz_m, cov_xyz_m2 : (k, 3), (k, 3, 3) float
        ECEF positions and covariances.
    rph_deg : (k, 3) float or None
        Roll, pitch, heading (no attitude columns when None).
    time, position, covariance : str
        Forms (:data:`TIME_FORMS`, :data:`POSITION_FORMS`, :data:`COVARIANCE_FORMS`). The ``sd_*`` forms
        keep the standard deviations only (lossless when the matrix is diagonal in that frame).

    Digits: times to 1 us (ISO) or 0.1 us, positions to 0.1 um (latitude and longitude to 1e-12 deg),
    covariance entries and angles to 12 significant digits.
    """
    if time not in TIME_FORMS or position not in POSITION_FORMS or covariance not in COVARIANCE_FORMS:
        raise ConfigError(
            f"antenna CSV forms: time in {TIME_FORMS}, position in {POSITION_FORMS}, covariance in "
            f"{COVARIANCE_FORMS}; got {time!r}, {position!r}, {covariance!r}"
        )
    p = Path(path)
    t = np.asarray(t_s, dtype=float)
    xyz = np.asarray(xyz_m, dtype=float)
    cov = np.asarray(cov_xyz_m2, dtype=float)
    lat, lon, h = pymap3d.ecef2geodetic(xyz[:, 0], xyz[:, 1], xyz[:, 2])
    if covariance.endswith("enu"):
        rot = np.swapaxes(enu_rotation_at(lat, lon), -1, -2)
        cov = np.swapaxes(rot, -1, -2) @ cov @ rot
    cols = [_TIME_OF_FORM[time], *_POSITION_OF_FORM[position], *_COVARIANCE_OF_FORM[covariance]]
    if rph_deg is not None:
        cols += list(_ATTITUDE)
    with p.open("w", encoding="utf-8", newline="") as fh:
        fh.write(",".join(cols) + "\n")
        for k in range(t.size):
            if time == "iso":
                stamp = datetime_from_j2000(t[k]).strftime("%Y-%m-%dT%H:%M:%S.%fZ")
            elif time == "j2000":
                stamp = f"{t[k]:.7f}"
            elif time == "unix":
                stamp = f"{t[k] + J2000_UNIX_S:.7f}"
            else:
                stamp = f"{unix_to_gps_s(t[k] + J2000_UNIX_S):.7f}"
            if position == "geodetic":
                pos = [f"{lat[k]:.12f}", f"{lon[k]:.12f}", f"{h[k]:.7f}"]
            else:
                pos = [f"{v:.7f}" for v in xyz[k]]
            if covariance.startswith("sd"):
                var = [f"{math.sqrt(max(cov[k, i, i], 0.0)):.12g}" for i in range(3)]
            else:
                var = [f"{cov[k, i, j]:.12g}" for i, j in _TRIANGLE]
            att = [] if rph_deg is None else [f"{v:.12g}" for v in np.asarray(rph_deg, float)[k]]
            fh.write(",".join([stamp, *pos, *var, *att]) + "\n")
    return p
