"""Reproduce the AquaQuad thesis' lab test of the TDOA UKF (Chapter V.C, Figures 62-67).

Three nodes hold position in a Y around a target that a person moves at random (stop and go); every
0.005 s the UKF ingests TDOA pseudo-measurements made from the true ranges with ``c = 1500 m/s`` plus white
noise. The thesis reports one run: a position mean square error of 0.21 (X) and 0.88 (Y) (printed as
"meters"; read as m^2), an injected noise of 0.0011 s mean magnitude, and residual peaks that coincide with
HDOP peaks (Figure 67). We simulate a Monte Carlo of random target paths and report the residual-HDOP
correlation over time per run (Pearson and Spearman, after the first two seconds of convergence), its
spread over runs, and the error statistics beside the thesis' values.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.config.flock import FlockScenario, load_flock_scenario
from oceanloc.errors import ConfigError
from oceanloc.estimation.gaussian import Gaussian
from oceanloc.estimation.tracking import run_filter
from oceanloc.estimation.unscented import SigmaPointParams
from oceanloc.evaluation.montecarlo import run_chunked
from oceanloc.sim.flock import epoch_times, scenario_nodes, simulate_scenario

SCENARIO = "dillard-lab-tdoa"
THESIS_MSE_X_M2 = 0.21
THESIS_MSE_Y_M2 = 0.88
THESIS_MEAN_ABS_NOISE_S = 0.0011
SETTLE_S = 2.0
"""The thesis' filter converged within two seconds (Figure 65); correlations use the time after that."""


@dataclass(frozen=True, slots=True, kw_only=True)
class _LabChunk:
    mse_xy: FloatArray  # (r, 2)
    pearson: FloatArray  # (r,)
    spearman: FloatArray  # (r,)
    mean_abs_noise_s: FloatArray  # (r,)
    nis_ratio: FloatArray  # (r,) mean NIS / dof
    residual_m: FloatArray  # (r, T_dec)
    hdop_m: FloatArray  # (r, T_dec)
    truth: FloatArray | None  # run 0, (T_dec, 6)
    estimates: FloatArray | None  # run 0, (T_dec, 6)
    tdoa_clean_s: FloatArray | None  # run 0, (T_dec, P)
    tdoa_noisy_s: FloatArray | None  # run 0, (T_dec, P)


@dataclass(frozen=True, slots=True)
class _LabTask:
    scenario: FlockScenario
    every: int

    def __call__(self, run_indices: np.ndarray) -> _LabChunk:
        sc = self.scenario
        r = len(run_indices)
        sim = simulate_scenario(sc, run_indices)
        times, nodes, truth, model = sim.times_s, sim.nodes_m, sim.truth, sim.sensor_model
        clean, z = sim.clean, sim.measurements
        f = sc.filters
        motion = f.motion_model(f.ukf_motion, sc.dt_s)
        params = SigmaPointParams(alpha=f.ukf_alpha, beta=f.ukf_beta, kappa=f.ukf_kappa)
        init = Gaussian.from_single(f.initial_state, f.initial_cov, r)
        res = run_filter("ukf", init, motion, model, z, nodes, params=params, record_covariances=False)
        err = truth[..., :2] - res.estimates[..., :2]
        residual = np.linalg.norm(err, axis=-1)
        settled = times >= SETTLE_S
        pearson = np.array(
            [np.corrcoef(residual[i, settled], res.hdop_m[i, settled])[0, 1] for i in range(r)]
        )
        import scipy.stats

        spearman = np.array(
            [scipy.stats.spearmanr(residual[i, settled], res.hdop_m[i, settled]).statistic for i in range(r)]
        )
        keep = slice(self.every - 1, None, self.every)
        first = run_indices[0] == 0
        return _LabChunk(
            mse_xy=np.mean(err**2, axis=1),
            pearson=pearson,
            spearman=spearman,
            mean_abs_noise_s=np.mean(np.abs(z - clean), axis=(1, 2)),
            nis_ratio=res.nis.sum(axis=1) / res.nis_dof.sum(axis=1),
            residual_m=residual[:, keep],
            hdop_m=res.hdop_m[:, keep],
            truth=truth[0, keep] if first else None,
            estimates=res.estimates[0, keep] if first else None,
            tdoa_clean_s=clean[0, keep] if first else None,
            tdoa_noisy_s=z[0, keep] if first else None,
        )


