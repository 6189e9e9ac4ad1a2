"""Pure, batched models shared by the simulators and the estimators (no I/O, no randomness inside).

:mod:`.measurements` (range, bearing and TDOA ``h(x)``, each with its analytic Jacobian beside it),
:mod:`.motion` (constant-velocity and constant-acceleration target models), :mod:`.vehicles` (surface
vehicle kinematics), :mod:`.acoustics` (sound speed, travel time <-> range, layered ray tracing),
:mod:`.currents` and :mod:`.currents_cf` (analytic, gridded and CF NetCDF ocean currents), :mod:`.drift`
(drifter integration), :mod:`.obstacles` (map bounds and obstacles), :mod:`.energy` (the AquaQuad energy
budget) and :mod:`.paths` (drift/flight paths and their energy).
"""
