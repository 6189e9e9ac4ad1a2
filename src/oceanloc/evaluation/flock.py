"""Monte Carlo of flock tracking: EKF/UKF variants over noise realizations, and the UKF's residual vs HDOP.

Two experiments, each a picklable chunk task run by :func:`oceanloc.evaluation.montecarlo.run_chunked` and
joined by :func:`~oceanloc.evaluation.montecarlo.concat_runs` (so the numbers do not depend on how runs are
chunked or where they are computed):

- :func:`filter_monte_carlo`: every filter variant (a filter and the motion model it propagates with) on the
  same simulated measurements of a deterministic (straight) target; per-run mean square errors, RMSE over
  time, NEES and the position RMSE over the square root of the posterior Cramer-Rao bound (PCRLB, Tichavsky
  recursion);
- :func:`tracking_hdop_monte_carlo`: the UKF on random target paths; the correlation over time of its
  position residual with the HDOP of the geometry, NIS and the injected noise.

The results have ``to_record()`` (plain JSON-ready summary) and ``to_dataset()`` (an :class:`xarray.Dataset`
with dims ``filter``, ``run``, ``epoch``, ``state``; units on every variable) for
:func:`oceanloc.io.records.write_netcdf`.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from concurrent.futures import Executor
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.config.flock import FlockScenario, MotionKind, check_memory
from oceanloc.errors import ConfigError
from oceanloc.estimation.bounds import measurement_information, pcrlb
from oceanloc.estimation.gaussian import Gaussian
from oceanloc.estimation.tracking import FilterKind, run_filter
from oceanloc.estimation.unscented import SigmaPointParams
from oceanloc.evaluation.montecarlo import concat_runs, run_chunked
from oceanloc.sim.flock import (
    epoch_times,
    scenario_nodes,
    scenario_sensor_model,
    scenario_truth,
    simulate_scenario,
)

if TYPE_CHECKING:
    import xarray as xr

__all__ = [
    "FilterMonteCarlo",
    "FilterVariant",
    "TrackingHdopMonteCarlo",
    "VariantStats",
    "filter_monte_carlo",
    "filter_variants",
    "position_pcrlb",
    "tracking_hdop_monte_carlo",
]

STATE_NAMES: tuple[str, ...] = ("x", "y", "u", "v", "ax", "ay")
STATE_UNITS: tuple[str, ...] = ("m", "m", "m s-1", "m s-1", "m s-2", "m s-2")


@dataclass(frozen=True, slots=True, kw_only=True)
class FilterVariant:
    """A filter and the motion model it propagates with."""

    key: str
    label: str
    filter: FilterKind
    motion: MotionKind

    @property
    def is_control(self) -> bool:
        """A control variant: a filter run with the other filter's motion model."""
        return self.key.endswith("control")


def filter_variants(scenario: FlockScenario, controls: bool = True) -> tuple[FilterVariant, ...]:
    """The scenario's EKF and UKF, plus (``controls``) each filter with the other's motion model.

    The controls separate the estimator (linearization vs unscented transform) from the motion model when the
    two filters are configured with different ones; with equal motion models there are none.
    """
    f = scenario.filters
    out = [
        FilterVariant(key="ekf", label=f"EKF ({f.ekf_motion})", filter="ekf", motion=f.ekf_motion),
        FilterVariant(key="ukf", label=f"UKF ({f.ukf_motion})", filter="ukf", motion=f.ukf_motion),
    ]
    if controls and f.ekf_motion != f.ukf_motion:
        out += [
            FilterVariant(
                key="ekf-control", label=f"EKF ({f.ukf_motion})", filter="ekf", motion=f.ukf_motion
            ),
            FilterVariant(
                key="ukf-control", label=f"UKF ({f.ekf_motion})", filter="ukf", motion=f.ekf_motion
            ),
        ]
    return tuple(out)


def _state_units(n: int) -> str:
    """``"x: m, y: m, u: m s-1, ..."``: the units of a state vector's components (a mixed-unit variable)."""
    return ", ".join(f"{s}: {u}" for s, u in zip(STATE_NAMES[:n], STATE_UNITS[:n], strict=True))


def _sigma_params(scenario: FlockScenario) -> SigmaPointParams:
    f = scenario.filters
    return SigmaPointParams(alpha=f.ukf_alpha, beta=f.ukf_beta, kappa=f.ukf_kappa)


