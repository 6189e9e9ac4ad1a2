"""Reader for GNSS-Acoustic ping files (the La Jolla Wave Glider format).

One ping per row, whitespace separated, ``#`` comments::

    # time0_transmit N0 E0 U0 sigN0 sigE0 sigU0 time1_receive N1 E1 U1 sigN1 sigE1 sigU1 TWTT(s)
    # Topocentric coordinates: Lat0=32.8668445 deg., Lon0=-117.2701205 deg., H0=-88.738 m
     49231669.0  55.7853 115.8632 53.3079 0.0168 0.0150 0.0177  49231669.3858  55.8253 ... 0.1858

Times are seconds after 2020-01-01 00:00:00 UTC; N, E, U are the surface transducer's topocentric
coordinates at transmit (0) and receive (1) with their 1-sigma; TWTT is the two-way travel time with
the transponder's turn-around delay removed. Positions are returned in the package's (E, N, U) order.
Malformed lines are skipped and recorded in a :class:`~oceanloc.io.qc.QcReport` (file and line).
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from oceanloc._typing import FloatArray, IntArray
from oceanloc.errors import ConfigError, DataError
from oceanloc.geo.enu import EnuOrigin
from oceanloc.io.qc import QcReport, read_lines

PUBLISHED_SOUND_SPEED_MPS: dict[str, float] = {
    "gnssa_data_20210723": 1499.3,
    "gnssa_data_20210823_SV3_1065": 1502.8,
    "gnssa_data_20210823_SV3_1063": 1504.7,
    "gnssa_data_20211210": 1504.4,
    "gnssa_data_20220321": 1495.4,
}
"""Harmonic-mean sound speeds used by Xie et al. (2023) for the five La Jolla surveys, keyed by file stem."""

GPS_EPOCH_2020_UNIX_S: float = 1577836800.0
"""2020-01-01 00:00:00 UTC as a Unix time: the files' time origin."""

_N_FIELDS = 15
_MAX_TWTT_S = 60.0
_ORIGIN_RE = re.compile(
    r"Lat0\s*=\s*(?P<lat>[-+0-9.eE]+).*?Lon0\s*=\s*(?P<lon>[-+0-9.eE]+).*?H0\s*=\s*(?P<h>[-+0-9.eE]+)"
)


@dataclass(frozen=True, slots=True, kw_only=True)
class GnssaSurvey:
    """One GNSS-Acoustic survey: ``n`` pings to one transponder.

    Attributes
    ----------
    name : str
        File stem (keys :data:`PUBLISHED_SOUND_SPEED_MPS`).
    path : str
        File the survey was read from.
    origin : EnuOrigin or None
        Geodetic origin of the topocentric frame (the header's Lat0, Lon0, H0), if the header has it.
    t_transmit_s, t_receive_s : (n,) float
        Transmit and receive times, seconds after 2020-01-01 UTC.
    transmit_enu_m, receive_enu_m : (n, 3) float
        Transducer positions (E, N, U) at transmit and receive, metres.
    sigma_transmit_enu_m, sigma_receive_enu_m : (n, 3) float
        Their 1-sigma uncertainties (E, N, U), metres.
    twtt_s : (n,) float
        Two-way travel times with the turn-around delay removed, seconds.
    line : (n,) int
        Line number of each ping in the file.
    qc : QcReport
        Lines skipped while reading, with reasons.
    """

    name: str
    path: str
    origin: EnuOrigin | None
    t_transmit_s: FloatArray
    t_receive_s: FloatArray
    transmit_enu_m: FloatArray
    receive_enu_m: FloatArray
    sigma_transmit_enu_m: FloatArray
    sigma_receive_enu_m: FloatArray
    twtt_s: FloatArray
    line: IntArray
    qc: QcReport

    @property
    def n_pings(self) -> int:
        return int(self.twtt_s.shape[0])

    @property
    def turnaround_s(self) -> FloatArray:
        """``receive - transmit - TWTT``: the transponder's turn-around delay already removed, (n,) s."""
        return self.t_receive_s - self.t_transmit_s - self.twtt_s

    @property
    def horizontal_offset_m(self) -> FloatArray:
        """Horizontal distance of the transmit position from the frame origin's vertical, (n,) m."""
        return np.hypot(self.transmit_enu_m[:, 0], self.transmit_enu_m[:, 1])


def lajolla_paths() -> list[Path]:
    """The five packaged La Jolla survey files, in date order."""
    folder = resources.files("oceanloc.data.gnssa_lajolla")
    return sorted(Path(str(p)) for p in folder.iterdir() if p.name.startswith("gnssa_data_"))


