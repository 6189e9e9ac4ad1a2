"""Shared small tracking problems for the estimation tests."""

import numpy as np

from oceanloc.estimation.gaussian import Gaussian
from oceanloc.estimation.tracking import FlockSensorModel
from oceanloc.models.motion import constant_velocity

SENSORS = np.array([[600.0, 0.0], [0.0, 600.0], [-600.0, 0.0], [0.0, -600.0]])


def consistent_bearing_problem(
    runs: int, epochs: int, seed: int, kind: str = "bearing", sigma: float = 0.005
):
    """Truth drawn from the filter's own model: x_0 ~ N(m_0, P_0), CV with white acceleration, 4 nodes."""
    rng = np.random.default_rng(seed)
    motion = constant_velocity(1.0, 0.05)
    m0 = np.array([50.0, -30.0, 2.0, 1.0])
    p0 = np.diag([20.0, 20.0, 1.0, 1.0]) ** 2
    x = m0 + rng.standard_normal((runs, 4)) @ np.linalg.cholesky(p0).T
    chol_q = np.linalg.cholesky(motion.process_noise)
    truth = np.empty((runs, epochs, 4))
    for k in range(epochs):
        x = x @ motion.transition.T + rng.standard_normal((runs, 4)) @ chol_q.T
        truth[:, k] = x
    model = FlockSensorModel.build(kind, 4, sigma)
    z = model.measure(truth, SENSORS) + sigma * rng.standard_normal((runs, epochs, model.dim))
    return motion, model, Gaussian.from_single(m0, p0, runs), truth, z
