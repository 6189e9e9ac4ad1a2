"""Random streams that do not depend on how Monte Carlo runs are batched.

Every Monte Carlo run owns its generator, seeded from ``(seed, run_index)`` through
:class:`numpy.random.SeedSequence`. Vectorized code draws a batch by asking each run's generator for
its own numbers in a fixed order, so a run produces the same numbers whether it is simulated alone, in a
chunk of seven or among a thousand, on one worker or many.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TypeAlias

import numpy as np

from oceanloc._typing import FloatArray

BatchRng: TypeAlias = np.random.Generator | Sequence[np.random.Generator]
"""One generator shared by the whole batch, or one generator per batch element."""


def run_generators(seed: int, run_indices: Sequence[int] | np.ndarray) -> list[np.random.Generator]:
    """One independent generator per Monte Carlo run.

    Parameters
    ----------
    seed : int
        Master seed of the experiment.
    run_indices : (R,) int
        Global indices of the runs (not positions within a chunk).
    """
    return [np.random.default_rng(np.random.SeedSequence([int(seed), int(r)])) for r in run_indices]


def uniform(rng: BatchRng, batch: int, shape: tuple[int, ...] = ()) -> FloatArray:
    """Uniform [0, 1) draws of shape ``(batch, *shape)``."""
    if isinstance(rng, np.random.Generator):
        return rng.random((batch, *shape))
    _check_len(rng, batch)
    return np.stack([g.random(shape) for g in rng]).reshape(batch, *shape)


def standard_normal(rng: BatchRng, batch: int, shape: tuple[int, ...] = ()) -> FloatArray:
    """Standard normal draws of shape ``(batch, *shape)``."""
    if isinstance(rng, np.random.Generator):
        return rng.standard_normal((batch, *shape))
    _check_len(rng, batch)
    return np.stack([g.standard_normal(shape) for g in rng]).reshape(batch, *shape)


def _check_len(rngs: Sequence[np.random.Generator], batch: int) -> None:
    if len(rngs) != batch:
        raise ValueError(f"expected one generator per batch element ({batch}), got {len(rngs)}")
