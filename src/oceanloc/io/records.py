"""Machine-readable results: plain records written as JSON, CSV or NetCDF, each with its provenance.

Every result type of oceanloc has a ``to_record()`` method returning plain JSON-ready data (dicts, lists,
strings, numbers; numpy values are converted here). This module is the one place that writes them:

- :func:`write_json` writes a record with a ``provenance`` entry;
- :func:`write_csv` writes rows (one mapping per row) with the provenance as leading ``# key: value``
  comment lines (``pandas.read_csv(path, comment="#")`` reads it);
- :func:`write_netcdf` writes an :class:`xarray.Dataset` (Monte Carlo results with dims such as ``run``,
  ``epoch``, ``planner``, ``transponder``) with CF ``Conventions``, units on every variable that has one,
  and the provenance as global attributes.

:class:`Provenance` says what made a file: the oceanloc version, the command line, the seed, the scenario
name and the SHA-256 of its TOML text, the other input files and their hashes, and the UTC time.
"""

from __future__ import annotations

import csv
import datetime as dt
import hashlib
import json
import math
import sys
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

from oceanloc.errors import ConfigError

if TYPE_CHECKING:
    import xarray as xr

__all__ = [
    "CF_CONVENTIONS",
    "Provenance",
    "Recordable",
    "file_sha256",
    "make_provenance",
    "to_jsonable",
    "write_csv",
    "write_json",
    "write_netcdf",
]

CF_CONVENTIONS = "CF-1.10"


@runtime_checkable
class Recordable(Protocol):
    """A result that can be written: ``to_record()`` returns plain JSON-ready data."""

    def to_record(self) -> dict[str, Any]: ...


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("oceanloc")
    except PackageNotFoundError:  # pragma: no cover - running from a source tree that is not installed
        return "unknown"