@dataclass(frozen=True, slots=True, kw_only=True)
class FilterRunMetrics:
    """What a chunk of runs sends back, per variant key (joined by ``concat_runs``; ``example`` kept).

    Attributes
    ----------
    sse : (r, n) float
        Sum over epochs of the squared error per run and state component.
    nees_sum : (r,) float
        Sum over epochs of the NEES per run.
    seconds : (r,) float
        The chunk's wall time of the variant shared equally by its runs, seconds.
    sq_err_sum : (1, T, n) float
        Sum over the chunk's runs of the squared error at every epoch (one row per chunk).
    example : (T_dec, n) float
        Run 0's estimates at the decimated epochs (empty for chunks without run 0).
    gated : (r,) int
        Epochs whose measurements the NIS gate rejected, per run.
    diverged_epoch : (r,) int
        First epoch (0-based) of the run's divergence, ``-1`` if none (:func:`run_filter`).
    """

    sse: dict[str, FloatArray]
    nees_sum: dict[str, FloatArray]
    seconds: dict[str, FloatArray]
    sq_err_sum: dict[str, FloatArray]
    example: dict[str, FloatArray]
    gated: dict[str, FloatArray]
    diverged_epoch: dict[str, FloatArray]


def _gate_settings(scenario: FlockScenario) -> dict[str, Any]:
    """``run_filter`` keywords of the scenario's NIS gate (probability 0 turns gating off)."""
    f = scenario.filters
    return {
        "gate_probability": f.gate_probability or None,
        "divergence_epochs": f.divergence_epochs,
    }


@dataclass(frozen=True, slots=True)
class _FiltersTask:
    """Picklable chunk task: simulate the given runs and run every filter variant on them."""

    scenario: FlockScenario
    variants: tuple[FilterVariant, ...]
    block: int
    example_every: int

    def __call__(self, run_indices: np.ndarray) -> FilterRunMetrics:
        sc = self.scenario
        r = len(run_indices)
        sim = simulate_scenario(sc, run_indices)
        times, nodes, model, z = sim.times_s, sim.nodes_m, sim.sensor_model, sim.measurements
        n = sc.filters.initial_state.size  # 6, or 4 for the constant-velocity model
        truth = np.broadcast_to(sim.truth[..., :n], (r, *sim.truth.shape[-2:-1], n))
        out = FilterRunMetrics(
            sse={}, nees_sum={}, seconds={}, sq_err_sum={}, example={}, gated={}, diverged_epoch={}
        )
        for v in self.variants:
            motion = sc.filters.motion_model(v.motion, sc.dt_s)
            state = Gaussian.from_single(sc.filters.initial_state, sc.filters.initial_cov, r)
            sse = np.zeros((r, state.dim))
            per_epoch = np.zeros((times.size, state.dim))
            nees = np.zeros(r)
            keep = []
            gated = np.zeros(r, dtype=np.int64)
            diverged = np.full(r, -1, dtype=np.int64)
            streak = np.zeros(r, dtype=np.int64)
            start = time.perf_counter()
            for k0 in range(0, times.size, self.block):
                sl = slice(k0, min(k0 + self.block, times.size))
                res = run_filter(
                    v.filter,
                    state,
                    motion,
                    model,
                    z[:, sl],
                    nodes[sl],
                    params=_sigma_params(sc),
                    initial_streak=streak,
                    **_gate_settings(sc),
                )
                state, streak = res.final, res.streak
                gated += res.gated_count
                diverged = np.where((diverged < 0) & res.diverged, res.diverged_epoch + k0, diverged)
                err = truth[:, sl] - res.estimates
                sse += np.sum(err**2, axis=1)
                per_epoch[sl] += np.sum(err**2, axis=0)
                assert res.covariances is not None
                nees += np.sum(
                    err[..., None, :] @ np.linalg.solve(res.covariances, err[..., None]), axis=(1, 2, 3)
                )
                if run_indices[0] == 0:
                    first = (np.arange(sl.start, sl.stop) + 1) % self.example_every == 0
                    keep.append(res.estimates[0, first])
            out.seconds[v.key] = np.full(r, (time.perf_counter() - start) / r)
            out.sse[v.key] = sse
            out.sq_err_sum[v.key] = per_epoch[None]
            out.nees_sum[v.key] = nees
            out.example[v.key] = np.concatenate(keep) if keep else np.zeros((0, state.dim))
            out.gated[v.key] = gated
            out.diverged_epoch[v.key] = diverged
        return out


