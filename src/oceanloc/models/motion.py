"""Target motion models: constant velocity (CV) and constant acceleration (CA) in the horizontal plane.

The AquaQuad thesis tracks the state ``x = [X, Y, u, v, ax, ay]`` (eq. III.1) and propagates it with
``Phi = exp(A dt)`` (Chapter III.C), ``A`` the continuous-time system matrix of the kinematic chain
position <- velocity <- acceleration. The matching process noise is the exact discretization of a
continuous white-noise input on the highest derivative (white acceleration for CV, white jerk for CA),
``Q = integral_0^dt Phi(s) L Qc L^T Phi(s)^T ds``, computed with Van Loan's matrix-exponential method
(Van Loan 1978) rather than typed-in polynomial blocks, so any order follows from one function.

State layouts (components last, axes interleaved by derivative as in the thesis):

- CV: ``[X, Y, u, v]``;
- CA: ``[X, Y, u, v, ax, ay]``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from oceanloc._typing import ArrayLike, FloatArray


@dataclass(frozen=True, slots=True, kw_only=True)
class LinearMotionModel:
    """A discrete linear-Gaussian motion model ``x_{k+1} = F x_k + w_k``, ``w_k ~ N(0, Q)``.

    Attributes
    ----------
    transition : (n, n) float
        ``F = exp(A dt)``.
    process_noise : (n, n) float
        ``Q``, symmetric positive semi-definite.
    dt_s : float
        Step, seconds.
    """

    transition: FloatArray
    process_noise: FloatArray
    dt_s: float

    def __post_init__(self) -> None:
        f = np.asarray(self.transition, dtype=float)
        q = np.asarray(self.process_noise, dtype=float)
        n = f.shape[0]
        if f.shape != (n, n) or q.shape != (n, n):
            raise ValueError(f"transition and process noise must be (n, n); got {f.shape} and {q.shape}")
        if not np.allclose(q, q.T, rtol=1e-12, atol=0.0):
            raise ValueError("process noise must be symmetric")
        object.__setattr__(self, "transition", f)
        object.__setattr__(self, "process_noise", q)

    @property
    def dim(self) -> int:
        """State dimension ``n``."""
        return int(self.transition.shape[0])

    def propagate(self, states: ArrayLike) -> FloatArray:
        """``F x`` for a batch of states ``(..., n)``."""
        return np.asarray(states, dtype=float) @ self.transition.T

    def with_process_noise(self, process_noise: ArrayLike) -> LinearMotionModel:
        """The same transition with another (e.g. hand-tuned, diagonal) ``Q``."""
        return LinearMotionModel(
            transition=self.transition, process_noise=np.asarray(process_noise, dtype=float), dt_s=self.dt_s
        )


def kinematic_system_matrix(order: int, n_axes: int = 2) -> FloatArray:
    """Continuous-time ``A`` of a chain of integrators, ``order`` derivatives per axis.

    ``order = 2`` (CV): ``d[X, Y] = [u, v]``; ``order = 3`` (CA): additionally ``d[u, v] = [ax, ay]``.

    Returns
    -------
    (order * n_axes, order * n_axes) float
    """
    if order < 1 or n_axes < 1:
        raise ValueError(f"order and axes must be positive, got {order}, {n_axes}")
    n = order * n_axes
    a = np.zeros((n, n))
    for k in range(order - 1):
        for axis in range(n_axes):
            a[k * n_axes + axis, (k + 1) * n_axes + axis] = 1.0
    return a


def discretize(system: ArrayLike, noise_input: ArrayLike, dt_s: float) -> tuple[FloatArray, FloatArray]:
    """Exact discretization of ``dx = A x dt + dW``, ``E[dW dW^T] = Qc dt`` (Van Loan's method).

    Parameters
    ----------
    system : (n, n) float
        ``A``.
    noise_input : (n, n) float
        ``L Qc L^T``, the continuous-time noise spectral density mapped into the state.
    dt_s : float
        Step, seconds.

    Returns
    -------
    transition : (n, n) float
        ``exp(A dt)``.
    process_noise : (n, n) float
        ``integral_0^dt exp(A s) L Qc L^T exp(A s)^T ds``.
    """
    a = np.asarray(system, dtype=float)
    g = np.asarray(noise_input, dtype=float)
    n = a.shape[0]
    block = np.zeros((2 * n, 2 * n))
    block[:n, :n] = -a
    block[:n, n:] = g
    block[n:, n:] = a.T
    import scipy.linalg

    e = scipy.linalg.expm(block * dt_s)
    transition = e[n:, n:].T
    q = transition @ e[:n, n:]
    return transition, 0.5 * (q + q.T)


def _chain_model(order: int, dt_s: float, spectral_density: float) -> LinearMotionModel:
    if not dt_s > 0:
        raise ValueError(f"time step must be positive, got {dt_s}")
    if spectral_density < 0:
        raise ValueError(f"spectral density must be non-negative, got {spectral_density}")
    a = kinematic_system_matrix(order)
    g = np.zeros_like(a)
    g[-2:, -2:] = spectral_density * np.eye(2)
    transition, q = discretize(a, g, dt_s)
    return LinearMotionModel(transition=transition, process_noise=q, dt_s=dt_s)


def constant_velocity(dt_s: float, accel_psd_m2_s3: float = 0.0) -> LinearMotionModel:
    """Constant-velocity model on ``[X, Y, u, v]`` driven by white acceleration.

    Parameters
    ----------
    dt_s : float
        Step, seconds.
    accel_psd_m2_s3 : float
        Power spectral density ``q`` of the white acceleration, m^2/s^3. Per axis
        ``Q = q [[dt^3/3, dt^2/2], [dt^2/2, dt]]``.
    """
    return _chain_model(2, dt_s, accel_psd_m2_s3)


def constant_acceleration(dt_s: float, jerk_psd_m2_s5: float = 0.0) -> LinearMotionModel:
    """Constant-acceleration model on ``[X, Y, u, v, ax, ay]`` (thesis eq. III.1) driven by white jerk.

    ``F = exp(A dt)`` has per axis the rows ``[1, dt, dt^2/2]``, ``[0, 1, dt]``, ``[0, 0, 1]``; ``Q`` is the
    matching white-jerk noise (``q dt^5/20, q dt^4/8, ...``).

    Parameters
    ----------
    dt_s : float
        Step, seconds.
    jerk_psd_m2_s5 : float
        Power spectral density of the white jerk, m^2/s^5.
    """
    return _chain_model(3, dt_s, jerk_psd_m2_s5)
