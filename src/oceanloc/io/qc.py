"""Quality control of log files: every skipped line is named (file, line, reason) and counted.

Field logs contain what field logs contain: corrupt sentences, truncated lines, a NaN, a range of
minus one metre, a clock stepping backwards, a beacon nobody configured, an empty file, a file saved in
the wrong encoding. Readers skip such lines, record each in a :class:`QcReport` and keep every valid
line; nothing crashes and nothing valid is lost. :func:`read_lines` is the shared entry point that
turns raw bytes into numbered text lines, recording lines that are not valid text; :func:`decode_line`
is its rule for one line, which the live streams apply to each line they receive.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from oceanloc.errors import DataError

REASONS: tuple[str, ...] = (
    "bad checksum",
    "truncated sentence",
    "non-numeric field",
    "NaN or infinite value",
    "negative or absurd range",
    "time going backwards",
    "unknown beacon id",
    "empty file",
    "wrong encoding",
    "unsupported sentence",
    "wrong field count",
    "invalid fix",
    "duplicate record",
    "gross outlier",
    "out of range",
)
"""Reasons a reader may give; free text is allowed, these are the ones the readers use."""

TIME_RANGE_UNIX_S: tuple[float, float] = (315_964_800.0, 4_102_444_800.0)
"""Times a log or journal record may carry: 1980-01-06 (the GPS epoch) to 2100-01-01 UTC, Unix seconds."""

LAT_RANGE_DEG: tuple[float, float] = (-90.0, 90.0)
LON_RANGE_DEG: tuple[float, float] = (-180.0, 180.0)
"""WGS84 latitude and longitude ranges, degrees (an NMEA longitude is at most 180 degrees E or W)."""

HEIGHT_RANGE_M: tuple[float, float] = (-1_000.0, 10_000.0)
"""Ellipsoidal heights a GPS antenna on a survey vehicle may have, metres: the geoid lies within about
-107 to +86 m of the ellipsoid, so anything beyond these bounds is a corrupt field."""

BEACON_ID_RANGE: tuple[int, int] = (0, 2**31 - 1)
"""Beacon ids a reader or the journal accepts (non-negative 32-bit integers: SQLite and numpy hold them)."""

MAX_RANGE_M: float = 10_000.0
"""Longest acoustic range a reader or the journal accepts, metres (USBL and LBL systems reach a few km)."""


def time_problem(t_unix_s: float) -> str | None:
    """None if a Unix time is within :data:`TIME_RANGE_UNIX_S`, else a message naming the range."""
    problem = out_of_range("time", t_unix_s, TIME_RANGE_UNIX_S, "s")
    return None if problem is None else f"{problem} (Unix time: 1980-01-06 to 2100-01-01 UTC)"


def out_of_range(name: str, value: float, bounds: tuple[float, float], unit: str) -> str | None:
    """None if ``bounds[0] <= value <= bounds[1]`` (and finite), else a message naming the field and range.

    Example: ``out_of_range("latitude", 99.0, LAT_RANGE_DEG, "deg")`` gives
    ``"latitude 99 deg is outside [-90, 90] deg"``.
    """
    lo, hi = bounds
    if math.isfinite(value) and lo <= value <= hi:
        return None
    return f"{name} {value:.12g} {unit} is outside [{lo:.12g}, {hi:.12g}] {unit}"


@dataclass(frozen=True, slots=True, kw_only=True)
class QcIssue:
    """One skipped line.

    Attributes
    ----------
    file : str
        File name as given to the reader.
    line : int
        1-based line number (0 for a whole-file issue such as an empty file).
    reason : str
        Short reason, one of :data:`REASONS` where it applies.
    detail : str
        What exactly was wrong (the field, the value), for the human reading the summary.
    """

    file: str
    line: int
    reason: str
    detail: str = ""

    def __str__(self) -> str:
        where = f"{self.file}:{self.line}" if self.line else self.file
        return f"{where}: {self.reason}" + (f" ({self.detail})" if self.detail else "")


@dataclass(slots=True)
class QcReport:
    """Accumulates the issues of one or more files and the number of lines read and kept."""

    issues: list[QcIssue] = field(default_factory=list)
    lines_read: int = 0
    records_kept: int = 0

    def add(self, file: str | Path, line: int, reason: str, detail: str = "") -> None:
        """Record one skipped line."""
        self.issues.append(QcIssue(file=str(file), line=line, reason=reason, detail=detail))

    def counts(self) -> dict[str, int]:
        """Number of skipped lines per reason."""
        return dict(Counter(i.reason for i in self.issues))

    def counts_by_file(self) -> dict[str, dict[str, int]]:
        """Number of skipped lines per file and reason."""
        out: dict[str, Counter[str]] = {}
        for i in self.issues:
            out.setdefault(i.file, Counter())[i.reason] += 1
        return {f: dict(c) for f, c in out.items()}

    def merge(self, other: QcReport) -> QcReport:
        """A new report holding both reports' issues and counts."""
        return QcReport(
            issues=[*self.issues, *other.issues],
            lines_read=self.lines_read + other.lines_read,
            records_kept=self.records_kept + other.records_kept,
        )

    def summary(self, max_lines: int = 20) -> str:
        """Human-readable summary: counts per reason, then the first ``max_lines`` issues."""
        head = f"{self.records_kept} records kept, {len(self.issues)} lines skipped of {self.lines_read}"
        if not self.issues:
            return head
        parts = [
            head,
            "skipped by reason: " + ", ".join(f"{k}: {v}" for k, v in sorted(self.counts().items())),
        ]
        parts += [f"  {i}" for i in self.issues[:max_lines]]
        if len(self.issues) > max_lines:
            parts.append(f"  ... and {len(self.issues) - max_lines} more")
        return "\n".join(parts)


