"""GNSS-A surveys of one site processed together: read each file, solve each, choose the site velocity
from the survey's location, and compare the positions at one epoch (:mod:`.repeatability`).

The site velocity (``--site-velocity``) is one of

* ``auto``: the plate the site lies on (:func:`oceanloc.geo.plate_motion.plate_at`, from the files' header
  latitude and longitude ``Lat0``, ``Lon0``) moved by the ITRF2014 plate-motion model; a site on no plate
  the model knows, or files without that header, are compared as surveyed, and the choice says why;
* a plate code of the model (``PCFC``, ``NOAM``);
* ``VE,VN[,VU]`` in mm/yr (a velocity the user knows, e.g. from a nearby GNSS station);
* ``none``: positions compared as surveyed.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from oceanloc.errors import ConfigError
from oceanloc.estimation.gnssa import GnssaOptions, GnssaResult, localize_gnssa
from oceanloc.estimation.gnssa_array import (
    ArrayGeometry,
    GnssaArrayOptions,
    GnssaArrayResult,
    localize_gnssa_array,
)
from oceanloc.field.repeatability import SurveySpread, survey_spread
from oceanloc.geo.plate_motion import (
    ITRF2014_POLES_MAS_YR,
    SiteVelocity,
    given_site_velocity,
    plate_at,
    plate_site_velocity,
)
from oceanloc.io.gnssa import GnssaSurvey, read_gnssa, survey_sound_speeds_mps
from oceanloc.io.gnssa_array import GnssaArraySurvey
from oceanloc.models.sound_profile import SoundSpeedProfile


@dataclass(frozen=True, slots=True, kw_only=True)
class SiteVelocityChoice:
    """The site velocity chosen for ``--site-velocity`` and why.

    Attributes
    ----------
    spec : str
        What was asked (``auto``, ``PCFC``, ``-40,20``, ``none``).
    velocity : SiteVelocity or None
        The velocity used; None compares the positions as surveyed.
    plate : str or None
        The plate the velocity comes from, when it comes from one.
    reason : str
        One line saying how it was chosen (for tables and records).
    """

    spec: str
    velocity: SiteVelocity | None
    plate: str | None
    reason: str

    def to_record(self) -> dict:
        """Plain JSON-ready data (velocity in mm/yr, E, N, U)."""
        v = None if self.velocity is None else [float(x) for x in self.velocity.velocity_enu_mm_yr]
        return {
            "spec": self.spec,
            "plate": self.plate,
            "source": None if self.velocity is None else self.velocity.source,
            "velocity_enu_mm_yr": v,
            "reason": self.reason,
        }


def choose_site_velocity(
    spec: str, surveys: Sequence[GnssaSurvey] | Sequence[GnssaArraySurvey]
) -> SiteVelocityChoice:
    """The site velocity for ``spec`` (see the module docstring) at the surveys' location.

    Raises
    ------
    ConfigError
        If ``spec`` is none of the accepted forms, a plate velocity is asked for files without a header
        origin, or the surveys' headers put them on different plates.
    """
    text = spec.strip()
    low = text.lower()
    if low == "none":
        return SiteVelocityChoice(spec=text, velocity=None, plate=None, reason="none asked: as surveyed")
    if "," in text:
        try:
            values = tuple(float(v) for v in text.split(","))
        except ValueError:
            raise ConfigError(f"--site-velocity: {spec!r} is not 'VE,VN[,VU]' in mm/yr") from None
        return SiteVelocityChoice(
            spec=text, velocity=given_site_velocity(values), plate=None, reason="given in mm/yr"
        )
    origins = [s.origin for s in surveys if s.origin is not None]
    if low == "auto":
        if not origins:
            reason = "no file header gives Lat0/Lon0: compared as surveyed"
            return SiteVelocityChoice(spec=text, velocity=None, plate=None, reason=reason)
        plates = {plate_at(o.lat_deg, o.lon_deg) for o in origins}
        if len(plates) > 1:
            named = ", ".join(sorted(p or "none known" for p in plates))
            raise ConfigError(f"--site-velocity auto: the files' headers lie on different plates ({named})")
        plate = plates.pop()
        o = origins[0]
        where = f"header Lat0 {o.lat_deg:.4f}, Lon0 {o.lon_deg:.4f}"
        if plate is None:
            known = ", ".join(ITRF2014_POLES_MAS_YR)
            reason = f"{where} is on none of the model's plates ({known}): compared as surveyed"
            return SiteVelocityChoice(spec=text, velocity=None, plate=None, reason=reason)
        velocity = plate_site_velocity(o.lat_deg, o.lon_deg, plate)
        return SiteVelocityChoice(spec=text, velocity=velocity, plate=plate, reason=f"{where} is on {plate}")
    plate = text.upper()
    if plate not in ITRF2014_POLES_MAS_YR:
        raise ConfigError(
            f"--site-velocity: {spec!r} is none of auto, none, VE,VN[,VU] (mm/yr) or a plate "
            f"({', '.join(ITRF2014_POLES_MAS_YR)})"
        )
    if not origins:
        raise ConfigError(f"--site-velocity {spec}: a plate velocity needs a file header with Lat0 and Lon0")
    o = origins[0]
    velocity = plate_site_velocity(o.lat_deg, o.lon_deg, plate)
    return SiteVelocityChoice(spec=text, velocity=velocity, plate=plate, reason=f"{plate} asked")


@dataclass(frozen=True, slots=True, kw_only=True)
class GnssaSurveys:
    """Several GNSS-A surveys of one transponder, each solved, and their agreement.

    Attributes
    ----------
    surveys : tuple of GnssaSurvey
    results : tuple of GnssaResult
        One solution per survey, in the files' order.
    site_velocity : SiteVelocityChoice
    spread : SurveySpread or None
        Agreement at one epoch, positions moved by the site velocity (None for a single survey).
    as_surveyed : SurveySpread or None
        The same without moving the positions.
    """

    surveys: tuple[GnssaSurvey, ...]
    results: tuple[GnssaResult, ...]
    site_velocity: SiteVelocityChoice
    spread: SurveySpread | None
    as_surveyed: SurveySpread | None

    @property
    def paths(self) -> list[str]:
        return [s.path for s in self.surveys]

    def pings_record(self) -> dict[str, list]:
        """Every ping of every survey: ``t_s`` (transmit time in the files' time base), ``transponder`` (the
        survey's name: one transponder per file), ``residual_m`` (two-way path at the solution),
        ``excluded`` and ``reason`` ("" for a used ping)."""
        out: dict[str, list] = {"t_s": [], "transponder": [], "residual_m": [], "excluded": [], "reason": []}
        for survey, res in zip(self.surveys, self.results, strict=True):
            reasons = [""] * survey.n_pings
            for x in res.exclusions:
                reasons[x.index] = x.reason
            out["t_s"] += [float(t) for t in survey.t_transmit_s]
            out["transponder"] += [res.name] * survey.n_pings
            out["residual_m"] += [float(r) for r in res.residual_m]
            out["excluded"] += [not bool(u) for u in res.used]
            out["reason"] += [
                r if not u and r else ("excluded" if not u else "")
                for r, u in zip(reasons, res.used, strict=True)
            ]
        return out

    def to_record(self) -> dict:
        """Plain JSON-ready data: one entry per survey, the site velocity, the spreads and every ping."""
        spread = None
        if self.spread is not None and self.as_surveyed is not None:
            spread = self.spread.to_record()
            spread["at_survey_epochs"] = self.as_surveyed.to_record()
        return {
            "surveys": [r.to_record() for r in self.results],
            "site_velocity": self.site_velocity.to_record(),
            "spread": spread,
            "pings": self.pings_record(),
        }


def process_gnssa_surveys(
    paths: Sequence[str | Path],
    options: GnssaOptions,
    *,
    sound_speeds_mps: Sequence[float] = (),
    site_velocity: str = "auto",
) -> GnssaSurveys:
    """Read and solve each GNSS-A file and compare the solutions at one epoch.

    Parameters
    ----------
    paths : sequence of path
        GNSS-A ping files (:func:`oceanloc.io.gnssa.read_gnssa`).
    options : GnssaOptions
        Solver options; the sound speed of each file replaces ``options.sound_speed_mps``.
    sound_speeds_mps : sequence of float
        One speed for all files, one per file, or none (the published speed of known files), m/s.
    site_velocity : str
        ``auto``, a plate code, ``VE,VN[,VU]`` in mm/yr or ``none`` (see the module docstring).
    """
    if not paths:
        raise ConfigError("no GNSS-A file to process")
    speeds = survey_sound_speeds_mps(paths, sound_speeds_mps)
    surveys = tuple(read_gnssa(p) for p in paths)
    choice = choose_site_velocity(site_velocity, surveys)
    results = tuple(
        localize_gnssa(s, dataclasses.replace(options, sound_speed_mps=c))
        for s, c in zip(surveys, speeds, strict=True)
    )
    spread = as_surveyed = None
    if len(results) >= 2:
        spread = survey_spread(list(results), choice.velocity)
        as_surveyed = survey_spread(list(results))
    return GnssaSurveys(
        surveys=surveys, results=results, site_velocity=choice, spread=spread, as_surveyed=as_surveyed
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class GnssaArraySurveys:
    """Several GNSS-A surveys of one transponder array, each solved, and the agreement of the array's
    centre across them (the usual GNSS-A observable: its motion is the site's).

    Attributes
    ----------
    surveys : tuple of GnssaArraySurvey
    results : tuple of GnssaArrayResult
        One solution per survey, in the order given.
    site_velocity : SiteVelocityChoice
    spread : SurveySpread or None
        Agreement of the centres at one epoch, moved by the site velocity (None for a single survey).
    as_surveyed : SurveySpread or None
        The same without moving them.
    """

    surveys: tuple[GnssaArraySurvey, ...]
    results: tuple[GnssaArrayResult, ...]
    site_velocity: SiteVelocityChoice
    spread: SurveySpread | None
    as_surveyed: SurveySpread | None

    def to_record(self) -> dict:
        """Plain JSON-ready data: one entry per survey, the site velocity and the centre's spreads."""
        spread = None
        if self.spread is not None and self.as_surveyed is not None:
            spread = self.spread.to_record()
            spread["at_survey_epochs"] = self.as_surveyed.to_record()
        return {
            "surveys": [r.to_record() for r in self.results],
            "site_velocity": self.site_velocity.to_record(),
            "centre_spread": spread,
        }


def process_gnssa_array_surveys(
    surveys: Sequence[GnssaArraySurvey],
    options: GnssaArrayOptions,
    *,
    profiles: Sequence[SoundSpeedProfile | None] = (),
    geometry: ArrayGeometry | None = None,
    site_velocity: str = "auto",
) -> GnssaArraySurveys:
    """Solve each array survey (:func:`~oceanloc.estimation.gnssa_array.localize_gnssa_array`) and compare
    the array's centre across them at one epoch (:func:`~oceanloc.field.repeatability.survey_spread`).

    Parameters
    ----------
    surveys : sequence of GnssaArraySurvey
        Surveys of one array, in the same ENU frame (the same origin).
    options : GnssaArrayOptions
    profiles : sequence of SoundSpeedProfile or None
        One profile per survey, one for all, or none.
    geometry : ArrayGeometry, optional
        The array's geometry (for the ``common_shift`` solution).
    site_velocity : str
        As in :func:`process_gnssa_surveys`.

    Raises
    ------
    ConfigError
        No survey, a profile count that is neither 0, 1 nor one per survey, or surveys whose transponders
        or origins differ.
    """
    if not surveys:
        raise ConfigError("no GNSS-A array survey to process")
    if len(profiles) not in (0, 1, len(surveys)):
        raise ConfigError(f"give one sound-speed profile, one per survey ({len(surveys)}) or none")
    ids = {s.transponder_ids for s in surveys}
    if len(ids) > 1:
        raise ConfigError("the surveys name different transponders: the array centre would not be comparable")
    origins = {s.origin for s in surveys}
    if len(origins) > 1:
        raise ConfigError("the surveys have different ENU origins: convert them to one frame first")
    per_survey = (
        list(profiles) * len(surveys) if len(profiles) == 1 else list(profiles) or [None] * len(surveys)
    )
    choice = choose_site_velocity(site_velocity, surveys)
    results = tuple(
        localize_gnssa_array(s, options, profile=p, geometry=geometry)
        for s, p in zip(surveys, per_survey, strict=True)
    )
    spread = as_surveyed = None
    if len(results) >= 2:
        centres = [r.centre for r in results]
        spread = survey_spread(list(centres), choice.velocity)
        as_surveyed = survey_spread(list(centres))
    return GnssaArraySurveys(
        surveys=tuple(surveys), results=results, site_velocity=choice, spread=spread, as_surveyed=as_surveyed
    )
