"""Reproduce the AquaQuad thesis' lab test of the TDOA UKF (Chapter V.C, Figures 62-67).

Three nodes hold position in a Y around a target that a person moves at random (stop and go); every
0.005 s the UKF ingests TDOA pseudo-measurements made from the true ranges with ``c = 1500 m/s`` plus white
noise. The thesis reports one run: a position mean square error of 0.21 (X) and 0.88 (Y) (printed as
"meters"; read as m^2), an injected noise of 0.0011 s mean magnitude, and residual peaks that coincide with
HDOP peaks (Figure 67). We simulate a Monte Carlo of random target paths and report the residual-HDOP
correlation over time per run (Pearson and Spearman, after the first two seconds of convergence), its
spread over runs, and the error statistics beside the thesis' values. The Monte Carlo itself is
:func:`oceanloc.evaluation.flock.tracking_hdop_monte_carlo`; this module holds the thesis' values, the
side-by-side rows and the acceptance checks.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import Executor
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.config.flock import FlockScenario, load_flock_scenario
from oceanloc.errors import ConfigError
from oceanloc.evaluation.flock import TrackingHdopMonteCarlo, tracking_hdop_monte_carlo
from oceanloc.reproduce.survey_tables import Check

__all__ = [
    "SCENARIO",
    "SETTLE_S",
    "THESIS_MEAN_ABS_NOISE_S",
    "THESIS_MSE_X_M2",
    "THESIS_MSE_Y_M2",
    "LabRow",
    "LabTdoaResult",
    "lab_checks",
    "lab_rows",
    "reproduce_dillard_lab_tdoa",
]

SCENARIO = "dillard-lab-tdoa"
THESIS_MSE_X_M2 = 0.21
THESIS_MSE_Y_M2 = 0.88
THESIS_MEAN_ABS_NOISE_S = 0.0011
SETTLE_S = 2.0
"""The thesis' filter converged within two seconds (Figure 65); correlations use the time after that."""

NOISE_TOLERANCE = 0.10
"""The simulated noise's mean magnitude matches the thesis' 1.1 ms within this fraction (it is printed with
two digits)."""


@dataclass(frozen=True, slots=True, kw_only=True)
class LabRow:
    """One quantity of the lab test: the thesis' single run beside our Monte Carlo (mean, sd, median)."""

    quantity: str
    unit: str
    mean: float
    sd: float
    median: float
    thesis: str | None = None


@dataclass(frozen=True, slots=True, kw_only=True)
class LabTdoaResult:
    """The reproduction: the Monte Carlo, the side-by-side rows and the acceptance checks."""

    monte_carlo: TrackingHdopMonteCarlo
    is_thesis: bool
    rows: tuple[LabRow, ...]
    checks: tuple[Check, ...]

    @property
    def runs(self) -> int:
        return self.monte_carlo.runs

    def to_record(self) -> dict[str, Any]:
        """The Monte Carlo's record, the thesis' values (for the thesis' scenario) and the checks."""
        record = self.monte_carlo.to_record()
        record["thesis_applies"] = self.is_thesis
        if self.is_thesis:
            record["thesis_mse_x_m2"] = THESIS_MSE_X_M2
            record["thesis_mse_y_m2"] = THESIS_MSE_Y_M2
            record["thesis_mean_abs_noise_s"] = THESIS_MEAN_ABS_NOISE_S
        record["checks"] = [asdict(c) for c in self.checks]
        return record


def _row(quantity: str, unit: str, values: FloatArray, thesis: str | None, scale: float = 1.0) -> LabRow:
    sd = float(np.std(values, ddof=1)) if values.size > 1 else 0.0
    return LabRow(
        quantity=quantity,
        unit=unit,
        mean=float(np.mean(values)) * scale,
        sd=sd * scale,
        median=float(np.median(values)) * scale,
        thesis=thesis,
    )


def lab_rows(mc: TrackingHdopMonteCarlo, is_thesis: bool) -> tuple[LabRow, ...]:
    """Position MSE, injected noise, residual-HDOP correlations and NIS, the thesis' values beside."""

    def t(text: str) -> str | None:
        return text if is_thesis else None

    noise_scale, noise_unit = (1e3, "ms") if mc.noise_unit == "s" else (1.0, mc.noise_unit)
    return (
        _row("position MSE X", "m²", mc.mse_xy_m2[:, 0], t(f"{THESIS_MSE_X_M2}")),
        _row("position MSE Y", "m²", mc.mse_xy_m2[:, 1], t(f"{THESIS_MSE_Y_M2}")),
        _row(
            "mean |injected noise|",
            noise_unit,
            mc.mean_abs_noise,
            t(f"{THESIS_MEAN_ABS_NOISE_S * 1e3:.1f}"),
            noise_scale,
        ),
        _row("corr(residual, HDOP), Pearson", "1", mc.pearson, t("peaks coincide (Fig. 67)")),
        _row("corr(residual, HDOP), Spearman", "1", mc.spearman, t("-")),
        _row("NIS / dof", "1", mc.nis_ratio, t("- (R is half the noise)")),
    )


def lab_checks(mc: TrackingHdopMonteCarlo, is_thesis: bool) -> tuple[Check, ...]:
    """The simulated noise is the thesis' (thesis scenario); the residual rises with HDOP (mean Pearson
    correlation over runs above zero by two standard errors; with one run, above zero)."""
    checks = []
    if is_thesis:
        noise = float(np.mean(mc.mean_abs_noise))
        checks.append(
            Check(
                name=f"mean |TDOA noise| within {100 * NOISE_TOLERANCE:.0f} % of the thesis' 1.1 ms",
                passed=bool(abs(noise / THESIS_MEAN_ABS_NOISE_S - 1) <= NOISE_TOLERANCE),
                detail=f"{noise * 1e3:.3f} ms",
            )
        )
    r = mc.pearson
    se = float(np.std(r, ddof=1) / np.sqrt(r.size)) if r.size > 1 else 0.0
    checks.append(
        Check(
            name="position residual correlates positively with HDOP (Pearson, mean > 2 SE)",
            passed=bool(np.mean(r) > 2 * se),
            detail=f"{np.mean(r):.3f} ± {se:.3f} over {r.size} run(s)",
        )
    )
    return tuple(checks)


def reproduce_dillard_lab_tdoa(
    scenario: FlockScenario | str = SCENARIO,
    *,
    runs: int | None = None,
    seed: int | None = None,
    executor: Executor | None = None,
    chunk_size: int | None = None,
    progress: Callable[[int], None] | None = None,
) -> LabTdoaResult:
    """Run the lab TDOA Monte Carlo (random target paths and noise per run) and compare with the thesis."""
    sc = load_flock_scenario(scenario) if isinstance(scenario, str) else scenario
    if runs is not None:
        sc = sc.with_overrides(runs=runs)
    if seed is not None:
        sc = sc.with_overrides(seed=seed)
    if sc.kind != "tdoa":
        raise ConfigError(f"{sc.name}: the lab reproduction needs TDOA measurements, got {sc.kind}")
    mc = tracking_hdop_monte_carlo(
        sc, settle_s=SETTLE_S, executor=executor, chunk_size=chunk_size, progress=progress
    )
    is_thesis = sc.name == SCENARIO
    return LabTdoaResult(
        monte_carlo=mc, is_thesis=is_thesis, rows=lab_rows(mc, is_thesis), checks=lab_checks(mc, is_thesis)
    )
