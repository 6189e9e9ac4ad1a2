"""Repeatability of repeated surveys of one transponder: the spread of their positions across surveys
and whether the surveys' own covariances explain it (a chi-square test per axis).

Nobody knows a seafloor transponder's true position; surveys of the same transponder are the check. A
good estimator gives positions that agree from survey to survey, with covariances that explain the spread.
The seafloor moves, though: surveys months apart are compared at one reference epoch, each position
moved by a secular site velocity (:mod:`oceanloc.geo.plate_motion`), ``x_i - v (t_i - t_ref)``, with the
velocity's uncertainty added to each survey's variance, ``sigma_i^2 + (sigma_v (t_i - t_ref))^2``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from oceanloc._typing import BoolArray, FloatArray
from oceanloc.errors import ConfigError
from oceanloc.geo.plate_motion import SECONDS_PER_YEAR, SiteVelocity

MIN_FIT_SPAN_S: float = 30.0 * 86400.0
"""Shortest span of survey epochs over which a velocity is fitted (a month)."""


class SurveyPosition(Protocol):
    """What the spread needs of a survey's result (:class:`~oceanloc.estimation.gnssa.GnssaResult`)."""

    @property
    def position_enu_m(self) -> FloatArray: ...

    @property
    def sigma_enu_m(self) -> FloatArray: ...

    @property
    def epoch_s(self) -> float: ...


@dataclass(frozen=True, slots=True, kw_only=True)
class SurveySpread:
    """Agreement of repeated surveys of one transponder.

    Attributes
    ----------
    positions_enu_m : (m, 3) float
        The surveys' positions at the reference epoch, metres.
    sigma_enu_m : (m, 3) float
        Their 1-sigma, the velocity's uncertainty included, metres.
    epochs_s : (m,) float
        The surveys' epochs, seconds (the results' time base).
    reference_epoch_s : float
        The epoch the positions are moved to (the mean epoch unless given).
    velocity : SiteVelocity or None
        The site velocity used (None: positions compared as surveyed).
    std_enu_m : (3,) float
        Sample standard deviation (ddof=1) of the positions across surveys, metres.
    rms_sigma_enu_m : (3,) float
        RMS of the surveys' 1-sigma, metres: what the sigmas predict for that spread.
    chi2_enu : (3,) float
        ``sum_i (x_i - mean)^2 / sigma_i^2`` per axis, chi-square with ``m - 1`` degrees of freedom if
        the sigmas are right.
    chi2_bounds : (2,) float
        Central 95% interval of that chi-square.
    fitted_velocity_enu_mps, fitted_velocity_sigma_enu_mps : (3,) float or None
        The velocity the surveys themselves imply (weighted least squares per axis on the surveyed
        positions) and its 1-sigma, m/s; None with fewer than three surveys or epochs spanning less than
        :data:`MIN_FIT_SPAN_S`.
    n_surveys : int
    """

    positions_enu_m: FloatArray
    sigma_enu_m: FloatArray
    epochs_s: FloatArray
    reference_epoch_s: float
    velocity: SiteVelocity | None
    std_enu_m: FloatArray
    rms_sigma_enu_m: FloatArray
    chi2_enu: FloatArray
    chi2_bounds: FloatArray
    fitted_velocity_enu_mps: FloatArray | None
    fitted_velocity_sigma_enu_mps: FloatArray | None
    n_surveys: int

    @property
    def sigmas_explain_spread(self) -> BoolArray:
        """Per axis: the chi-square lies inside its 95% interval."""
        return (self.chi2_enu >= self.chi2_bounds[0]) & (self.chi2_enu <= self.chi2_bounds[1])

    def to_record(self) -> dict:
        """Plain JSON-ready data: per axis (e, n, u) the spread, the RMS sigma and the chi-square test; the
        velocity used and the one the surveys imply, in mm/yr."""
        out: dict = {"n_surveys": self.n_surveys}
        for axis, j in (("e", 0), ("n", 1), ("u", 2)):
            out[f"std_{axis}_m"] = float(self.std_enu_m[j])
            out[f"rms_sigma_{axis}_m"] = float(self.rms_sigma_enu_m[j])
            out[f"chi2_{axis}"] = float(self.chi2_enu[j])
            out[f"sigmas_explain_{axis}"] = bool(self.sigmas_explain_spread[j])
        out["chi2_95_range"] = [float(v) for v in self.chi2_bounds]
        out["reference_epoch_s"] = float(self.reference_epoch_s)
        out["site_velocity"] = (
            None
            if self.velocity is None
            else {"source": self.velocity.source, **_enu(self.velocity.velocity_enu_mm_yr)}
        )
        if self.fitted_velocity_enu_mps is not None and self.fitted_velocity_sigma_enu_mps is not None:
            out["fitted_velocity"] = {
                **_mm_yr(self.fitted_velocity_enu_mps),
                **{f"sigma_{k}": v for k, v in _mm_yr(self.fitted_velocity_sigma_enu_mps).items()},
            }
        return out


