"""Console, progress and output helpers shared by the command modules.

Text that comes from a user (a file name, a log line, a TOML value) goes through :func:`escape` before it
reaches rich, so ``[/x]`` or ``[sensor]`` prints as written.
"""

from __future__ import annotations

import dataclasses
import os
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any

import click
import typer
from rich.console import Console
from rich.markup import escape

__all__ = ["cli_provenance", "console", "err_console", "escape", "progress_bar", "to_jsonable", "write_json"]
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from oceanloc.errors import ConfigError
from oceanloc.io import records

PIPED_WIDTH = 100
"""Columns for tables when stdout is not a terminal and ``COLUMNS`` is unset (rich would assume 80, and
the tables are laid out to fit 100)."""


def _stdout_console() -> Console:
    plain = Console()
    if plain.is_terminal or "COLUMNS" in os.environ:
        return plain
    return Console(width=PIPED_WIDTH)


console = _stdout_console()
err_console = Console(stderr=True, soft_wrap=True)
"""Messages on stderr are never wrapped: a QC line or an error stays one line, whatever the width."""

Workers = Annotated[
    int | None,
    typer.Option(
        "--workers", min=1, help="Local worker processes (default: all cores; 1 runs in this process)."
    ),
]
Scheduler = Annotated[
    str | None,
    typer.Option(
        "--scheduler",
        help="Dask scheduler address (tcp://host:8786), or local:N for a local Dask cluster of N workers.",
    ),
]
Seed = Annotated[int | None, typer.Option("--seed", min=0, help="Master seed (same seed, same numbers).")]
JsonOut = Annotated[Path | None, typer.Option("--json", help="Write the results as JSON to this file.")]
FiguresOut = Annotated[Path | None, typer.Option("--figures", help="Write the figures (PNG) to this folder.")]
NetcdfOut = Annotated[
    Path | None, typer.Option("--netcdf", help="Write the Monte Carlo as NetCDF (CF, xarray) to this file.")
]


@contextmanager
def progress_bar(total: int, description: str) -> Iterator[Callable[[int], None]]:
    """Progress of ``total`` units of work; yields ``advance(n)``.

    On a terminal, a rich progress bar on stderr. Otherwise (piped, redirected, under CI) plain lines on
    stderr, ``description: done/total (percent), elapsed``, at most one per tenth of the work or per 10 s,
    and one when the work is done, so long commands stay visible in logs.
    """
    if err_console.is_terminal:
        columns = (
            TextColumn("[progress.description]{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TimeElapsedColumn(),
        )
        with Progress(*columns, console=err_console, transient=True) as bar:
            task = bar.add_task(escape(description), total=total)
            yield lambda n: bar.advance(task, n)
        return
    lines = ProgressLines(total=total, description=description, write=_stderr_line)
    yield lines.advance
    lines.finish()


def _stderr_line(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


@dataclass(slots=True)
class ProgressLines:
    """Plain progress lines for a stream that is not a terminal (see :func:`progress_bar`)."""

    total: int
    description: str
    write: Callable[[str], None]
    min_interval_s: float = 10.0
    done: int = 0
    _start: float = field(default_factory=time.monotonic)
    _last_time: float = field(default_factory=time.monotonic)
    _last_tenth: int = 0

    def advance(self, n: int) -> None:
        self.done += int(n)
        now = time.monotonic()
        tenth = (10 * self.done) // max(self.total, 1)
        if self.done < self.total and (
            tenth > self._last_tenth or now - self._last_time >= self.min_interval_s
        ):
            self._emit(now)
            self._last_tenth = tenth

    def finish(self) -> None:
        self._emit(time.monotonic())

    def _emit(self, now: float) -> None:
        self._last_time = now
        pct = 100.0 * self.done / self.total if self.total else 100.0
        self.write(f"{self.description}: {self.done}/{self.total} ({pct:.0f} %), {now - self._start:.0f} s")


def to_jsonable(value: Any) -> Any:
    """Plain JSON values (see :func:`oceanloc.io.records.to_jsonable`)."""
    return records.to_jsonable(value)


def cli_provenance(
    *,
    seed: int | None = None,
    scenario: str | None = None,
    scenario_toml: str | bytes | None = None,
    inputs: Sequence[str | Path] = (),
) -> records.Provenance:
    """Provenance of the running command: the command line as typed (``oceanloc ...``) and the command's
    resolved parameters; inside an in-process runner, where ``sys.argv`` is the runner's, the command path
    and parameters alone."""
    command = None
    params: dict[str, Any] = {}
    ctx = click.get_current_context(silent=True) or _typer_context()
    if ctx is not None:
        params = {k: v for k, v in ctx.params.items() if v is not None}
        if records.oceanloc_command_line() is None:
            command = ctx.command_path.split()
    prov = records.make_provenance(
        seed=seed, scenario=scenario, scenario_toml=scenario_toml, inputs=inputs, command=command
    )
    return dataclasses.replace(prov, parameters=records.to_jsonable(params))


def _typer_context() -> Any:
    try:
        from typer._click.globals import get_current_context
    except ImportError:  # pragma: no cover - older typer uses click's context
        return None
    return get_current_context(silent=True)


def write_json(path: Path, payload: Any, provenance: records.Provenance | None = None) -> None:
    """Write ``payload`` as indented JSON with the provenance of this command line; say so on stderr."""
    if provenance is None:
        provenance = cli_provenance(seed=_seed_of(payload))
    records.write_json(path, payload, provenance)
    err_console.print(f"wrote {escape(str(path))}", highlight=False)


def write_netcdf(path: Path, dataset: Any, provenance: records.Provenance | None = None) -> None:
    """Write an xarray Dataset as NetCDF with the provenance of this command line; say so on stderr."""
    records.write_netcdf(path, dataset, provenance or cli_provenance())
    err_console.print(f"wrote {escape(str(path))}", highlight=False)


def _seed_of(payload: Any) -> int | None:
    seed = payload.get("seed") if isinstance(payload, dict) else getattr(payload, "seed", None)
    return seed if isinstance(seed, int) and not isinstance(seed, bool) else None


def ensure_dir(path: Path) -> Path:
    """Create an output folder or raise a ConfigError naming it."""
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(f"{path}: cannot create folder ({exc})") from None
    return path
