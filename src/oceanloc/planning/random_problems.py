"""Random but realistic planning problems for the transponder-survey planners (tests and benchmarks)."""

from __future__ import annotations

import numpy as np

from oceanloc.models.measurements import range_jacobian
from oceanloc.planning.measurement_sites import PlanningState

JOURNAL_TRANSPONDERS = np.array(
    [[17.0, 15.0, -6.0], [-2.0, -1.0, -7.0], [5.0, 5.0, -10.0], [-9.0, 13.0, -8.0]]
)


def random_planning_states(rng: np.random.Generator, batch: int, n_transponders: int) -> PlanningState:
    """States as a survey would produce them: covariances after 1-12 ranges from random surface sites
    (prior diag(1e4, 1e4, 4), sigma 0.12 m), estimates perturbed from the journal's transponders."""
    truth = JOURNAL_TRANSPONDERS[:n_transponders]
    prior_info = np.linalg.inv(np.diag([1e4, 1e4, 4.0]))
    covs = np.empty((batch, n_transponders, 3, 3))
    ests = np.empty((batch, n_transponders, 3))
    for b in range(batch):
        n = int(rng.integers(1, 13))
        sites = np.column_stack([rng.uniform(-25, 25, (n, 2)), np.zeros(n)])
        for m in range(n_transponders):
            h = range_jacobian(truth[m], sites)
            covs[b, m] = np.linalg.inv(prior_info + h.T @ h / 0.12**2)
            est = truth[m] + rng.normal(0.0, np.sqrt(np.minimum(np.diag(covs[b, m]), 25.0)))
            est[2] = -abs(est[2])
            ests[b, m] = est
    pos = np.column_stack([rng.uniform(-25, 25, (batch, 2)), np.zeros(batch)])
    return PlanningState(
        pos_enu_m=pos, yaw_rad=rng.uniform(-np.pi, np.pi, batch), estimates_m=ests, covariances_m2=covs
    )
