"""Closed loops and synthetic data: the estimators and planners run against a simulated world.

:mod:`.survey` (closed-loop transponder surveys, vectorized across Monte Carlo runs), :mod:`.flock`
(drifting sensor nodes, target trajectories, noisy measurements), :mod:`.path_following` and
:mod:`.drifters` (following drift plans in a perturbed current; two drifters swapping positions) and
:mod:`.logs` (realistic GPS and USBL logs of a pier experiment).
"""
