"""CSV tables written column by column: a header of names (units in the names), one row per record.

Floats are written with ``repr`` (the shortest text that reads back to the same double), so a table
round-trips exactly; NaN is written as an empty field.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from oceanloc.errors import ConfigError


def write_csv(path: str | Path, columns: Mapping[str, Sequence[Any] | np.ndarray]) -> Path:
    """Write equal-length columns as a CSV file with a header; creates parent folders.

    Parameters
    ----------
    path : str or Path
    columns : mapping of name -> (n,) values
        Numbers, strings or booleans; numpy scalars are converted.

    Raises
    ------
    ConfigError
        If the columns differ in length or the file cannot be written.
    """
    p = Path(path)
    lengths = {name: len(col) for name, col in columns.items()}
    if len(set(lengths.values())) > 1:
        raise ConfigError(f"{p}: columns of different lengths {lengths}")
    n = next(iter(lengths.values()), 0)
    cols = [np.asarray(c).tolist() for c in columns.values()]
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        with p.open("w", newline="", encoding="utf-8") as f:
            w = csv.writer(f, lineterminator="\n")
            w.writerow(list(columns))
            for i in range(n):
                w.writerow([_cell(c[i]) for c in cols])
    except OSError as exc:
        raise ConfigError(f"{p}: cannot write CSV ({exc})") from None
    return p


def _cell(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return "" if not math.isfinite(value) else repr(value)
    return str(value)
