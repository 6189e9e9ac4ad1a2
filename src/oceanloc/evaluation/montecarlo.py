"""Monte Carlo runner: chunks of runs, vectorized inside, parallel across workers.

A Monte Carlo experiment is a picklable ``task(run_indices) -> chunk_result`` that simulates the given
runs as one vectorized batch. Each run draws from its own generator seeded by ``(seed, run_index)``
(:func:`oceanloc._random.run_generators`), so the numbers do not depend on how runs are split into
chunks or on which worker computes them: one worker or eight, chunks of 1 or 1000, local processes or a
Dask cluster give identical results.

The executor comes from the caller (any :class:`concurrent.futures.Executor`, including Dask's
``Client.get_executor()``); :func:`open_executor` builds the usual ones from a short spec.
"""

from __future__ import annotations

import dataclasses
import math
import multiprocessing
import os
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Executor, ProcessPoolExecutor
from contextlib import contextmanager
from typing import Any, TypeVar

import numpy as np

from oceanloc.errors import ConfigError

T = TypeVar("T")


def chunk_indices(n_runs: int, chunk_size: int) -> list[np.ndarray]:
    """Split ``0 .. n_runs-1`` into consecutive chunks of at most ``chunk_size`` runs."""
    if n_runs < 1:
        raise ConfigError(f"the number of runs must be at least 1, got {n_runs}")
    if chunk_size < 1:
        raise ConfigError(f"chunk size must be at least 1, got {chunk_size}")
    return [np.arange(s, min(s + chunk_size, n_runs)) for s in range(0, n_runs, chunk_size)]


MAX_RESULT_GIB = 8.0
"""Largest Monte Carlo result (all runs' arrays together) a run may build, GiB."""

PROBE_ABOVE_RUNS = 10_000
"""Above this many runs, one run is computed first to measure a run's result before the rest start."""


def result_nbytes(result: Any) -> int:
    """Bytes held by the arrays of a chunk result (a dataclass's array fields and dicts of arrays)."""
    if isinstance(result, np.ndarray):
        return int(result.nbytes)
    if isinstance(result, dict):
        return sum(result_nbytes(v) for v in result.values())
    if isinstance(result, list | tuple):
        return sum(result_nbytes(v) for v in result)
    if dataclasses.is_dataclass(result) and not isinstance(result, type):
        return sum(result_nbytes(getattr(result, f.name)) for f in dataclasses.fields(result))
    return 0