def read_lines(path: str | Path, qc: QcReport) -> Iterator[tuple[int, str]]:
    """Yield ``(line_number, text)`` for each non-blank line of a text file.

    The file is read as bytes and decoded line by line as UTF-8 (ASCII logs are UTF-8); a line that is
    not valid UTF-8 or holds NUL bytes is recorded as ``wrong encoding`` and skipped. A UTF-16 file
    (byte-order mark) is decoded as such. An empty file is recorded as ``empty file``. A missing or
    unreadable file is a :class:`DataError`: there is nothing to salvage.
    """
    p = Path(path)
    try:
        raw = p.read_bytes()
    except FileNotFoundError:
        raise DataError(f"{p}: file not found") from None
    except OSError as exc:
        raise DataError(f"{p}: cannot read ({exc})") from None
    if not raw.strip():
        qc.add(p, 0, "empty file")
        return
    if raw[:2] in (b"\xff\xfe", b"\xfe\xff"):
        try:
            raw = raw.decode("utf-16").encode("utf-8")
        except UnicodeDecodeError:
            qc.add(p, 0, "wrong encoding", "UTF-16 byte-order mark but undecodable content")
            return
    if raw.isascii() and not any(c in raw for c in _NOT_PLAIN_ASCII):
        # The common case, decoded at once: for ASCII without these bytes, str.splitlines and
        # str.strip split and strip exactly as bytes.splitlines and decode_line do.
        for number, line in enumerate(raw.decode("ascii").splitlines(), start=1):
            text = line.strip()
            if text:
                qc.lines_read += 1
                yield number, text
        return
    for number, line in enumerate(raw.splitlines(), start=1):
        text = decode_line(line, number, qc, p)
        if text is not None:
            yield number, text


_NOT_PLAIN_ASCII = (b"\x00", b"\x0b", b"\x0c", b"\x1c", b"\x1d", b"\x1e", b"\x1f")
"""Bytes on which str and bytes line splitting or stripping differ, and NUL (a ``wrong encoding``)."""


def decode_line(raw: bytes | str, number: int, qc: QcReport, source: str | Path) -> str | None:
    """One raw line as stripped text, or None if it is blank or not valid text.

    The one per-line rule of :func:`read_lines`, also used by the live streams (UDP, TCP, serial): a
    blank line is not counted; any other line counts in ``qc.lines_read``; NUL bytes or invalid UTF-8
    are recorded as ``wrong encoding`` (``source:number``) and give None. A leading byte-order mark is
    dropped. A ``str`` (already decoded) is only checked for NUL characters.
    """
    if not raw.strip():
        return None
    qc.lines_read += 1
    if ("\x00" if isinstance(raw, str) else b"\x00") in raw:
        qc.add(source, number, "wrong encoding", "NUL bytes")
        return None
    try:
        text = raw if isinstance(raw, str) else raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        qc.add(source, number, "wrong encoding", f"not UTF-8 at byte {exc.start}")
        return None
    return text.strip().lstrip("\ufeff")
