from functools import partial

import numpy as np
import pytest

from oceanloc._random import run_generators
from oceanloc.errors import ConfigError
from oceanloc.evaluation.montecarlo import chunk_indices, open_executor, run_chunked


def _draws(idx, seed):
    return np.stack([g.standard_normal(4) for g in run_generators(seed, idx)])


def test_results_do_not_depend_on_chunking_or_workers():
    task = partial(_draws, seed=9)
    ref = np.concatenate(run_chunked(task, 23, chunk_size=23))
    for size in (1, 4, 7):
        np.testing.assert_array_equal(np.concatenate(run_chunked(task, 23, chunk_size=size)), ref)
    with open_executor(None, 2) as pool:
        np.testing.assert_array_equal(np.concatenate(run_chunked(task, 23, executor=pool, chunk_size=5)), ref)


def test_progress_counts_every_run():
    seen = []
    run_chunked(partial(_draws, seed=1), 10, chunk_size=3, progress=seen.append)
    assert sum(seen) == 10 and len(seen) == 4


def test_bad_specs_are_user_errors():
    with pytest.raises(ConfigError, match="at least 1"):
        chunk_indices(0, 5)
    with pytest.raises(ConfigError, match="local:N needs an integer"), open_executor("local:x"):
        pass
    with pytest.raises(ConfigError, match="--workers"), open_executor(None, 0):
        pass


def test_concat_runs_joins_arrays_and_dicts_and_keeps_the_named_fields():
    import dataclasses

    from oceanloc.evaluation.montecarlo import concat_runs

    @dataclasses.dataclass(frozen=True)
    class Part:
        truth: np.ndarray
        errors: np.ndarray
        per_filter: dict
        name: str

    parts = [
        Part(truth=np.ones(3), errors=np.arange(2.0), per_filter={"ekf": np.arange(2)}, name="a"),
        Part(truth=np.ones(3), errors=np.arange(2.0, 5.0), per_filter={"ekf": np.arange(2, 5)}, name="a"),
    ]
    joined = concat_runs(parts, keep=("truth",))
    np.testing.assert_array_equal(joined.errors, np.arange(5.0))
    np.testing.assert_array_equal(joined.per_filter["ekf"], np.arange(5))
    np.testing.assert_array_equal(joined.truth, np.ones(3))
    assert joined.name == "a"


def test_resolve_workers_names_the_option_and_reads_local_n():
    from oceanloc.evaluation.montecarlo import resolve_workers

    assert resolve_workers(3) == 3
    assert resolve_workers(None, "local:2") == 2
    assert resolve_workers() >= 1
    with pytest.raises(ConfigError, match="--workers must be at least 1"):
        resolve_workers(0)
    with pytest.raises(ConfigError, match="local:N needs an integer"):
        resolve_workers(None, "local:x")


def test_a_run_count_whose_results_do_not_fit_is_refused_before_the_runs_start():
    from oceanloc.evaluation.montecarlo import check_result_memory, result_nbytes, run_chunked

    calls = []

    def task(idx):
        calls.append(idx.size)
        return {"errors": np.zeros((idx.size, 1000))}  # 8000 bytes per run

    assert result_nbytes(task(np.arange(3))) == 24_000
    calls.clear()
    with pytest.raises(
        ConfigError, match=r"10000000 runs would hold about 74.5 GiB .* use --runs 1073741 or fewer"
    ):
        run_chunked(task, 10_000_000)
    assert calls == [1]  # one probe run, nothing else started
    check_result_memory(task, 5_000)  # under the probe threshold: no probe, no error
    assert calls == [1]


def test_a_billion_runs_from_the_command_line_is_one_line_and_exit_2():
    import os
    import subprocess
    import sys

    result = subprocess.run(
        [sys.executable, "-m", "oceanloc", "simulate", "drift-follow", "--runs", "1000000000"],
        capture_output=True,
        text=True,
        env=os.environ,
        timeout=300,
    )
    assert result.returncode == 2, result.stderr
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert "Traceback" not in result.stderr
    assert lines[-1].startswith("error: 1000000000 runs would hold about") and "use --runs" in lines[-1]