@dataclass(frozen=True, slots=True, kw_only=True)
class LabTdoaResult:
    """Monte Carlo of the lab TDOA test.

    Attributes
    ----------
    mse_xy_m2 : (R, 2) float
        Position mean square error per run (X, Y).
    pearson, spearman : (R,) float
        Correlation over time of the position residual with HDOP, per run (after ``SETTLE_S``).
    mean_abs_noise_s : (R,) float
        Mean magnitude of the injected TDOA noise (the thesis reports 0.0011 s).
    nis_ratio : (R,) float
        Mean NIS over its degrees of freedom (1 for a consistent filter; the thesis' R is half the noise).
    times_s : (T_dec,) float
        Decimated epochs of the time series below.
    residual_m, hdop_m : (R, T_dec) float
    nodes_m : (3, 2) float
    truth, estimates : (T_dec, 6) float
        Run 0.
    tdoa_clean_s, tdoa_noisy_s : (T_dec, P) float
        Run 0's TDOA before and after noise (Figure 62).
    """

    scenario: FlockScenario
    runs: int
    mse_xy_m2: FloatArray
    pearson: FloatArray
    spearman: FloatArray
    mean_abs_noise_s: FloatArray
    nis_ratio: FloatArray
    times_s: FloatArray
    residual_m: FloatArray
    hdop_m: FloatArray
    nodes_m: FloatArray
    truth: FloatArray
    estimates: FloatArray
    tdoa_clean_s: FloatArray
    tdoa_noisy_s: FloatArray

    def to_json(self) -> dict[str, object]:
        """Summary statistics (means and standard deviations over runs) beside the thesis' values."""

        def stat(x: FloatArray) -> dict[str, float]:
            sd = float(np.std(x, ddof=1)) if x.size > 1 else 0.0
            return {"mean": float(np.mean(x)), "sd": sd, "median": float(np.median(x))}

        return {
            "runs": self.runs,
            "mse_x_m2": stat(self.mse_xy_m2[:, 0]),
            "mse_y_m2": stat(self.mse_xy_m2[:, 1]),
            "thesis_mse_x_m2": THESIS_MSE_X_M2,
            "thesis_mse_y_m2": THESIS_MSE_Y_M2,
            "residual_hdop_pearson": stat(self.pearson),
            "residual_hdop_spearman": stat(self.spearman),
            "mean_abs_noise_s": stat(self.mean_abs_noise_s),
            "thesis_mean_abs_noise_s": THESIS_MEAN_ABS_NOISE_S,
            "nis_over_dof": stat(self.nis_ratio),
        }


def reproduce_dillard_lab_tdoa(
    scenario: FlockScenario | str = SCENARIO,
    *,
    runs: int | None = None,
    seed: int | None = None,
    executor: object | None = None,
    chunk_size: int | None = None,
    progress: Callable[[int], None] | None = None,
) -> LabTdoaResult:
    """Run the lab TDOA Monte Carlo (random target paths and noise per run)."""
    sc = load_flock_scenario(scenario) if isinstance(scenario, str) else scenario
    if runs is not None:
        sc = sc.with_overrides(runs=runs)
    if seed is not None:
        sc = sc.with_overrides(seed=seed)
    if sc.kind != "tdoa":
        raise ConfigError(f"{sc.name}: the lab reproduction needs TDOA measurements, got {sc.kind}")
    if sc.duration_s <= SETTLE_S + 10 * sc.dt_s:
        raise ConfigError(f"{sc.name}: duration must exceed the {SETTLE_S} s convergence time")
    every = max(1, round(0.05 / sc.dt_s))
    task = _LabTask(scenario=sc, every=every)
    chunks = run_chunked(task, sc.runs, executor=executor, chunk_size=chunk_size, progress=progress)  # type: ignore[arg-type]
    times = epoch_times(sc.dt_s, sc.duration_s)
    first = next(c for c in chunks if c.truth is not None)

    def cat(name: str) -> FloatArray:
        return np.concatenate([getattr(c, name) for c in chunks], axis=0)

    assert first.truth is not None and first.estimates is not None
    assert first.tdoa_clean_s is not None and first.tdoa_noisy_s is not None
    return LabTdoaResult(
        scenario=sc,
        runs=sc.runs,
        mse_xy_m2=cat("mse_xy"),
        pearson=cat("pearson"),
        spearman=cat("spearman"),
        mean_abs_noise_s=cat("mean_abs_noise_s"),
        nis_ratio=cat("nis_ratio"),
        times_s=times[every - 1 :: every],
        residual_m=cat("residual_m"),
        hdop_m=cat("hdop_m"),
        nodes_m=scenario_nodes(sc, times[:1])[0],
        truth=first.truth,
        estimates=first.estimates,
        tdoa_clean_s=first.tdoa_clean_s,
        tdoa_noisy_s=first.tdoa_noisy_s,
    )
