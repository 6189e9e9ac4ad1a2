"""Console, progress and output helpers shared by the command modules."""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from oceanloc.errors import ConfigError

console = Console()
err_console = Console(stderr=True)

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


@contextmanager
def progress_bar(total: int, description: str) -> Iterator[Callable[[int], None]]:
    """A rich progress bar; yields ``advance(n)``. Silent when stderr is not a terminal."""
    columns = (
        TextColumn("[progress.description]{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
    )
    with Progress(*columns, console=err_console, transient=True, disable=not err_console.is_terminal) as bar:
        task = bar.add_task(description, total=total)
        yield lambda n: bar.advance(task, n)


def to_jsonable(value: Any) -> Any:
    """Convert numpy scalars and arrays (recursively) to plain JSON values; NaN becomes null."""
    if isinstance(value, dict):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [to_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return to_jsonable(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def write_json(path: Path, payload: dict[str, Any]) -> None:
    """Write ``payload`` as indented JSON, creating parent folders."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(to_jsonable(payload), indent=2) + "\n", encoding="utf-8")
    except OSError as exc:
        raise ConfigError(f"{path}: cannot write JSON ({exc})") from None
    err_console.print(f"wrote {path}")


def ensure_dir(path: Path) -> Path:
    """Create an output folder or raise a ConfigError naming it."""
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(f"{path}: cannot create folder ({exc})") from None
    return path
