"""Option parsers shared by every command: comma lists, numbers, points, origins, times, names.

One convention per quantity: positions on the Earth are ``LAT,LON[,H]`` (degrees, metres), local points
``E,N[,U]`` in metres, bearings clockwise from true north in degrees, times ISO 8601 UTC or Unix seconds.
Every error is a :class:`~oceanloc.errors.ConfigError` that names the option and what it accepts.
"""

from __future__ import annotations

import datetime as dt
import math
from collections.abc import Sequence

import numpy as np

from oceanloc.errors import ConfigError, DataError
from oceanloc.geo.enu import EnuOrigin

__all__ = [
    "parse_choices",
    "parse_fields",
    "parse_floats",
    "parse_ints",
    "parse_number",
    "parse_origin",
    "parse_point",
    "parse_time",
]


def parse_number(text: str, name: str, where: str, low: float = -math.inf, high: float = math.inf) -> float:
    """A finite number in ``[low, high]``; errors start with ``where`` and name the field ``name``."""
    try:
        value = float(text)
    except ValueError:
        raise ConfigError(f"{where}: {name} {text.strip()!r} is not a number") from None
    if not math.isfinite(value):
        raise ConfigError(f"{where}: {name} is NaN or infinite")
    if not low <= value <= high:
        raise ConfigError(f"{where}: {name} {value:g} is outside [{low:g}, {high:g}]")
    return value


def parse_fields(text: str, names: Sequence[str], where: str) -> tuple[float, ...]:
    """Comma-separated finite numbers, one per name (``"T,LAT,LON,H"`` style)."""
    parts = [p.strip() for p in text.split(",")]
    if len(parts) != len(names):
        raise ConfigError(f"{where}: expected {','.join(names)} ({len(names)} values), got {len(parts)}")
    return tuple(parse_number(part, name, where) for name, part in zip(names, parts, strict=True))


def parse_floats(text: str, option: str, size: int | None = None) -> list[float]:
    """``"a,b,c"`` -> finite floats; ``size`` fixes how many."""
    parts = [p.strip() for p in text.split(",") if p.strip()]
    what = f"{size} comma-separated numbers" if size else "comma-separated numbers"
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise ConfigError(f"{option} must be {what}, got {text!r}") from None
    if not values or (size is not None and len(values) != size) or not all(map(math.isfinite, values)):
        raise ConfigError(f"{option} must be {what}, got {text!r}")
    return values


def parse_ints(text: str, option: str, low: int | None = None, high: int | None = None) -> tuple[int, ...]:
    """``"1,3,2"`` -> sorted distinct integers within ``[low, high]``."""
    try:
        values = sorted({int(p) for p in text.split(",") if p.strip()})
    except ValueError:
        raise ConfigError(f"{option} must be comma-separated integers, got {text!r}") from None
    if not values:
        raise ConfigError(f"{option} must list at least one integer, got {text!r}")
    if (low is not None and values[0] < low) or (high is not None and values[-1] > high):
        raise ConfigError(f"{option} values must be in [{low}, {high}], got {text!r}")
    return tuple(values)


def parse_choices(text: str, option: str, choices: Sequence[str]) -> list[str]:
    """``"a,b"`` -> names, each one of ``choices`` (case-insensitive), in order, without repeats."""
    names = [p.strip().lower() for p in text.split(",") if p.strip()]
    bad = [n for n in names if n not in choices]
    if bad or not names:
        raise ConfigError(f"{option} must list names from {', '.join(choices)}; got {text!r}")
    return list(dict.fromkeys(names))


def parse_point(text: str, option: str, size: int = 2) -> np.ndarray:
    """A local point ``"E,N"`` (or ``"E,N,U"`` with ``size=3``), metres, as a ``(size,)`` array."""
    axes = ("E", "N", "U")[:size]
    return np.array(parse_fields(text, axes, option))


def parse_origin(text: str, option: str = "--origin", need_height: bool = False) -> EnuOrigin:
    """A geodetic origin ``"LAT,LON[,H]"`` (degrees, degrees, metres above the ellipsoid; H defaults to 0)."""
    parts = [p.strip() for p in text.split(",")]
    if len(parts) not in ((3,) if need_height else (2, 3)):
        form = "LAT,LON,H" if need_height else "LAT,LON[,H]"
        raise ConfigError(f"{option}: expected {form} (degrees, degrees, metres), got {text!r}")
    lat = parse_number(parts[0], "LAT", option, -90.0, 90.0)
    lon = parse_number(parts[1], "LON", option, -180.0, 360.0)
    h = parse_number(parts[2], "H", option, -12_000.0, 10_000.0) if len(parts) == 3 else 0.0
    try:
        return EnuOrigin(lat_deg=lat, lon_deg=lon, h_m=h)
    except DataError as exc:
        raise ConfigError(f"{option}: {exc}") from None


def parse_time(text: str, where: str) -> float:
    """ISO 8601 (UTC if no zone is given) or Unix seconds -> Unix seconds."""
    text = text.strip()
    try:
        return parse_number(text, "T", where)
    except ConfigError as exc:
        if "NaN" in str(exc):
            raise
    try:
        stamp = dt.datetime.fromisoformat(text.replace("Z", "+00:00"))
    except ValueError:
        raise ConfigError(f"{where}: T {text!r} is neither ISO 8601 UTC nor Unix seconds") from None
    return (stamp if stamp.tzinfo else stamp.replace(tzinfo=dt.UTC)).timestamp()
