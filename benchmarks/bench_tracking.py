"""UKF step speed: oceanloc vs FilterPy on identical inputs (6-state CA target, four bearing sensors).

One predict + update step: a single track, and a batch of 1000 tracks (oceanloc steps them in one
vectorized call; FilterPy steps 1000 filter objects one after another). Both filters get the same sigma-point
parameters (alpha = 1e-3, beta = 2, kappa = 0), the same measurement function, centred state mean, circular
measurement mean and wrapped residual, and their outputs are checked to agree before timing.
Targets: no slower than FilterPy on one track; at least 20x faster per track on the batch.
"""

from __future__ import annotations

import time

import numpy as np
from filterpy.kalman import MerweScaledSigmaPoints, UnscentedKalmanFilter

from oceanloc.estimation.gaussian import Gaussian
from oceanloc.estimation.unscented import SigmaPointParams, ukf_predict, ukf_update
from oceanloc.models.measurements import bearing_rad, wrap_angle_rad
from oceanloc.models.motion import constant_acceleration

SENSORS = np.array([[200.0, 0.0], [0.0, 200.0], [-200.0, 0.0], [0.0, -200.0]])
MOTION = constant_acceleration(0.005).with_process_noise(1e-6 * np.diag([10, 10, 1, 1, 1, 1]))
R = 1e-6 * np.eye(4)
PARAMS = SigmaPointParams(alpha=1e-3, beta=2.0, kappa=0.0)
ANGLES = np.ones(4, dtype=bool)
X0 = np.array([100.0, 100.0, 20.0, 20.0, 0.0, 0.0])
P0 = np.diag([100.0, 100.0, 20.0, 20.0, 1.0, 1.0]) ** 2


def _filterpy() -> UnscentedKalmanFilter:
    f = UnscentedKalmanFilter(
        6,
        4,
        MOTION.dt_s,
        hx=lambda x: bearing_rad(x, SENSORS),
        fx=lambda x, dt: MOTION.transition @ x,
        points=MerweScaledSigmaPoints(6, alpha=1e-3, beta=2.0, kappa=0.0),
        x_mean_fn=lambda s, w: s[0] + w @ (s - s[0]),
        z_mean_fn=lambda s, w: wrap_angle_rad(s[0] + w @ wrap_angle_rad(s - s[0])),
        residual_z=lambda a, b: wrap_angle_rad(a - b),
    )
    f.x, f.P, f.Q, f.R = X0.copy(), P0.copy(), MOTION.process_noise, R
    return f


def _ours(state: Gaussian, z: np.ndarray) -> Gaussian:
    pred = ukf_predict(state, lambda x: x @ MOTION.transition.T, MOTION.process_noise, PARAMS)
    return ukf_update(pred.state, z, lambda x: bearing_rad(x, SENSORS), R, PARAMS, angle_mask=ANGLES).state


def _best_of(fn, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    z = bearing_rad(np.array([0.0, 0.0]), SENSORS) + 0.001
    ref = _filterpy()
    ref.predict()
    ref.update(z)
    mine = _ours(Gaussian.from_single(X0, P0), z[None])
    agree = max(
        np.abs(mine.mean[0] - ref.x).max() / 1000.0, np.abs(mine.cov[0] - ref.P).max() / np.abs(ref.P).max()
    )
    print(f"agreement with FilterPy after one step: {agree:.1e} (relative to the state's scale)")

    single = Gaussian.from_single(X0, P0)
    steps = 200

    def ours_single() -> None:
        for _ in range(steps):
            _ours(single, z[None])

    filters = [_filterpy() for _ in range(steps)]

    def filterpy_single() -> None:
        for f in filters:
            f.predict()
            f.update(z)

    t_ours_1 = _best_of(ours_single, 5) / steps
    t_fp_1 = _best_of(filterpy_single, 5) / steps
    batch = 1000
    state_b = Gaussian.from_single(X0, P0, batch)
    z_b = np.tile(z, (batch, 1))
    t_ours_b = _best_of(lambda: _ours(state_b, z_b), 7)
    fleet = [_filterpy() for _ in range(batch)]

    def filterpy_batch() -> None:
        for f in fleet:
            f.predict()
            f.update(z)

    t_fp_b = _best_of(filterpy_batch, 3)
    speed_1 = t_fp_1 / t_ours_1
    speed_b = (t_fp_b / batch) / (t_ours_b / batch)
    rows = [
        ("one track, per step", t_ours_1, t_fp_1, speed_1, 1.0),
        (f"batch of {batch}, per track per step", t_ours_b / batch, t_fp_b / batch, speed_b, 20.0),
    ]
    print(
        f"{'UKF predict + update, 6 states, 4 bearings':44s} {'oceanloc':>11s} {'FilterPy':>11s} ratio target"
    )
    for name, ours, theirs, ratio, target in rows:
        verdict = "met" if ratio >= target else "MISSED"
        print(
            f"{name:44s} {ours * 1e6:8.2f} us {theirs * 1e6:8.1f} us {ratio:6.1f}x >= {target:g}x {verdict}"
        )


if __name__ == "__main__":
    main()