@dataclass(frozen=True, slots=True, kw_only=True)
class VariantStats:
    """Monte Carlo statistics of one filter variant.

    Attributes
    ----------
    variant : FilterVariant
    mse_per_run : (R, n) float
        Time-averaged squared error per run and state component (m^2, (m/s)^2, (m/s^2)^2).
    rmse_time : (T, n) float
        Root mean square error over runs at each epoch.
    nees_per_run : (R,) float
        NEES averaged over epochs, per run (the state dimension for a consistent filter).
    step_time_s : float
        Wall time of one predict + update step per track (vectorized over a chunk's runs), seconds.
    rmse_over_sqrt_pcrlb : float
        Position RMSE over all runs and epochs / sqrt(time-averaged position PCRLB trace).
    example_estimates : (T_dec, n) float
        Run 0's estimates at the decimated epochs.
    gated_per_run : (R,) int
        Epochs rejected by the NIS gate, per run.
    diverged_epoch : (R,) int
        First epoch (0-based) of each run's divergence, ``-1`` if none.
    """

    variant: FilterVariant
    mse_per_run: FloatArray
    rmse_time: FloatArray
    nees_per_run: FloatArray
    step_time_s: float
    rmse_over_sqrt_pcrlb: float
    example_estimates: FloatArray
    gated_per_run: FloatArray
    diverged_epoch: FloatArray

    @property
    def diverged_runs(self) -> int:
        """Runs flagged as diverged."""
        return int(np.sum(self.diverged_epoch >= 0))

    @property
    def mse_mean(self) -> FloatArray:
        return self.mse_per_run.mean(axis=0)

    @property
    def mse_sd(self) -> FloatArray:
        runs = self.mse_per_run.shape[0]
        return self.mse_per_run.std(axis=0, ddof=1) if runs > 1 else np.zeros(self.mse_per_run.shape[1])

    @property
    def nees_mean(self) -> float:
        return float(self.nees_per_run.mean())

    @property
    def position_mse_m2(self) -> float:
        """Mean over runs of the time-averaged ``x`` plus ``y`` squared error, m^2."""
        return float(self.mse_mean[0] + self.mse_mean[1])