def file_sha256(path: str | Path) -> str:
    """SHA-256 (hex) of a file's bytes; of a directory (a Zarr store), of every file's relative path and
    bytes in sorted order."""
    root = Path(path)
    if root.is_dir():
        digest = hashlib.sha256()
        for f in sorted(q for q in root.rglob("*") if q.is_file()):
            digest.update(str(f.relative_to(root)).encode("utf-8") + b"\0")
            digest.update(file_sha256(f).encode("ascii"))
        return digest.hexdigest()
    digest = hashlib.sha256()
    with root.open("rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


@dataclass(frozen=True, slots=True, kw_only=True)
class Provenance:
    """What made a result file.

    Attributes
    ----------
    version : str
        The installed oceanloc version.
    command : tuple[str, ...]
        The command line (``oceanloc`` and its arguments), or the Python entry point's ``sys.argv``.
    seed : int or None
        The master seed, where the result is random.
    scenario : str or None
        The scenario's name (a built-in name or the file's path).
    scenario_sha256 : str or None
        SHA-256 of the scenario's TOML text.
    inputs : tuple[tuple[str, str], ...]
        ``(path, sha256)`` of every other input file.
    created_utc : str
        ISO 8601 UTC time the record was made.
    parameters : dict
        The command's resolved options (defaults included), JSON-ready.
    """

    version: str
    command: tuple[str, ...]
    seed: int | None = None
    scenario: str | None = None
    scenario_sha256: str | None = None
    inputs: tuple[tuple[str, str], ...] = field(default_factory=tuple)
    created_utc: str = ""
    parameters: dict[str, Any] = field(default_factory=dict)

    def to_record(self) -> dict[str, Any]:
        return {
            "oceanloc_version": self.version,
            "command": list(self.command),
            "seed": self.seed,
            "scenario": self.scenario,
            "scenario_sha256": self.scenario_sha256,
            "inputs": [{"path": p, "sha256": h} for p, h in self.inputs],
            "created_utc": self.created_utc,
            "parameters": self.parameters,
        }

    def attributes(self) -> dict[str, str | int]:
        """Flat global attributes for NetCDF (no None values: netCDF attributes cannot hold them)."""
        attrs: dict[str, str | int] = {
            "oceanloc_version": self.version,
            "history": f"{self.created_utc} {' '.join(self.command)}".strip(),
        }
        if self.seed is not None:
            attrs["seed"] = int(self.seed)
        if self.scenario is not None:
            attrs["scenario"] = self.scenario
        if self.scenario_sha256 is not None:
            attrs["scenario_sha256"] = self.scenario_sha256
        if self.inputs:
            attrs["inputs"] = "; ".join(f"{p} sha256:{h}" for p, h in self.inputs)
        return attrs


def oceanloc_command_line() -> list[str] | None:
    """``["oceanloc", *args]`` when this process is the ``oceanloc`` script or ``python -m oceanloc``."""
    argv = list(sys.argv)
    first = Path(argv[0]) if argv else Path()
    ours = first.name == "oceanloc" or (first.name == "__main__.py" and first.parent.name == "oceanloc")
    return ["oceanloc", *argv[1:]] if ours else None


def make_provenance(
    *,
    seed: int | None = None,
    scenario: str | None = None,
    scenario_toml: str | bytes | None = None,
    inputs: Iterable[str | Path] = (),
    command: Sequence[str] | None = None,
) -> Provenance:
    """Provenance of a result made now by this process.

    ``scenario_toml`` is the scenario's TOML text (hashed as UTF-8); ``inputs`` are files read, each hashed
    (a path that cannot be read is recorded with the hash ``"unreadable"``).
    """
    if command is None:
        command = oceanloc_command_line() or list(sys.argv)
    toml_hash = None
    if scenario_toml is not None:
        raw = scenario_toml.encode("utf-8") if isinstance(scenario_toml, str) else scenario_toml
        toml_hash = hashlib.sha256(raw).hexdigest()
    hashed = []
    for p in inputs:
        try:
            hashed.append((str(p), file_sha256(p)))
        except OSError:
            hashed.append((str(p), "unreadable"))
    return Provenance(
        version=_version(),
        command=tuple(str(c) for c in command),
        seed=None if seed is None else int(seed),
        scenario=scenario,
        scenario_sha256=toml_hash,
        inputs=tuple(hashed),
        created_utc=dt.datetime.now(dt.UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
    )


def to_jsonable(value: Any) -> Any:
    """Plain JSON values from records: numpy scalars and arrays converted, ``to_record()`` called,
    non-finite floats as ``null`` (JSON has no NaN)."""
    if isinstance(value, Recordable) and not isinstance(value, type):
        return to_jsonable(value.to_record())
    if isinstance(value, Mapping):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [to_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return to_jsonable(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _prepare(path: str | Path) -> Path:
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(f"{path.parent}: cannot create folder ({exc.strerror or exc})") from None
    return path


def write_json(path: str | Path, record: Any, provenance: Provenance | None = None) -> Path:
    """Write ``record`` (a mapping or a :class:`Recordable`) as indented JSON, with ``provenance``."""
    path = _prepare(path)
    data = to_jsonable(record)
    if not isinstance(data, dict):
        data = {"result": data}
    if provenance is not None:
        data = {"provenance": provenance.to_record(), **data}
    try:
        path.write_text(json.dumps(data, indent=2, allow_nan=False) + "\n", encoding="utf-8")
    except OSError as exc:
        raise ConfigError(f"{path}: cannot write JSON ({exc.strerror or exc})") from None
    return path


def _csv_cell(value: Any) -> Any:
    value = to_jsonable(value)
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, list | dict):
        return json.dumps(value)
    return value


def write_csv(
    path: str | Path,
    rows: Sequence[Mapping[str, Any]],
    provenance: Provenance | None = None,
    columns: Sequence[str] | None = None,
) -> Path:
    """Write rows as CSV: a header of ``columns`` (default: the first row's keys, in order), floats as
    ``repr`` so they read back exactly, missing values empty; provenance as ``# key: value`` lines first."""
    path = _prepare(path)
    if columns is None:
        columns = list(rows[0].keys()) if rows else []
    try:
        with path.open("w", newline="", encoding="utf-8") as fh:
            if provenance is not None:
                for key, value in provenance.to_record().items():
                    fh.write(f"# {key}: {json.dumps(to_jsonable(value))}\n")
            writer = csv.writer(fh)
            writer.writerow(columns)
            for row in rows:
                writer.writerow([_csv_cell(row.get(c)) for c in columns])
    except OSError as exc:
        raise ConfigError(f"{path}: cannot write CSV ({exc.strerror or exc})") from None
    return path


def write_netcdf(path: str | Path, dataset: xr.Dataset, provenance: Provenance | None = None) -> Path:
    """Write a Dataset as NetCDF-4 with ``Conventions`` and the provenance as global attributes.

    Every data variable and coordinate should carry ``units`` (CF; ``"1"`` for dimensionless) and a
    ``long_name``; a variable without ``units`` is an error here, so a file never leaves without them.
    """
    variables = {**dataset.data_vars, **dataset.coords}
    missing = [str(n) for n, v in variables.items() if _needs_units(v) and "units" not in v.attrs]
    if missing:
        raise ConfigError(f"{path}: NetCDF variables without units: {', '.join(sorted(missing))}")
    path = _prepare(path)
    out = dataset.copy()
    out.attrs = {**out.attrs, "Conventions": CF_CONVENTIONS, "source": "oceanloc"}
    if provenance is not None:
        out.attrs.update(provenance.attributes())
    try:
        out.to_netcdf(path)
    except (OSError, ValueError, RuntimeError) as exc:
        raise ConfigError(f"{path}: cannot write NetCDF ({exc})") from None
    return path


def _needs_units(var: Any) -> bool:
    """Numeric variables need units; strings and labels (planner names) do not."""
    return np.asarray(var.values).dtype.kind in "fiuc"
