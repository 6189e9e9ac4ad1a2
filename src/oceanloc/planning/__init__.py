"""Where to measure or where to go: planners that take a problem and return a result with a status.

:mod:`.measurement_sites` holds the D-optimal measurement-site planners of the transponder surveys
(multi-step look-ahead over yaw rates, greedy within a reach) and the papers' random baselines, built on
:mod:`.information` (the information gain) and :mod:`.box_search` (their global maximization);
:mod:`.site_planners` gives them one vocabulary (names, parser, label, factory). :mod:`.dop` computes
dilution of precision maps and HDOP-optimal node placement; :mod:`.drift_rrt` the energy-aware drift
planners (DR-RRT* and oceanloc's drift/hop lattice planner). :mod:`.status` is the shared outcome
vocabulary, :mod:`.random_problems` random planning problems for tests and benchmarks.
"""