def published_sound_speed_mps(path: str | Path) -> float | None:
    """The published sound speed for a La Jolla file (by file stem), or None if unknown."""
    return PUBLISHED_SOUND_SPEED_MPS.get(Path(path).stem)


def survey_sound_speeds_mps(paths: Sequence[str | Path], given: Sequence[float] = ()) -> list[float]:
    """One sound speed per survey file: the one given for all, one given per file, or the published one.

    Raises
    ------
    ConfigError
        If the number given is neither one nor one per file, or a file has no published speed and none
        was given.
    """
    given = list(given)
    if len(given) == 1:
        return given * len(paths)
    if given and len(given) != len(paths):
        raise ConfigError(f"--sound-speed: give one value or one per file ({len(paths)}), got {len(given)}")
    if given:
        return given
    out = []
    for p in paths:
        c = published_sound_speed_mps(p)
        if c is None:
            raise ConfigError(f"{p}: no published sound speed for this file; give --sound-speed")
        out.append(c)
    return out


def read_gnssa(path: str | Path) -> GnssaSurvey:
    """Read a GNSS-Acoustic ping file.

    A line is skipped (and recorded in ``qc``) if it does not have 15 fields, has a non-numeric field,
    a NaN or infinite value, a non-positive sigma, a TWTT outside (0, 60) s, a receive time before the
    transmit time, or a transmit time earlier than the previous ping's (time going backwards). Lines
    that parse are kept even if the ping is an outlier: that is the estimator's business.

    Raises
    ------
    DataError
        If the file cannot be read or holds no valid ping.
    """
    p = Path(path)
    qc = QcReport()
    origin: EnuOrigin | None = None
    rows: list[list[float]] = []
    lines: list[int] = []
    last_t = -math.inf
    for number, text in read_lines(p, qc):
        if text.startswith("#"):
            qc.lines_read -= 1
            match = _ORIGIN_RE.search(text)
            if match and origin is None:
                try:
                    origin = EnuOrigin(
                        lat_deg=float(match["lat"]), lon_deg=float(match["lon"]), h_m=float(match["h"])
                    )
                except (ValueError, DataError) as exc:
                    qc.add(p, number, "non-numeric field", f"header origin: {exc}")
            continue
        fields = text.split()
        if len(fields) != _N_FIELDS:
            reason = "truncated sentence" if len(fields) < _N_FIELDS else "wrong field count"
            qc.add(p, number, reason, f"{len(fields)} fields, expected {_N_FIELDS}")
            continue
        try:
            values = [float(f) for f in fields]
        except ValueError:
            bad = next(i for i, f in enumerate(fields) if not _is_float(f))
            qc.add(p, number, "non-numeric field", f"field {bad + 1}: {fields[bad]!r}")
            continue
        if not all(math.isfinite(v) for v in values):
            qc.add(p, number, "NaN or infinite value")
            continue
        sigmas = values[4:7] + values[11:14]
        if min(sigmas) <= 0.0:
            qc.add(p, number, "non-numeric field", "a position sigma is not positive")
            continue
        twtt = values[14]
        if not 0.0 < twtt < _MAX_TWTT_S:
            qc.add(p, number, "negative or absurd range", f"TWTT {twtt} s")
            continue
        if values[7] < values[0]:
            qc.add(p, number, "time going backwards", "receive time before transmit time")
            continue
        if values[0] <= last_t:
            qc.add(p, number, "time going backwards", f"transmit {values[0]} s after {last_t} s")
            continue
        last_t = values[0]
        rows.append(values)
        lines.append(number)
    if not rows:
        detail = "; ".join(str(i) for i in qc.issues[:3])
        raise DataError(f"{p}: no valid ping" + (f" ({detail})" if detail else ""))
    a = np.asarray(rows, dtype=float)
    enu = [1, 0, 2]  # file order is N, E, U
    qc.records_kept = len(rows)
    return GnssaSurvey(
        name=p.stem,
        path=str(p),
        origin=origin,
        t_transmit_s=a[:, 0],
        t_receive_s=a[:, 7],
        transmit_enu_m=a[:, 1:4][:, enu],
        receive_enu_m=a[:, 8:11][:, enu],
        sigma_transmit_enu_m=a[:, 4:7][:, enu],
        sigma_receive_enu_m=a[:, 11:14][:, enu],
        twtt_s=a[:, 14],
        line=np.asarray(lines, dtype=np.int64),
        qc=qc,
    )


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True