@dataclass(frozen=True, slots=True, kw_only=True)
class FilterMonteCarlo:
    """Filter variants tracking one deterministic target over ``runs`` noise realizations.

    Attributes
    ----------
    scenario : FlockScenario
    runs : int
    seed : int
    variants : dict[str, VariantStats]
        By variant key (``ekf``, ``ukf``, ``ekf-control``, ``ukf-control``).
    times_s : (T,) float
    truth : (T, n) float
        The true state (the same in every run).
    nodes_m : (T, N, 2) float
    example_times_s : (T_dec,) float
        Epochs of the example estimates (every 0.1 s).
    pcrlb_position_m2 : (T,) float
        Trace of the position block of the PCRLB.
    """

    scenario: FlockScenario
    runs: int
    seed: int
    variants: dict[str, VariantStats]
    times_s: FloatArray
    truth: FloatArray
    nodes_m: FloatArray
    example_times_s: FloatArray
    pcrlb_position_m2: FloatArray

    def paired_difference(self, a: str, b: str) -> tuple[FloatArray, FloatArray]:
        """Mean and standard error of the per-run MSE difference ``a - b`` (the same noise in both)."""
        d = self.variants[a].mse_per_run - self.variants[b].mse_per_run
        se = d.std(axis=0, ddof=1) / np.sqrt(d.shape[0]) if d.shape[0] > 1 else np.full(d.shape[1], np.nan)
        return d.mean(axis=0), se

    def paired_position_difference(self, a: str, b: str) -> tuple[float, float]:
        """Mean and standard error of the per-run position MSE difference ``a - b``, m^2."""
        d = self.variants[a].mse_per_run[:, :2].sum(axis=1) - self.variants[b].mse_per_run[:, :2].sum(axis=1)
        se = float(d.std(ddof=1) / np.sqrt(d.size)) if d.size > 1 else float("nan")
        return float(d.mean()), se

    def to_record(self) -> dict[str, Any]:
        """Per-variant means and spreads over runs (units in the key names)."""
        n = self.truth.shape[-1]
        filters = {}
        for key, v in self.variants.items():
            entry: dict[str, Any] = {"label": v.variant.label, "filter": v.variant.filter}
            entry["motion"] = v.variant.motion
            for i in range(n):
                unit = ("m2", "m2", "m2s2", "m2s2", "m2s4", "m2s4")[i]
                entry[f"mse_{STATE_NAMES[i]}_{unit}"] = float(v.mse_mean[i])
                entry[f"mse_{STATE_NAMES[i]}_sd_{unit}"] = float(v.mse_sd[i])
            entry["position_mse_m2"] = v.position_mse_m2
            entry["nees_mean"] = v.nees_mean
            entry["nees_dof"] = n
            entry["rmse_over_sqrt_pcrlb"] = float(v.rmse_over_sqrt_pcrlb)
            entry["step_time_s"] = float(v.step_time_s)
            entry["gated_epochs_mean"] = float(np.mean(v.gated_per_run))
            entry["gated_fraction"] = float(np.mean(v.gated_per_run) / self.times_s.size)
            entry["diverged_runs"] = v.diverged_runs
            div = v.diverged_epoch[v.diverged_epoch >= 0]
            entry["first_divergence_s"] = float(self.times_s[div.min()]) if div.size else None
            filters[key] = entry
        return {
            "scenario": self.scenario.name,
            "measurement": self.scenario.kind,
            "runs": self.runs,
            "seed": self.seed,
            "epochs": int(self.times_s.size),
            "dt_s": self.scenario.dt_s,
            "gate_probability": self.scenario.filters.gate_probability,
            "divergence_epochs": self.scenario.filters.divergence_epochs,
            "filters": filters,
        }

    def _divergence_times(self, epochs: FloatArray) -> FloatArray:
        idx = np.asarray(epochs, dtype=np.int64)
        return np.where(idx >= 0, self.times_s[np.maximum(idx, 0)], np.nan)

    def to_dataset(self) -> xr.Dataset:
        """The Monte Carlo as a Dataset: per-run MSE ``(filter, run, state)``, RMSE and run 0's estimate
        ``(filter, epoch, state)`` at the decimated epochs, the truth and the PCRLB ``(epoch)``."""
        import xarray as xr

        keys = list(self.variants)
        n = self.truth.shape[-1]
        idx = np.searchsorted(self.times_s, self.example_times_s)
        mse = np.stack([self.variants[k].mse_per_run for k in keys])
        rmse = np.stack([self.variants[k].rmse_time[idx] for k in keys])
        est = np.stack([self.variants[k].example_estimates for k in keys])
        units = _state_units(n)
        return xr.Dataset(
            {
                "mse": (
                    ("filter", "run", "state"),
                    mse,
                    {
                        "long_name": "time-averaged squared error per run",
                        "units": "1",
                        "comment": f"squares of the state units ({units})",
                    },
                ),
                "rmse": (
                    ("filter", "epoch", "state"),
                    rmse,
                    {
                        "long_name": "root mean square error over runs",
                        "units": "1",
                        "comment": f"in the state units ({units})",
                    },
                ),
                "estimate_run0": (
                    ("filter", "epoch", "state"),
                    est,
                    {"long_name": "estimated state of run 0", "units": "1", "comment": units},
                ),
                "truth": (
                    ("epoch", "state"),
                    self.truth[idx],
                    {"long_name": "true state", "units": "1", "comment": units},
                ),
                "pcrlb_position": (
                    ("epoch",),
                    self.pcrlb_position_m2[idx],
                    {"long_name": "trace of the position block of the PCRLB", "units": "m2"},
                ),
                "nees": (
                    ("filter", "run"),
                    np.stack([self.variants[k].nees_per_run for k in keys]),
                    {"long_name": "normalized estimation error squared, mean over epochs", "units": "1"},
                ),
                "step_time": (
                    ("filter",),
                    np.array([self.variants[k].step_time_s for k in keys]),
                    {"long_name": "wall time of one filter step per track", "units": "s"},
                ),
                "rmse_over_sqrt_pcrlb": (
                    ("filter",),
                    np.array([self.variants[k].rmse_over_sqrt_pcrlb for k in keys]),
                    {"long_name": "position RMSE over the square root of the mean PCRLB", "units": "1"},
                ),
                "gated_epochs": (
                    ("filter", "run"),
                    np.stack([self.variants[k].gated_per_run for k in keys]),
                    {"long_name": "epochs rejected by the NIS gate", "units": "1"},
                ),
                "diverged": (
                    ("filter", "run"),
                    np.stack([self.variants[k].diverged_epoch >= 0 for k in keys]).astype(np.int8),
                    {"long_name": "run flagged as diverged (1) or not (0)", "units": "1"},
                ),
                "divergence_time": (
                    ("filter", "run"),
                    np.stack([self._divergence_times(self.variants[k].diverged_epoch) for k in keys]),
                    {"long_name": "time of the first epoch of the divergence (NaN: none)", "units": "s"},
                ),
            },
            coords={
                "filter": ("filter", keys, {"long_name": "filter variant"}),
                "filter_label": ("filter", [self.variants[k].variant.label for k in keys]),
                "run": ("run", np.arange(self.runs), {"long_name": "Monte Carlo run", "units": "1"}),
                "epoch": ("epoch", self.example_times_s, {"long_name": "time since start", "units": "s"}),
                "state": ("state", list(STATE_NAMES[:n]), {"long_name": "state component"}),
            },
            attrs={
                "title": f"Flock filter Monte Carlo, {self.scenario.name} ({self.scenario.kind})",
                "measurement": self.scenario.kind,
                "runs": self.runs,
            },
        )


