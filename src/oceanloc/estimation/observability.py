"""What a set of measurements can separate: the information's eigen-directions against the prior, the
parameters held at their prior, their "consider" covariance, and the linearization check of a factor graph.

**Observability.** With the whitened Jacobian ``J`` of the data and the prior covariance ``P_0 = L L^T``,
the data's information in prior units is ``M = L^T J^T J L``. An eigenvector ``v`` of ``M`` with
eigenvalue ``lambda`` is a combination of parameters (``L v`` in their units) about which the data know
``lambda`` times what the prior knows: ``lambda = 0`` is a direction the track cannot see at all (the
roll misalignment against the beacon's position across a single straight line, the lever arm's down
component against the beacon's depth, the turn-around delay against a range bias), a small ``lambda`` one
it barely sees. Where ``lambda`` is below a threshold (1 by default: the data know less than the prior),
the estimate along ``v`` would be the prior plus noise. :func:`held_parameters` then holds, one direction
at a time, the calibration parameter with the largest share of ``v`` (in prior standard deviations) at
its prior mean and names it with the parameters it cannot be told from (those whose posterior
correlation with it, before holding, is at least 0.5); beacon coordinates are never
held (a direction made of them alone is reported, and their estimate there is the prior's).

**Consider covariance.** A held parameter ``c`` stays at its prior mean ``c_0`` with its prior
covariance ``P_c``; the estimate of the free ones ``f`` then carries the error of ``c_0`` through the
data: with ``P_f = (J_f^T J_f + P_{0,f}^-1)^-1`` and ``S = P_f J_f^T J_c``, the error covariance is
``P_f + S P_c S^T``, and ``-S P_c`` between ``f`` and ``c`` (Schmidt's consider parameters). Holding a
parameter therefore never makes the others look better than they are.

**Linearization check.** As :func:`~oceanloc.estimation.consistency.range_linearization_check` does for
the range survey, generalized to any whitened model: the cost at the ``2 d`` sigma points of the
confidence ellipsoid against the quadratic prediction ``1/2 Delta^T Y Delta``; trusted when every ratio
lies in :data:`~oceanloc.estimation.consistency.LINEARIZATION_BAND`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from oceanloc._typing import BoolArray, FloatArray, IntArray
from oceanloc.errors import ConfigError
from oceanloc.estimation.consistency import LINEARIZATION_BAND

DEFAULT_OBSERVABILITY_RATIO = 1.0
"""Data-to-prior information ratio below which a direction counts as not seen by the track."""

_SHARE_HELD = 0.1
"""Smallest share (largest component 1) a calibration parameter needs in a weak direction to be held."""

_SHARE_NAMED = 0.3
"""Share from which a beacon coordinate is named in a weak direction made of beacon coordinates alone."""

_CORR_NAMED = 0.5
"""Posterior correlation (before holding) from which another parameter is named as what the held one
cannot be told from."""


@dataclass(frozen=True, slots=True, kw_only=True)
class Observability:
    """Eigen-directions of the data's information in prior units, for ``B`` problems over ``d`` parameters.

    Attributes
    ----------
    ratio : (B, d) float
        Eigenvalues ``lambda`` (data information / prior information along each direction), ascending.
    directions : (B, d, d) float
        Column ``j``: the direction of ``ratio[:, j]`` in parameter units (``L v``), scaled so that its
        largest component in prior standard deviations is 1.
    """

    ratio: FloatArray
    directions: FloatArray


def observability(data_information: FloatArray, prior_cov: FloatArray) -> Observability:
    """The eigen-directions of ``L^T Y_data L`` (module docstring); ``Y_data``, ``P_0`` are ``(B, d, d)``."""
    chol = np.linalg.cholesky(prior_cov)
    m = np.swapaxes(chol, -1, -2) @ data_information @ chol
    lam, vec = np.linalg.eigh(0.5 * (m + np.swapaxes(m, -1, -2)))
    raw = chol @ vec
    share = raw / np.sqrt(np.diagonal(prior_cov, axis1=-2, axis2=-1))[..., :, None]
    top = np.max(np.abs(share), axis=-2, keepdims=True)
    return Observability(ratio=lam, directions=raw / np.where(top > 0, top, 1.0))


@dataclass(frozen=True, slots=True, kw_only=True)
class HeldParameters:
    """Which parameters a track cannot see, for ``B`` problems.

    Attributes
    ----------
    held : (B, d) bool
        Held at their prior mean.
    notes : tuple of B tuples of str
        One line per held parameter (and per weak direction made of beacon coordinates alone), naming
        what it cannot be told from and the data/prior information ratio.
    """

    held: BoolArray
    notes: tuple[tuple[str, ...], ...]


def held_parameters(
    data_information: FloatArray,
    prior_cov: FloatArray,
    names: Sequence[str],
    holdable: BoolArray,
    threshold: float = DEFAULT_OBSERVABILITY_RATIO,
) -> HeldParameters:
    """Decide, problem by problem, which parameters to hold at their prior (module docstring).

    Parameters
    ----------
    data_information : (B, d, d) float
        ``J^T J`` of the data alone (whitened), at the estimate.
    prior_cov : (B, d, d) float
    names : sequence of d str
        Parameter names for the notes (``"misalignment roll"``).
    holdable : (d,) bool
        Parameters that may be held (the calibration parameters, not the beacon coordinates).
    threshold : float
        Data/prior information ratio below which a direction is not seen.
    """
    if not threshold > 0.0:
        raise ConfigError(f"observability threshold must be positive, got {threshold}")
    y = np.asarray(data_information, dtype=float)
    p0 = np.asarray(prior_cov, dtype=float)
    batch, d = y.shape[0], y.shape[-1]
    held = np.zeros((batch, d), dtype=bool)
    notes: list[tuple[str, ...]] = []
    for b in range(batch):
        lines: list[str] = []
        free = np.ones(d, dtype=bool)
        reported: set[tuple[int, ...]] = set()
        for _ in range(d):
            idx = np.flatnonzero(free)
            y_f, p_f = y[b][np.ix_(idx, idx)], p0[b][np.ix_(idx, idx)]
            obs = observability(y_f[None], p_f[None])
            post = np.linalg.inv(y_f + np.linalg.inv(p_f))
            sd = np.sqrt(np.diag(post))
            corr = post / np.outer(sd, sd)
            chosen = None
            for w in np.flatnonzero(obs.ratio[0] < threshold):
                share = np.abs(obs.directions[0][:, w] / np.sqrt(np.diag(p_f)))
                share = share / max(share.max(), 1e-300)
                cand = [k for k in range(idx.size) if holdable[idx[k]] and share[k] >= _SHARE_HELD]
                if cand:
                    k = max(cand, key=lambda k: share[k])
                    partners = [
                        idx[o]
                        for o in np.argsort(-np.abs(corr[k]))
                        if o != k and abs(corr[k, o]) >= _CORR_NAMED
                    ]
                    chosen = (idx[k], partners, obs.ratio[0][w])
                    break
                others = tuple(sorted(idx[o] for o in range(idx.size) if share[o] >= _SHARE_NAMED))
                if others not in reported:
                    reported.add(others)
                    lines.append(
                        f"{' / '.join(names[o] for o in others)}: not determined by this track (data/prior "
                        f"information {max(obs.ratio[0][w], 0.0):.2g}); the estimate there is the prior's"
                    )
            if chosen is None:
                break
            j, partners, ratio = chosen
            free[j] = False
            held[b, j] = True
            what = (
                f"not separable from {', '.join(names[o] for o in partners)} on this track"
                if partners
                else "not measured better than its prior by this track"
            )
            lines.append(
                f"{names[j]} held at its prior: {what} (data/prior information {max(ratio, 0.0):.2g})"
            )
        notes.append(tuple(lines))
    return HeldParameters(held=held, notes=tuple(notes))


def consider_covariance(
    jacobian: FloatArray, prior_cov: FloatArray, held: BoolArray
) -> tuple[FloatArray, FloatArray]:
    """The error covariance with ``held`` components at their prior (module docstring).

    Parameters
    ----------
    jacobian : (B, N, d) float
        Whitened data Jacobian at the estimate.
    prior_cov : (B, d, d) float
        Block-diagonal between held and free components (the calibration's priors are).
    held : (d,) bool
        One mask for the batch.

    Returns
    -------
    covariance : (B, d, d) float
        With the consider terms.
    free_covariance : (B, d_f, d_f) float
        ``P_f`` alone (the free components' covariance as if the held ones were exact).
    """
    held = np.asarray(held, dtype=bool)
    f = np.flatnonzero(~held)
    c = np.flatnonzero(held)
    jf = jacobian[:, :, f]
    info_f = np.swapaxes(jf, 1, 2) @ jf + np.linalg.inv(prior_cov[:, f][:, :, f])
    p_f = _sym(np.linalg.inv(info_f))
    d = prior_cov.shape[-1]
    cov = np.zeros((jacobian.shape[0], d, d))
    if c.size == 0:
        cov[:] = p_f
        return cov, p_f
    p_c = prior_cov[:, c][:, :, c]
    s = p_f @ np.swapaxes(jf, 1, 2) @ jacobian[:, :, c]
    cov[np.ix_(np.arange(cov.shape[0]), f, f)] = p_f + s @ p_c @ np.swapaxes(s, 1, 2)
    cross = -s @ p_c
    cov[np.ix_(np.arange(cov.shape[0]), f, c)] = cross
    cov[np.ix_(np.arange(cov.shape[0]), c, f)] = np.swapaxes(cross, 1, 2)
    cov[np.ix_(np.arange(cov.shape[0]), c, c)] = p_c
    return _sym(cov), p_f


def _sym(a: FloatArray) -> FloatArray:
    return 0.5 * (a + np.swapaxes(a, -1, -2))


@dataclass(frozen=True, slots=True, kw_only=True)
class GraphLinearizationCheck:
    """:func:`graph_linearization_check` for ``B`` estimates: ``ratio (B, 2 d_f)``, ``statistic (B,)``
    (``max |log ratio|``), ``trusted (B,)`` and the ellipsoid's ``confidence``."""

    ratio: FloatArray
    statistic: FloatArray
    trusted: BoolArray
    confidence: float


def graph_linearization_check(
    residuals,
    estimate: FloatArray,
    free: IntArray,
    free_covariance: FloatArray,
    prior_mean: FloatArray,
    prior_cov: FloatArray,
    *,
    confidence: float = 0.95,
    band: tuple[float, float] = LINEARIZATION_BAND,
) -> GraphLinearizationCheck:
    """Whether the linearized covariance of the free components can be trusted (module docstring).

    Parameters
    ----------
    residuals : callable
        ``residuals(x (b, d), rows (b,)) -> (b, N)``, the whitened data residuals (a
        :class:`~oceanloc.estimation.factors.FactorGraph`'s ``residuals``).
    estimate : (B, d) float
        Full states (held components at their held values).
    free : (d_f,) int
        The components estimated.
    free_covariance : (B, d_f, d_f) float
        Their covariance ``(J_f^T J_f + P_{0,f}^-1)^-1``.
    prior_mean, prior_cov : (B, d) and (B, d, d) float
    """
    from oceanloc.estimation.consistency import _stats

    batch, nf = estimate.shape[0], free.size
    lam, vec = np.linalg.eigh(_sym(free_covariance))
    c = float(np.sqrt(_stats().chi2.ppf(confidence, nf)))
    axes = np.swapaxes(c * np.sqrt(np.maximum(lam, 0.0))[:, None, :] * vec, 1, 2)  # (B, d_f, d_f) rows
    delta_f = np.concatenate([axes, -axes], axis=1)  # (B, 2 d_f, d_f)
    pts = np.repeat(estimate[:, None, :], 1 + 2 * nf, axis=1)
    pts[:, 1:, free] += delta_f
    rows = np.repeat(np.arange(batch), 1 + 2 * nf)
    r = residuals(pts.reshape(-1, estimate.shape[1]), rows).reshape(batch, 1 + 2 * nf, -1)
    info0 = np.linalg.inv(prior_cov[:, free][:, :, free])
    dev = pts[:, :, free] - prior_mean[:, None, free]
    cost = 0.5 * np.sum(r * r, axis=-1) + 0.5 * np.einsum("bci,bij,bcj->bc", dev, info0, dev)
    info = np.linalg.inv(free_covariance)
    predicted = 0.5 * np.einsum("bci,bij,bcj->bc", delta_f, info, delta_f)
    ratio = (cost[:, 1:] - cost[:, :1]) / np.maximum(predicted, 1e-300)
    statistic = np.max(np.abs(np.log(np.maximum(ratio, 1e-300))), axis=1)
    trusted = np.all((ratio >= band[0]) & (ratio <= band[1]), axis=1)
    return GraphLinearizationCheck(ratio=ratio, statistic=statistic, trusted=trusted, confidence=confidence)
