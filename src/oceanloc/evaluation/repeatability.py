"""Repeatability of repeated surveys of one transponder: the spread of their positions across surveys
and whether the surveys' own covariances explain it (a chi-square test per axis).

Nobody knows a seafloor transponder's true position; surveys of the same transponder are the check. A
good estimator gives positions that agree from survey to survey, with covariances that explain the spread.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from oceanloc._typing import BoolArray, FloatArray
from oceanloc.errors import ConfigError
from oceanloc.estimation.gnssa import GnssaResult


@dataclass(frozen=True, slots=True, kw_only=True)
class SurveySpread:
    """Agreement of repeated surveys of one transponder.

    Attributes
    ----------
    std_enu_m : (3,) float
        Sample standard deviation (ddof=1) of the positions across surveys, metres.
    rms_sigma_enu_m : (3,) float
        RMS of the surveys' reported 1-sigma, metres: what the sigmas predict for that spread.
    chi2_enu : (3,) float
        ``sum_i (x_i - mean)^2 / sigma_i^2`` per axis, chi-square with ``m - 1`` degrees of freedom if
        the sigmas are right.
    chi2_bounds : (2,) float
        Central 95% interval of that chi-square.
    n_surveys : int
    """

    std_enu_m: FloatArray
    rms_sigma_enu_m: FloatArray
    chi2_enu: FloatArray
    chi2_bounds: FloatArray
    n_surveys: int

    @property
    def sigmas_explain_spread(self) -> BoolArray:
        """Per axis: the chi-square lies inside its 95% interval."""
        return (self.chi2_enu >= self.chi2_bounds[0]) & (self.chi2_enu <= self.chi2_bounds[1])


def survey_spread(results: list[GnssaResult]) -> SurveySpread:
    """Spread across surveys and whether the reported sigmas explain it (needs two or more surveys)."""
    from scipy.stats import chi2  # imported on use: the command line starts without scipy

    if len(results) < 2:
        raise ConfigError("the spread across surveys needs at least two surveys")
    pos = np.array([r.position_enu_m for r in results])
    sig = np.array([r.sigma_enu_m for r in results])
    dev = pos - pos.mean(axis=0)
    dof = len(results) - 1
    return SurveySpread(
        std_enu_m=pos.std(axis=0, ddof=1),
        rms_sigma_enu_m=np.sqrt(np.mean(sig * sig, axis=0)),
        chi2_enu=np.sum(dev * dev / (sig * sig), axis=0),
        chi2_bounds=np.array([chi2.ppf(0.025, dof), chi2.ppf(0.975, dof)]),
        n_surveys=len(results),
    )