def position_pcrlb(
    scenario: FlockScenario, times_s: FloatArray, nodes_m: FloatArray, truth: FloatArray
) -> FloatArray:
    """Trace of the position block of the PCRLB at every epoch, ``(T,)`` m^2 (deterministic truth).

    Tichavsky recursion with the scenario's prior and ``Q``, the constant-velocity transition of the
    listing (which matches the truth's kinematics) and the true measurement noise.
    """
    f = scenario.filters
    model = scenario_sensor_model(scenario)
    true_noise = scenario.sigma_true**2 * np.eye(model.dim)
    info = measurement_information(model.jacobian(truth, nodes_m), true_noise)
    motion = f.motion_model("listing" if f.initial_state.size == 6 else "constant-velocity", scenario.dt_s)
    bound = pcrlb(f.initial_cov, motion.transition, motion.process_noise, info)
    return bound[:, 0, 0] + bound[:, 1, 1]


def _default_chunk_size(runs: int, executor: Executor | None) -> int:
    # Large chunks vectorize better; two per worker still balance the load and show progress.
    workers = getattr(executor, "_max_workers", None) or getattr(executor, "oceanloc_workers", None) or 1
    return max(1, -(-runs // (2 * int(workers))))


def filter_monte_carlo(
    scenario: FlockScenario,
    variants: tuple[FilterVariant, ...] | None = None,
    *,
    executor: Executor | None = None,
    chunk_size: int | None = None,
    progress: Callable[[int], None] | None = None,
) -> FilterMonteCarlo:
    """Run every filter variant on ``scenario.runs`` noise realizations of the scenario's straight track.

    Parameters
    ----------
    scenario : FlockScenario
        Its target must move straight (a deterministic truth, needed for the PCRLB and the paired runs).
    variants : tuple of FilterVariant, optional
        Default: :func:`filter_variants` with controls.
    executor, chunk_size, progress
        See :func:`oceanloc.evaluation.montecarlo.run_chunked` (``progress`` counts runs).
    """
    sc = scenario
    if sc.target.motion != "straight":
        raise ConfigError(f"{sc.name}: the filter Monte Carlo needs a straight (deterministic) target")
    variants = filter_variants(sc) if variants is None else variants
    times = epoch_times(sc.dt_s, sc.duration_s)
    every = max(1, round(0.1 / sc.dt_s))  # keep run 0's estimates every 0.1 s for the figures
    task = _FiltersTask(scenario=sc, variants=variants, block=2000, example_every=every)
    size = chunk_size or _default_chunk_size(sc.runs, executor)
    check_memory(sc, min(size, sc.runs))
    parts = run_chunked(task, sc.runs, executor=executor, chunk_size=size, progress=progress)
    joined = concat_runs(parts, keep=("example",))
    nodes = scenario_nodes(sc, times)
    truth = scenario_truth(sc, times, np.random.default_rng(0), 1)[..., : sc.filters.initial_state.size]
    bound_pos = position_pcrlb(sc, times, nodes, truth)
    n_epochs = times.size
    stats = {}
    for v in variants:
        sse = joined.sse[v.key]
        mse_pos = float(np.sum(sse[:, :2]) / (sc.runs * n_epochs))
        stats[v.key] = VariantStats(
            variant=v,
            mse_per_run=sse / n_epochs,
            rmse_time=np.sqrt(joined.sq_err_sum[v.key].sum(axis=0) / sc.runs),
            nees_per_run=joined.nees_sum[v.key] / n_epochs,
            step_time_s=float(joined.seconds[v.key].sum() / (sc.runs * n_epochs)),
            rmse_over_sqrt_pcrlb=float(np.sqrt(mse_pos / np.mean(bound_pos))),
            example_estimates=joined.example[v.key],
            gated_per_run=joined.gated[v.key],
            diverged_epoch=joined.diverged_epoch[v.key],
        )
    return FilterMonteCarlo(
        scenario=sc,
        runs=sc.runs,
        seed=sc.seed,
        variants=stats,
        times_s=times,
        truth=truth,
        nodes_m=nodes,
        example_times_s=times[every - 1 :: every],
        pcrlb_position_m2=bound_pos,
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class TrackingRunMetrics:
    """What a chunk of UKF tracking runs sends back (joined by ``concat_runs``; run 0's series kept)."""

    mse_xy: FloatArray  # (r, 2)
    pearson: FloatArray  # (r,)
    spearman: FloatArray  # (r,)
    mean_abs_noise_s: FloatArray  # (r,)
    nis_ratio: FloatArray  # (r,) mean NIS / dof
    residual_m: FloatArray  # (r, T_dec)
    hdop_m: FloatArray  # (r, T_dec)
    truth: FloatArray  # run 0 (first chunk), (T_dec, 6)
    estimates: FloatArray  # run 0, (T_dec, 6)
    clean: FloatArray  # run 0, (T_dec, m)
    measured: FloatArray  # run 0, (T_dec, m)
    gated: FloatArray  # (r,) epochs rejected by the NIS gate
    diverged_epoch: FloatArray  # (r,) first epoch of the divergence, -1 if none


@dataclass(frozen=True, slots=True)
class _TrackingTask:
    scenario: FlockScenario
    every: int
    settle_s: float

    def __call__(self, run_indices: np.ndarray) -> TrackingRunMetrics:
        import scipy.stats

        sc = self.scenario
        r = len(run_indices)
        sim = simulate_scenario(sc, run_indices)
        times, nodes, model = sim.times_s, sim.nodes_m, sim.sensor_model
        n = sc.filters.initial_state.size  # 6, or 4 for the constant-velocity model
        truth = np.broadcast_to(sim.truth[..., :n], (r, *sim.truth.shape[-2:-1], n))
        clean = np.broadcast_to(sim.clean, (r, *sim.clean.shape[-2:]))
        z = sim.measurements
        f = sc.filters
        motion = f.motion_model(f.ukf_motion, sc.dt_s)
        init = Gaussian.from_single(f.initial_state, f.initial_cov, r)
        res = run_filter(
            "ukf",
            init,
            motion,
            model,
            z,
            nodes,
            params=_sigma_params(sc),
            record_covariances=False,
            **_gate_settings(sc),
        )
        err = truth[..., :2] - res.estimates[..., :2]
        residual = np.linalg.norm(err, axis=-1)
        settled = times >= self.settle_s
        pearson = [np.corrcoef(residual[i, settled], res.hdop_m[i, settled])[0, 1] for i in range(r)]
        spearman = [
            scipy.stats.spearmanr(residual[i, settled], res.hdop_m[i, settled]).statistic for i in range(r)
        ]
        keep = slice(self.every - 1, None, self.every)
        with np.errstate(invalid="ignore"):
            abs_noise = np.nanmean(np.abs(z - clean), axis=(1, 2))
        return TrackingRunMetrics(
            mse_xy=np.mean(err**2, axis=1),
            pearson=np.array(pearson),
            spearman=np.array(spearman),
            mean_abs_noise_s=abs_noise,
            nis_ratio=res.nis.sum(axis=1) / res.nis_dof.sum(axis=1),
            residual_m=residual[:, keep],
            hdop_m=res.hdop_m[:, keep],
            truth=truth[0, keep],
            estimates=res.estimates[0, keep],
            clean=clean[0, keep],
            measured=z[0, keep],
            gated=res.gated_count,
            diverged_epoch=res.diverged_epoch,
        )


@dataclass(frozen=True, slots=True, kw_only=True)
class TrackingHdopMonteCarlo:
    """Monte Carlo of UKF tracking on random target paths: errors, NIS and residual vs HDOP.

    Attributes
    ----------
    scenario : FlockScenario
    runs, seed : int
    settle_s : float
        Correlations use the epochs from this time on (after the filter's convergence).
    mse_xy_m2 : (R, 2) float
        Position mean square error per run (x, y).
    pearson, spearman : (R,) float
        Correlation over time of the position residual with HDOP, per run (after ``settle_s``).
    mean_abs_noise : (R,) float
        Mean magnitude of the injected measurement noise (s for TDOA, rad, m).
    nis_ratio : (R,) float
        Mean NIS over its degrees of freedom (1 for a consistent filter).
    times_s : (T_dec,) float
        Decimated epochs of the time series below (every 0.05 s).
    residual_m, hdop_m : (R, T_dec) float
    nodes_m : (N, 2) float
        The nodes at the first epoch.
    truth, estimates : (T_dec, n) float
        Run 0.
    clean, measured : (T_dec, m) float
        Run 0's measurements before and after the noise.
    gated : (R,) int
        Epochs rejected by the UKF's NIS gate, per run.
    diverged_epoch : (R,) int
        First epoch (0-based, of the full time axis) of each run's divergence, ``-1`` if none.
    """

    scenario: FlockScenario
    runs: int
    seed: int
    settle_s: float
    mse_xy_m2: FloatArray
    pearson: FloatArray
    spearman: FloatArray
    mean_abs_noise: FloatArray
    nis_ratio: FloatArray
    times_s: FloatArray
    residual_m: FloatArray
    hdop_m: FloatArray
    nodes_m: FloatArray
    truth: FloatArray
    estimates: FloatArray
    clean: FloatArray
    measured: FloatArray
    gated: FloatArray
    diverged_epoch: FloatArray

    @property
    def noise_unit(self) -> str:
        return {"tdoa": "s", "bearing": "rad", "range": "m"}[self.scenario.kind]

    def to_record(self) -> dict[str, Any]:
        """Mean, standard deviation and median over runs of every per-run statistic."""

        def stat(x: FloatArray) -> dict[str, float]:
            sd = float(np.std(x, ddof=1)) if x.size > 1 else 0.0
            return {"mean": float(np.mean(x)), "sd": sd, "median": float(np.median(x))}

        return {
            "scenario": self.scenario.name,
            "measurement": self.scenario.kind,
            "runs": self.runs,
            "seed": self.seed,
            "settle_s": self.settle_s,
            "mse_x_m2": stat(self.mse_xy_m2[:, 0]),
            "mse_y_m2": stat(self.mse_xy_m2[:, 1]),
            "residual_hdop_pearson": stat(self.pearson),
            "residual_hdop_spearman": stat(self.spearman),
            f"mean_abs_noise_{self.noise_unit}": stat(self.mean_abs_noise),
            "nis_over_dof": stat(self.nis_ratio),
            "gate_probability": self.scenario.filters.gate_probability,
            "gated_epochs": stat(self.gated.astype(float)),
            "diverged_runs": int(np.sum(self.diverged_epoch >= 0)),
            "diverged_run_indices": [int(i) for i in np.flatnonzero(self.diverged_epoch >= 0)],
        }

    def to_dataset(self) -> xr.Dataset:
        """Per-run statistics ``(run)``, residual and HDOP ``(run, epoch)``, run 0's track
        ``(epoch, state)``."""
        import xarray as xr

        n = self.truth.shape[-1]
        unit = self.noise_unit
        return xr.Dataset(
            {
                "mse_x": (
                    ("run",),
                    self.mse_xy_m2[:, 0],
                    {"long_name": "x mean square error", "units": "m2"},
                ),
                "mse_y": (
                    ("run",),
                    self.mse_xy_m2[:, 1],
                    {"long_name": "y mean square error", "units": "m2"},
                ),
                "pearson": (
                    ("run",),
                    self.pearson,
                    {"long_name": "Pearson corr(residual, HDOP)", "units": "1"},
                ),
                "spearman": (
                    ("run",),
                    self.spearman,
                    {"long_name": "Spearman corr(residual, HDOP)", "units": "1"},
                ),
                "mean_abs_noise": (
                    ("run",),
                    self.mean_abs_noise,
                    {"long_name": "mean |injected noise|", "units": unit},
                ),
                "nis_ratio": (("run",), self.nis_ratio, {"long_name": "mean NIS over dof", "units": "1"}),
                "gated_epochs": (
                    ("run",),
                    self.gated,
                    {"long_name": "epochs rejected by the NIS gate", "units": "1"},
                ),
                "diverged": (
                    ("run",),
                    (self.diverged_epoch >= 0).astype(np.int8),
                    {"long_name": "run flagged as diverged (1) or not (0)", "units": "1"},
                ),
                "residual": (
                    ("run", "epoch"),
                    self.residual_m,
                    {"long_name": "position residual", "units": "m"},
                ),
                "hdop": (("run", "epoch"), self.hdop_m, {"long_name": "HDOP of the geometry", "units": "m"}),
                "truth_run0": (
                    ("epoch", "state"),
                    self.truth,
                    {"long_name": "true state of run 0", "units": "1", "comment": _state_units(n)},
                ),
                "estimate_run0": (
                    ("epoch", "state"),
                    self.estimates,
                    {"long_name": "UKF estimate of run 0", "units": "1", "comment": _state_units(n)},
                ),
                "node_x": (("node",), self.nodes_m[:, 0], {"long_name": "node east", "units": "m"}),
                "node_y": (("node",), self.nodes_m[:, 1], {"long_name": "node north", "units": "m"}),
            },
            coords={
                "run": ("run", np.arange(self.runs), {"long_name": "Monte Carlo run", "units": "1"}),
                "epoch": ("epoch", self.times_s, {"long_name": "time since start", "units": "s"}),
                "state": ("state", list(STATE_NAMES[:n]), {"long_name": "state component"}),
            },
            attrs={
                "title": f"UKF tracking Monte Carlo, {self.scenario.name} ({self.scenario.kind})",
                "measurement": self.scenario.kind,
                "settle_s": self.settle_s,
            },
        )


def tracking_hdop_monte_carlo(
    scenario: FlockScenario,
    *,
    settle_s: float = 2.0,
    executor: Executor | None = None,
    chunk_size: int | None = None,
    progress: Callable[[int], None] | None = None,
) -> TrackingHdopMonteCarlo:
    """Run the UKF on ``scenario.runs`` random target paths (and noise) and correlate residual with HDOP.

    Parameters
    ----------
    scenario : FlockScenario
    settle_s : float
        Convergence time excluded from the correlations, seconds; the duration must exceed it by ten steps.
    executor, chunk_size, progress
        See :func:`oceanloc.evaluation.montecarlo.run_chunked` (``progress`` counts runs).
    """
    sc = scenario
    if sc.duration_s <= settle_s + 10 * sc.dt_s:
        raise ConfigError(f"{sc.name}: duration must exceed the {settle_s} s convergence time")
    every = max(1, round(0.05 / sc.dt_s))
    task = _TrackingTask(scenario=sc, every=every, settle_s=settle_s)
    check_memory(sc, min(chunk_size or sc.runs, sc.runs))
    parts = run_chunked(task, sc.runs, executor=executor, chunk_size=chunk_size, progress=progress)
    joined = concat_runs(parts, keep=("truth", "estimates", "clean", "measured"))
    times = epoch_times(sc.dt_s, sc.duration_s)
    return TrackingHdopMonteCarlo(
        scenario=sc,
        runs=sc.runs,
        seed=sc.seed,
        settle_s=settle_s,
        mse_xy_m2=joined.mse_xy,
        pearson=joined.pearson,
        spearman=joined.spearman,
        mean_abs_noise=joined.mean_abs_noise_s,
        nis_ratio=joined.nis_ratio,
        times_s=times[every - 1 :: every],
        residual_m=joined.residual_m,
        hdop_m=joined.hdop_m,
        nodes_m=scenario_nodes(sc, times[:1])[0],
        truth=joined.truth,
        estimates=joined.estimates,
        clean=joined.clean,
        measured=joined.measured,
        gated=joined.gated,
        diverged_epoch=joined.diverged_epoch,
    )
