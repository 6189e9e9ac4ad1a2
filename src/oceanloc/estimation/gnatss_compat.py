"""GNATSS's array solution under GNATSS's own settings, batched in numpy (the "same settings" mode).

What GNATSS's solver (v0.4) does, restated from its documentation and source so that oceanloc can run
the very same estimate on the same pings (and be compared with it to the millimetre):

1. Replies are grouped by interrogation; an interrogation is dropped if it lies in a deletion window,
   if a position's ``sqrt(sum(diag(cov)^2))`` reaches ``gps_sigma_limit`` (GNATSS's "3-D sigma"
   test, applied to the covariance diagonal as written), if the interrogation position is farther than
   ``distance_limit`` horizontally from the array centre, or if not every transponder replied.
2. Each transponder's sound speed is the harmonic mean of the profile from
   ``harmonic_mean_start_depth`` to its a-priori depth, rounded to 1 mm/s.
3. Model: straight rays, ``TWTT - delay_k = (|p_k - a| + |p_k - b_k|) / c_k``; per interrogation
   the travel-time covariance is ``|U_tx S_tx U_tx^T| * 2 / c^2 + sigma_tt^2 I`` (``U_tx`` the
   unit vectors from the interrogation position, ``S_tx`` its covariance, the absolute value taken
   entry by entry, as GNATSS does; the reply positions' covariance is not used).
4. Weighted least squares of all transponders' corrections with the constraint that they are equal:
   the array's common shift, its geometry fixed at the a-priori positions. Iterate until every
   ``|shift| <= 0.1 sigma`` (at most seven iterations); the reported positions are those of the last
   iteration (the final, converged increment is not applied).
5. Residuals are reported in one-way centimetres at 1500 m/s; interrogations whose residual exceeds
   ``residual_limit`` or whose spread across transponders exceeds ``residual_range_limit`` are
   outliers; GNATSS's documented procedure re-runs the solver with them deleted
   (``--remove-outliers``), which ``outlier_rounds = 2`` reproduces.

Everything is batched over interrogations (no per-ping Python loop); the constrained solution is
written directly as the common shift ``(J^T N J)^-1 J^T b`` (``J`` stacks identities), which equals
GNATSS's Lagrange-multiplier form.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pymap3d

from oceanloc._typing import BoolArray, FloatArray, IntArray
from oceanloc.errors import DataError
from oceanloc.io.gnatss import RESIDUAL_SPEED_MPS, ArrayPings, GnatssConfig, in_windows


@dataclass(frozen=True, slots=True, kw_only=True)
class GnatssSettings:
    """GNATSS's solver settings (its names and units; defaults are GNATSS's)."""

    distance_limit_m: float = 150.0
    residual_limit_cm: float = 10000.0
    residual_range_limit_cm: float = 20000.0
    residual_outliers_threshold_percent: float = 25.0
    gps_sigma_limit_m: float = 0.05
    travel_times_variance_s2: float = 1e-10
    max_iterations: int = 7
    outlier_rounds: int = 2

    @classmethod
    def from_config(cls, config: GnatssConfig, outlier_rounds: int = 2) -> GnatssSettings:
        return cls(
            distance_limit_m=config.distance_limit_m,
            residual_limit_cm=config.residual_limit_cm,
            residual_range_limit_cm=config.residual_range_limit_cm,
            gps_sigma_limit_m=config.gps_sigma_limit_m,
            travel_times_variance_s2=config.travel_times_variance_s2,
            outlier_rounds=outlier_rounds,
        )


@dataclass(frozen=True, slots=True, kw_only=True)
class GnatssIteration:
    """One iteration: RMS residual (cm, at the transponders' speeds), error factor, common shift (m)."""

    rms_residual_cm: float
    error_factor: float
    shift_xyz_m: FloatArray
    sigma_xyz_m: FloatArray


@dataclass(frozen=True, slots=True, kw_only=True)
class GnatssSolution:
    """The array's position by GNATSS's method.

    Attributes
    ----------
    ids : tuple of str
    position_xyz_m : (m, 3) float
        Final Earth-fixed transponder positions (a-priori + the accumulated common shift), metres.
    apriori_xyz_m : (m, 3) float
    covariance_xyz_m2 : (3, 3) float
        Covariance of the common shift (of every transponder's position), Earth-fixed, m^2.
    sound_speed_mps : (m,) float
    iterations : tuple of GnatssIteration
        Those of the last outlier round.
    converged : bool
    reply_used : (n,) bool
        Replies of the input used in the final round.
    reply_reason : (n,) str
        Why each unused reply was dropped ("" when used).
    residual_s : (n,) float
        Every reply's travel-time residual at the final positions, seconds.
    epoch_t_s : (E,) float
        Interrogations used in the final round, J2000 s.
    epoch_residual_cm : (E, m) float
        Their residuals in GNATSS's one-way centimetres.
    outlier_t_s : (k,) float
        Interrogations found outliers in the final round (still in the solution, as GNATSS leaves them
        until the next ``--remove-outliers`` run).
    deleted_windows : (d, 2) float
        Deletion windows used (the file's, then each round's outliers as single instants), J2000 s.
    """

    ids: tuple[str, ...]
    position_xyz_m: FloatArray
    apriori_xyz_m: FloatArray
    covariance_xyz_m2: FloatArray
    sound_speed_mps: FloatArray
    iterations: tuple[GnatssIteration, ...]
    converged: bool
    reply_used: BoolArray
    reply_reason: tuple[str, ...]
    residual_s: FloatArray
    epoch_t_s: FloatArray
    epoch_residual_cm: FloatArray
    outlier_t_s: FloatArray
    deleted_windows: FloatArray


def apriori_xyz_m(config: GnatssConfig) -> FloatArray:
    """A-priori transponder positions, Earth-fixed: ``(lat, lon, height + geoid_undulation)``."""
    tps = config.transponders
    x, y, z = pymap3d.geodetic2ecef(
        np.array([t.lat_deg for t in tps]),
        np.array([t.lon_deg for t in tps]),
        np.array([t.height_m for t in tps]) + config.geoid_undulation_m,
    )
    return np.stack([x, y, z], axis=-1)


def _epoch_table(pings: ArrayPings, m: int, keep: BoolArray) -> tuple[FloatArray, IntArray]:
    """Interrogation times with all ``m`` replies among ``keep``, and the reply index table (E, m)."""
    t = pings.t_transmit_s[keep]
    idx = np.flatnonzero(keep)
    times, inv, counts = np.unique(t, return_inverse=True, return_counts=True)
    table = np.full((times.size, m), -1, dtype=np.int64)
    table[inv, pings.transponder[idx]] = idx
    full = (counts == m) & np.all(table >= 0, axis=1)
    return times[full], table[full]


def _solve(
    pings: ArrayPings,
    table: IntArray,
    x0: FloatArray,
    speed: FloatArray,
    delay: FloatArray,
    settings: GnatssSettings,
) -> tuple[FloatArray, FloatArray, tuple[GnatssIteration, ...], bool, FloatArray]:
    """GNATSS's iterations on the epochs of ``table``; returns positions, shift covariance, iterations,
    convergence and the (E, m) travel-time residuals of the last iteration."""
    m = x0.shape[0]
    tx = pings.transmit_xyz_m[table[:, 0]]  # (E, 3): one interrogation position per epoch
    rx = pings.receive_xyz_m[table]  # (E, m, 3)
    cov_tx = pings.transmit_cov_m2[table[:, 0]]  # (E, 3, 3)
    tt = pings.twtt_s[table] - delay  # (E, m)
    n_data = tt.size
    x = x0.copy()
    iterations: list[GnatssIteration] = []
    converged = False
    resid = np.zeros_like(tt)
    cov = np.zeros((3, 3))
    # GNATSS divides the partials (m, 3) by the (m,) speeds: component j by c_j for three transponders
    partial_div = speed[None, None, :] if m == 3 else speed[None, :, None]
    for _ in range(settings.max_iterations):
        v_tx = x[None, :, :] - tx[:, None, :]
        v_rx = x[None, :, :] - rx
        d_tx = np.linalg.norm(v_tx, axis=-1)
        d_rx = np.linalg.norm(v_rx, axis=-1)
        resid = tt - (d_tx + d_rx) / speed
        u_tx = v_tx / d_tx[..., None]
        u_rx = v_rx / d_rx[..., None]
        partial = (u_tx + u_rx) / partial_div  # (E, m, 3)
        c_tt = np.abs(u_tx @ cov_tx @ np.swapaxes(u_tx, 1, 2)) * (2.0 / speed**2)[None, None, :]
        c_tt = c_tt + settings.travel_times_variance_s2 * np.eye(m)
        w = np.linalg.inv(c_tt)  # (E, m, m)
        # A_e = blockdiag rows: A_e[i, 3i:3i+3] = partial[i]; A_e J = partial (common shift)
        ajw = np.einsum("eik,eij->ekj", partial, w)  # (E, 3, m): (A J)^T W
        n_c = np.einsum("ekj,ejl->kl", ajw, partial)
        b_c = np.einsum("ekj,ej->k", ajw, resid)
        cov = np.linalg.inv(n_c)
        shift = cov @ b_c
        sigma = np.sqrt(np.maximum(np.diag(cov), 0.0))
        rms_cm = float(np.sqrt(np.sum((100.0 * speed * resid) ** 2) / n_data))
        sig_tt = np.sqrt(np.diagonal(c_tt, axis1=1, axis2=2))
        errfac = float(np.sqrt(np.sum((resid / sig_tt) ** 2) / max(n_data - 3 * m, 1)))
        iterations.append(
            GnatssIteration(rms_residual_cm=rms_cm, error_factor=errfac, shift_xyz_m=shift, sigma_xyz_m=sigma)
        )
        if np.all((np.abs(shift) <= 0.1 * sigma) | (sigma == 0.0)):
            converged = True
            break
        x = x + shift
    return x, cov, tuple(iterations), converged, resid


def gnatss_solve(
    pings: ArrayPings,
    config: GnatssConfig,
    sound_speed_mps: FloatArray,
    settings: GnatssSettings | None = None,
    deletions: FloatArray | None = None,
) -> GnatssSolution:
    """The array solution by GNATSS's method (see the module docstring) on per-reply data.

    Parameters
    ----------
    pings : ArrayPings
        Replies with Earth-fixed transducer positions (``transponder`` indexes ``config.ids``).
    config : GnatssConfig
        A-priori positions, internal delays, array centre.
    sound_speed_mps : (m,) float
        Each transponder's harmonic-mean sound speed (GNATSS rounds it to 1 mm/s; pass it rounded for
        identical results).
    settings : GnatssSettings, optional
        Limits (default: those of ``config``).
    deletions : (d, 2) float, optional
        Deletion windows, J2000 seconds.

    Raises
    ------
    DataError
        If no interrogation has every transponder's reply after the cuts, or more than
        ``residual_outliers_threshold_percent`` of the interrogations are outliers (GNATSS refuses too).
    """
    settings = settings or GnatssSettings.from_config(config)
    m = len(config.ids)
    if tuple(pings.ids) != config.ids:
        raise DataError(
            f"{pings.path}: transponders {list(pings.ids)} differ from the configuration's {list(config.ids)}"
        )
    speed = np.asarray(sound_speed_mps, dtype=float)
    delay = np.array([t.internal_delay_s for t in config.transponders])
    x0 = apriori_xyz_m(config)
    n = pings.n_replies
    reason = np.full(n, "", dtype=object)
    windows = np.zeros((0, 2)) if deletions is None else np.asarray(deletions, dtype=float).reshape(-1, 2)
    t = pings.t_transmit_s

    def sig3d(cov: FloatArray) -> FloatArray:
        return np.sqrt(np.sum(np.diagonal(cov, axis1=1, axis2=2) ** 2, axis=1))

    bad_sigma = (sig3d(pings.receive_cov_m2) >= settings.gps_sigma_limit_m) | (
        sig3d(pings.transmit_cov_m2) >= settings.gps_sigma_limit_m
    )
    ac = config.array_center
    e, nn, _ = pymap3d.ecef2enu(*pings.transmit_xyz_m.T, ac.lat_deg, ac.lon_deg, ac.h_m)
    far = np.hypot(e, nn) > settings.distance_limit_m
    base_reason = np.where(bad_sigma, "GNSS 3-D sigma above gps_sigma_limit", "")
    base_reason = np.where(
        far & (base_reason == ""),
        f"farther than {settings.distance_limit_m:g} m from the array centre",
        base_reason,
    )
    outlier_t = np.zeros(0)
    result = None
    for _round in range(max(settings.outlier_rounds, 1)):
        deleted = in_windows(t, windows)
        reason = np.where(deleted, "deleted (deletion window or earlier outlier)", base_reason)
        keep = reason == ""
        times, table = _epoch_table(pings, m, keep)
        incomplete = keep & ~np.isin(np.arange(n), table)
        reason = np.where(incomplete, "not every transponder replied to this interrogation", reason)
        if times.size == 0:
            raise DataError(
                f"{pings.path}: no interrogation with every transponder's reply is left after the cuts"
            )
        x, cov, its, conv, resid = _solve(pings, table, x0, speed, delay, settings)
        res_cm = 100.0 * RESIDUAL_SPEED_MPS * resid / 2.0
        flag = np.any(np.abs(res_cm) > settings.residual_limit_cm, axis=1) | (
            res_cm.max(axis=1) - res_cm.min(axis=1) > settings.residual_range_limit_cm
        )
        outlier_t = times[flag]
        result = (x, cov, its, conv, times, table, res_cm, reason.copy())
        if 100.0 * flag.mean() > settings.residual_outliers_threshold_percent:
            raise DataError(
                f"{pings.path}: {100.0 * flag.mean():.1f} % of the interrogations exceed the residual limits "
                f"({settings.residual_limit_cm:g} cm, range {settings.residual_range_limit_cm:g} cm), above "
                f"the {settings.residual_outliers_threshold_percent:g} % GNATSS accepts"
            )
        if not flag.any() or _round == settings.outlier_rounds - 1:
            break
        windows = np.concatenate([windows, np.column_stack([outlier_t, outlier_t])])
    assert result is not None
    x, cov, its, conv, times, table, res_cm, reason = result
    used = np.zeros(n, dtype=bool)
    used[table.ravel()] = True
    # every reply's residual at the final positions
    v_tx = np.linalg.norm(x[pings.transponder] - pings.transmit_xyz_m, axis=1)
    v_rx = np.linalg.norm(x[pings.transponder] - pings.receive_xyz_m, axis=1)
    residual_all = pings.twtt_s - delay[pings.transponder] - (v_tx + v_rx) / speed[pings.transponder]
    return GnatssSolution(
        ids=config.ids,
        position_xyz_m=x,
        apriori_xyz_m=x0,
        covariance_xyz_m2=cov,
        sound_speed_mps=speed,
        iterations=its,
        converged=conv,
        reply_used=used,
        reply_reason=tuple(str(r) for r in reason),
        residual_s=residual_all,
        epoch_t_s=times,
        epoch_residual_cm=res_cm,
        outlier_t_s=outlier_t,
        deleted_windows=windows,
    )
