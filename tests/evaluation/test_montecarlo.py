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
