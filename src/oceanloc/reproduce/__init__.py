"""Paper reproductions: one module per paper, with its scenarios, published values, side-by-side tables
and acceptance checks.

:mod:`.garcia2019` (journal Section V), :mod:`.garcia2019_replay` (Section VI on recorded data),
:mod:`.garcia2018` (the thesis' greedy planner), :mod:`.dillard_filters`, :mod:`.dillard_lab_tdoa` and
:mod:`.dillard_drrt` (AquaQuad thesis Table 2, lab TDOA test, Table 4); :mod:`.survey_tables` holds the
pieces the survey reproductions share. How each paper was read is in ``docs/``.
"""
