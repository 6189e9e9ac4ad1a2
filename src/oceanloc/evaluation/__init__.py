"""Monte Carlo orchestration and its metrics: many runs of a simulation or replay, summarized.

:mod:`.montecarlo` runs chunks of runs in this process, local worker processes or a Dask cluster
(``run_chunked``, ``concat_runs``, ``resolve_workers``); results do not depend on the chunking.
:mod:`.survey` and :mod:`.replay` are the survey and replay Monte Carlo studies, :mod:`.metrics` their
RMSEE and log det statistics; the drift-planner and path-following studies sit beside them.
"""
