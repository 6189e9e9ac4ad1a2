"""Typed, validated access to TOML tables.

Every scenario file goes through :class:`Table`: each value is checked once, at the edge, and an error
names the file, the table and the field, with the allowed range. Unknown fields are reported too, so a
typo (``sped_mps``) is an error instead of a silently ignored setting.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.errors import ConfigError

_MISSING: Any = object()


def read_toml(path: str | Path) -> Table:
    """Parse a TOML file into a root :class:`Table`; unreadable or malformed files raise ConfigError."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ConfigError(f"{p}: file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{p}: cannot read ({exc})") from None
    return parse_toml(text, source=str(p))


MAX_TOML_DEPTH = 16
"""Deepest nesting of tables and arrays a scenario file may have (the scenarios use 3)."""


def parse_toml(text: str, source: str = "<string>") -> Table:
    """Parse TOML text; ``source`` names it in error messages.

    Raises
    ------
    ConfigError
        If the text is not valid TOML or nests tables and arrays deeper than :data:`MAX_TOML_DEPTH`.
    """
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{source}: not valid TOML ({exc})") from None
    except RecursionError:
        raise ConfigError(f"{source}: not valid TOML (arrays or tables nested too deeply)") from None
    except ValueError as exc:  # an integer of more than 4300 digits
        raise ConfigError(f"{source}: not valid TOML ({exc})") from None
    if _depth(data) > MAX_TOML_DEPTH:
        raise ConfigError(f"{source}: tables and arrays nested deeper than {MAX_TOML_DEPTH} levels")
    return Table(data, source=source, name="")


def _depth(value: Any) -> int:
    """Nesting depth of dicts and lists (iterative: no recursion limit)."""
    deepest, stack = 0, [(value, 0)]
    while stack:
        item, level = stack.pop()
        if isinstance(item, dict | list):
            deepest = max(deepest, level + 1)
            if deepest > MAX_TOML_DEPTH:
                return deepest
            stack.extend((v, level + 1) for v in (item.values() if isinstance(item, dict) else item))
    return deepest


class Table:
    """One TOML table with typed getters that validate and remember which fields were read."""

    def __init__(self, data: dict[str, Any], *, source: str, name: str) -> None:
        self._data = data
        self._source = source
        self._name = name
        self._used: set[str] = set()

    @property
    def source(self) -> str:
        return self._source

    def where(self, key: str | None = None) -> str:
        """``file: [table] key`` for messages."""
        table = f"[{self._name}]" if self._name else "top level"
        return f"{self._source}: {table}" + (f" field '{key}'" if key else "")

    def error(self, key: str | None, message: str) -> ConfigError:
        """A ConfigError naming this table and ``key``."""
        return ConfigError(f"{self.where(key)}: {message}")

    def has(self, key: str) -> bool:
        return key in self._data

    def _get(self, key: str, default: Any) -> Any:
        self._used.add(key)
        if key in self._data:
            return self._data[key]
        if default is _MISSING:
            raise self.error(key, "is required but missing")
        return default

    def float(
        self,
        key: str,
        default: Any = _MISSING,
        *,
        lo: float | None = None,
        hi: float | None = None,
        lo_open: bool = False,
        hi_open: bool = False,
    ) -> float:
        """A finite number within ``[lo, hi]`` (open ends if requested)."""
        value = self._get(key, default)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.error(key, f"must be a number, got {value!r}")
        try:
            value = float(value)
        except OverflowError:
            raise self.error(key, f"must be finite, got an integer of {len(str(value))} digits") from None
        if not math.isfinite(value):
            raise self.error(key, f"must be finite, got {value}")
        _check_range(self, key, value, lo, hi, lo_open, hi_open)
        return value

    def int(self, key: str, default: Any = _MISSING, *, lo: int | None = None, hi: int | None = None) -> int:
        """An integer within ``[lo, hi]``."""
        value = self._get(key, default)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(key, f"must be an integer, got {value!r}")
        _check_range(self, key, value, lo, hi, False, False)
        return int(value)

    def str(self, key: str, default: Any = _MISSING, *, choices: Sequence[str] | None = None) -> str:
        """A string, optionally one of ``choices``."""
        value = self._get(key, default)
        if not isinstance(value, str):
            raise self.error(key, f"must be a string, got {value!r}")
        if choices is not None and value not in choices:
            raise self.error(key, f"must be one of {', '.join(choices)}; got '{value}'")
        return value

    def bool(self, key: str, default: Any = _MISSING) -> bool:
        value = self._get(key, default)
        if not isinstance(value, bool):
            raise self.error(key, f"must be true or false, got {value!r}")
        return value

    def vector(
        self,
        key: str,
        length: int | None = None,
        default: Any = _MISSING,
        *,
        positive: bool = False,
        lo: float | None = None,
        hi: float | None = None,
    ) -> FloatArray:
        """A list of finite numbers, of ``length`` if given, each in ``[lo, hi]`` when given."""
        value = self._get(key, default)
        if isinstance(value, np.ndarray):
            value = value.tolist()
        if not isinstance(value, list) or not all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in value
        ):
            raise self.error(key, f"must be a list of numbers, got {value!r}")
        try:
            arr = np.asarray(value, dtype=float)
        except OverflowError:
            raise self.error(key, "must hold finite numbers, got an integer too large for a float") from None
        if length is not None and arr.shape != (length,):
            raise self.error(key, f"must have {length} numbers, got {arr.size}")
        if not np.all(np.isfinite(arr)):
            raise self.error(key, f"must hold finite numbers, got {value!r}")
        if positive and not np.all(arr > 0):
            raise self.error(key, f"must hold positive numbers, got {value!r}")
        outside = (arr < lo if lo is not None else False) | (arr > hi if hi is not None else False)
        if np.any(outside):
            bounds = f"[{'-inf' if lo is None else f'{lo:g}'}, {'inf' if hi is None else f'{hi:g}'}]"
            raise self.error(key, f"must hold numbers in {bounds}, got {value!r}")
        return arr

    def table(self, key: str, *, required: bool = True) -> Table:
        """A sub-table; an empty one if optional and absent."""
        value = self._get(key, _MISSING if required else {})
        if not isinstance(value, dict):
            raise self.error(key, "must be a table")
        return Table(value, source=self._source, name=_join(self._name, key))

    def tables(self, key: str, *, min_count: int = 0) -> list[Table]:
        """An array of tables (``[[key]]``)."""
        value = self._get(key, _MISSING if min_count else [])
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            raise self.error(key, "must be an array of tables ([[...]])")
        if len(value) < min_count:
            raise self.error(key, f"needs at least {min_count} entries, got {len(value)}")
        return [
            Table(v, source=self._source, name=f"{_join(self._name, key)}[{i}]") for i, v in enumerate(value)
        ]

    def check_unknown(self) -> None:
        """Raise if the table holds fields no getter asked for."""
        unknown = sorted(set(self._data) - self._used)
        if unknown:
            known = ", ".join(sorted(self._used)) or "none"
            raise self.error(unknown[0], f"unknown field (known fields here: {known})")


def _join(parent: str, key: str) -> str:
    return f"{parent}.{key}" if parent else key


def _check_range(
    table: Table,
    key: str,
    value: float,
    lo: float | None,
    hi: float | None,
    lo_open: bool,
    hi_open: bool,
) -> None:
    if lo is not None and (value < lo or (lo_open and value == lo)):
        raise table.error(key, f"must be {'>' if lo_open else '>='} {lo}, got {value}")
    if hi is not None and (value > hi or (hi_open and value == hi)):
        raise table.error(key, f"must be {'<' if hi_open else '<='} {hi}, got {value}")