def _mm_yr(v_mps: FloatArray) -> dict[str, float]:
    return _enu(np.asarray(v_mps) * 1e3 * SECONDS_PER_YEAR)


def _enu(v_mm_yr: FloatArray) -> dict[str, float]:
    return {"e_mm_yr": float(v_mm_yr[0]), "n_mm_yr": float(v_mm_yr[1]), "u_mm_yr": float(v_mm_yr[2])}


def survey_spread(
    results: list[SurveyPosition],
    velocity: SiteVelocity | None = None,
    *,
    reference_epoch_s: float | None = None,
) -> SurveySpread:
    """Spread across surveys and whether the reported sigmas explain it (needs two or more surveys).

    Parameters
    ----------
    results : list of survey results
        Each with ``position_enu_m (3,)``, ``sigma_enu_m (3,)`` and ``epoch_s``.
    velocity : SiteVelocity, optional
        Secular velocity of the transponder; None compares the positions as surveyed.
    reference_epoch_s : float, optional
        Epoch to compare at (default: the mean of the surveys' epochs; the spread does not depend on it).
    """
    from scipy.stats import chi2  # imported on use: the command line starts without scipy

    if len(results) < 2:
        raise ConfigError("the spread across surveys needs at least two surveys")
    surveyed = np.array([r.position_enu_m for r in results])
    sig_surveyed = np.array([r.sigma_enu_m for r in results])
    epochs = np.array([float(r.epoch_s) for r in results])
    t_ref = float(np.mean(epochs)) if reference_epoch_s is None else float(reference_epoch_s)
    dt = (epochs - t_ref)[:, None]
    pos, sig = surveyed, sig_surveyed
    if velocity is not None:
        pos = surveyed - velocity.velocity_enu_mps * dt
        sig = np.sqrt(sig * sig + (velocity.sigma_enu_mps * dt) ** 2)
    dev = pos - pos.mean(axis=0)
    dof = len(results) - 1
    fit, fit_sigma = _fitted_velocity(surveyed, sig_surveyed, epochs)
    return SurveySpread(
        positions_enu_m=pos,
        sigma_enu_m=sig,
        epochs_s=epochs,
        reference_epoch_s=t_ref,
        velocity=velocity,
        std_enu_m=pos.std(axis=0, ddof=1),
        rms_sigma_enu_m=np.sqrt(np.mean(sig * sig, axis=0)),
        chi2_enu=np.sum(dev * dev / (sig * sig), axis=0),
        chi2_bounds=np.array([chi2.ppf(0.025, dof), chi2.ppf(0.975, dof)]),
        fitted_velocity_enu_mps=fit,
        fitted_velocity_sigma_enu_mps=fit_sigma,
        n_surveys=len(results),
    )


def _fitted_velocity(
    pos: FloatArray, sig: FloatArray, epochs: FloatArray
) -> tuple[FloatArray | None, FloatArray | None]:
    """Weighted least-squares slope of ``pos (m, 3)`` against ``epochs (m,)`` per axis, and its 1-sigma."""
    if len(epochs) < 3 or np.ptp(epochs) < MIN_FIT_SPAN_S:
        return None, None
    w = 1.0 / (sig * sig)  # (m, 3)
    t = (epochs - epochs.mean())[:, None]
    sw, st, stt = w.sum(axis=0), (w * t).sum(axis=0), (w * t * t).sum(axis=0)
    sx, stx = (w * pos).sum(axis=0), (w * t * pos).sum(axis=0)
    det = sw * stt - st * st
    return (sw * stx - st * sx) / det, np.sqrt(sw / det)