def check_result_memory(
    task: Callable[[np.ndarray], Any], n_runs: int, max_gib: float = MAX_RESULT_GIB
) -> None:
    """Refuse, before the runs start, a run count whose results would not fit in ``max_gib``.

    Above :data:`PROBE_ABOVE_RUNS` runs one run (run 0) is computed to measure what a run's result holds;
    results do not depend on chunking, so the probe changes nothing. The message says how many runs fit.
    """
    if n_runs <= PROBE_ABOVE_RUNS:
        return
    per_run = max(result_nbytes(task(np.arange(1))), 1)
    need = per_run * n_runs
    if need > max_gib * 2**30:
        fit = int(max_gib * 2**30 // per_run)
        raise ConfigError(
            f"{n_runs} runs would hold about {need / 2**30:.3g} GiB of results ({per_run} bytes per run; "
            f"limit {max_gib:g} GiB): use --runs {fit} or fewer"
        )


def default_chunk_size(n_runs: int, workers: int) -> int:
    """About four chunks per worker, at most 250 runs each: enough to balance, large enough to vectorize."""
    return max(1, min(250, math.ceil(n_runs / (4 * max(workers, 1)))))


def run_chunked(
    task: Callable[[np.ndarray], T],
    n_runs: int,
    *,
    executor: Executor | None = None,
    chunk_size: int | None = None,
    progress: Callable[[int], None] | None = None,
) -> list[T]:
    """Run ``task`` over all runs in chunks and return the chunk results in run order.

    Parameters
    ----------
    task : callable
        Picklable function of a ``(r,)`` int array of global run indices.
    n_runs : int
        Number of runs.
    executor : Executor, optional
        Where chunks run; in this process when ``None``.
    chunk_size : int, optional
        Runs per chunk; :func:`default_chunk_size` when omitted.
    progress : callable, optional
        Called with the number of runs just finished.
    """
    if n_runs < 1:
        raise ConfigError(f"the number of runs must be at least 1, got {n_runs}")
    check_result_memory(task, n_runs)
    workers = _executor_workers(executor)
    chunks = chunk_indices(n_runs, chunk_size or default_chunk_size(n_runs, workers))
    if executor is None:
        results = []
        for idx in chunks:
            results.append(task(idx))
            if progress:
                progress(idx.size)
        return results
    futures = [executor.submit(task, idx) for idx in chunks]
    pending = set(range(len(futures)))
    while pending:
        finished = [i for i in pending if futures[i].done()]
        for i in finished:
            pending.discard(i)
            if progress:
                progress(chunks[i].size)
        if pending and not finished:
            time.sleep(0.02)
    return [f.result() for f in futures]


def _executor_workers(executor: Executor | None) -> int:
    if executor is None:
        return 1
    count = getattr(executor, "_max_workers", None) or getattr(executor, "oceanloc_workers", None)
    return int(count) if count else (os.cpu_count() or 1)


@contextmanager
def open_executor(scheduler: str | None = None, workers: int | None = None) -> Iterator[Executor | None]:
    """An executor from a short spec, closed on exit.

    Parameters
    ----------
    scheduler : str, optional
        ``None``: local processes (``workers`` of them, all cores by default; in this process when
        ``workers == 1``). ``"local:N"``: a Dask ``LocalCluster`` with ``N`` single-threaded worker
        processes. Anything else: the address of a running Dask scheduler (``tcp://host:8786``).
    workers : int, optional
        Number of local processes when ``scheduler`` is ``None``.
    """
    if scheduler is None:
        n = resolve_workers(workers)
        if n == 1:
            yield None
            return
        with ProcessPoolExecutor(max_workers=n, mp_context=multiprocessing.get_context("forkserver")) as pool:
            yield pool
        return
    yield from _dask_executor(scheduler)


def _dask_executor(scheduler: str) -> Iterator[Executor]:
    try:
        from distributed import Client, LocalCluster
    except ImportError:  # pragma: no cover - distributed is a declared dependency
        raise ConfigError("--scheduler needs the 'distributed' package (pip install distributed)") from None
    if scheduler.startswith("local:"):
        n = resolve_workers(None, scheduler)
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, dashboard_address=None, processes=True)
        client = Client(cluster)
        try:
            executor = client.get_executor()
            executor.oceanloc_workers = n  # type: ignore[attr-defined]
            yield executor
        finally:
            client.close()
            cluster.close()
        return
    try:
        client = Client(scheduler, timeout="10s")
    except (OSError, TimeoutError) as exc:
        raise ConfigError(f"cannot reach the Dask scheduler at '{scheduler}' ({exc})") from None
    try:
        executor = client.get_executor()
        executor.oceanloc_workers = max(1, sum(client.nthreads().values()))  # type: ignore[attr-defined]
        yield executor
    finally:
        client.close()


def concat_runs(parts: Sequence[T], *, keep: Sequence[str] = ()) -> T:
    """Join chunk results of one dataclass type along the run axis, in the given order.

    Every array field is concatenated along axis 0, and so is every dict of arrays (key by key);
    the fields named in ``keep`` (run-independent: the truth, a planner name) and any other non-array
    field are taken from the first part. This is the one place chunked Monte Carlo results are joined,
    so a result never depends on how its runs were chunked.
    """
    if not parts:
        raise ConfigError("no chunk results to join (zero runs?)")
    first = parts[0]
    if not dataclasses.is_dataclass(first):
        raise TypeError(f"concat_runs joins dataclass results, got {type(first).__name__}")
    values: dict[str, Any] = {}
    for f in dataclasses.fields(first):
        value = getattr(first, f.name)
        if f.name in keep:
            values[f.name] = value
        elif isinstance(value, np.ndarray):
            values[f.name] = np.concatenate([getattr(p, f.name) for p in parts], axis=0)
        elif isinstance(value, dict) and value and all(isinstance(v, np.ndarray) for v in value.values()):
            values[f.name] = {
                k: np.concatenate([getattr(p, f.name)[k] for p in parts], axis=0) for k in value
            }
        else:
            values[f.name] = value
    return dataclasses.replace(first, **values)


def resolve_workers(workers: int | None = None, scheduler: str | None = None) -> int:
    """How many workers a run will use: ``workers`` if given (at least 1), ``N`` of ``local:N``, else all
    cores; the one place the default is decided (the count a remote scheduler has is known only once
    connected, see :func:`open_executor`)."""
    if workers is not None:
        if workers < 1:
            raise ConfigError(f"--workers must be at least 1, got {workers}")
        return int(workers)
    if scheduler is not None and scheduler.startswith("local:"):
        try:
            n = int(scheduler.split(":", 1)[1])
        except ValueError:
            raise ConfigError(f"--scheduler local:N needs an integer N, got '{scheduler}'") from None
        if n < 1:
            raise ConfigError(f"--scheduler local:N needs N >= 1, got {n}")
        return n
    return os.cpu_count() or 1
