"""A survey's estimates kept up to date as records arrive: the live loop's estimator.

:func:`~oceanloc.field.survey.estimates.survey_estimates` recomputes everything from the journal: fine for
``survey status``, but a live loop re-estimating after every range would do work growing with the
journal. :class:`SurveyState` holds the journal's records in memory and, per appended record, does only
what the estimate needs:

* a new fix is converted to ENU once; a range is aligned (interpolated on the track, as
  :func:`~oceanloc.io.usbl.align_ranges` does, to the bit) once the fix after it has arrived. A fix that
  arrives out of time order re-aligns the ranges it brackets, and their beacon is then fitted afresh;
* only a beacon that received aligned ranges is re-estimated, warm-started from its previous estimate
  (once it has :data:`FRESH_BELOW` ranges; before, afresh as the batch does): the outlier rule
  (:func:`~oceanloc.estimation.range_logs.robust_white_fit`) keeps the exclusions made so far and tests
  the new ranges (ranges excluded earlier whose residual is now within the threshold are given back and
  the rule re-run, so the mask is the one-shot rule's fixed point); then the two generalized
  least-squares passes with the Gauss-Markov GPS error of the batch estimate
  (:func:`~oceanloc.estimation.range_logs.correlated_fit`, O(n): the first linearized at this epoch's
  white estimate, the second at the first's result, as in the batch), each by Newton steps from the
  previous epoch's result instead of a solve from afar; and the linearization check of its ellipse.

Readings (each a difference from the batch estimate far below a millimetre; tested on simulated logs
against :func:`~oceanloc.field.survey.estimates.survey_estimates` of the records held, every 400 s of an
hour: positions within 1 mm, measured about 1e-6 m, the same outliers range for range): a beacon that
got no new range keeps its estimate although the prior's surface height (the median antenna height
over all ranges) moved by a millimetre; the outlier mask is carried over instead of re-running the rule
from all ranges (the same where no residual sits on the threshold); the Newton steps stop within the
solver's tolerance of the batch solve's point.

Work per epoch: O(n_b) for the re-estimated beacon ``b`` (a few vectorized passes over its ranges),
nothing for the others; no Python loop over records.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from oceanloc._typing import ArrayLike, BoolArray, FloatArray, IntArray
from oceanloc.errors import DataError
from oceanloc.estimation.consistency import (
    LinearizationCheck,
    confidence_ellipse,
    range_linearization_check,
)
from oceanloc.estimation.map_gauss_newton import MapOptions
from oceanloc.estimation.range_logs import (
    beacon_prior,
    correlated_fit,
    robust_white_fit,
)
from oceanloc.field.survey.estimates import (
    ELLIPSE_CONFIDENCE,
    MIN_RANGES,
    RANGE_STATUS,
    SurveyEstimates,
    Waypoint,
    drop_means_enu_m,
    next_waypoint,
)
from oceanloc.field.survey.journal import Journal, JournalRecords
from oceanloc.field.survey.settings import JournalSettings
from oceanloc.geo.enu import EnuOrigin, enu_to_geodetic, geodetic_to_enu

OUTLIER_THRESHOLD = 3.0
MAX_OUTLIER_FRACTION = 0.25
"""The outlier rule of :func:`~oceanloc.estimation.range_logs.localize_beacons`'s defaults, which
:func:`~oceanloc.field.survey.estimates.survey_estimates` uses; the GPS error model is the survey's
(:attr:`JournalSettings.gps_sigma_m`, ``gps_correlation_s``)."""

FRESH_BELOW = 500
"""A beacon with fewer aligned ranges than this is fitted afresh from its prior each epoch, exactly as
the batch estimate (cheap while it has few ranges): with few ranges the problem can have several minima
(a mirror image, a flat valley) and a warm start could settle in another one than the batch's."""


class _Rows:
    """A growable float array of rows (capacity doubling); ``view`` is the filled part."""

    def __init__(self, width: int, dtype: type = np.float64) -> None:
        self._buf = np.zeros((64, width), dtype=dtype)
        self.n = 0

    @property
    def view(self) -> np.ndarray:
        return self._buf[: self.n]

    def append(self, rows: np.ndarray) -> None:
        k = rows.shape[0]
        if self.n + k > self._buf.shape[0]:
            grown = np.zeros((max(2 * self._buf.shape[0], self.n + k), self._buf.shape[1]), self._buf.dtype)
            grown[: self.n] = self._buf[: self.n]
            self._buf = grown
        self._buf[self.n : self.n + k] = rows
        self.n += k

    def replace(self, rows: np.ndarray) -> None:
        """All rows anew (a fresh buffer: views handed out earlier keep their content)."""
        self._buf = np.zeros((max(64, 2 * rows.shape[0]), rows.shape[1]), self._buf.dtype)
        self.n = 0
        self.append(rows)


@dataclass(slots=True)
class _Beacon:
    """One beacon's aligned ranges (time order) and its current fit."""

    t: _Rows = field(default_factory=lambda: _Rows(1))
    z: _Rows = field(default_factory=lambda: _Rows(1))
    sensor: _Rows = field(default_factory=lambda: _Rows(3))
    used: _Rows = field(default_factory=lambda: _Rows(1, bool))
    key: _Rows = field(default_factory=lambda: _Rows(1))
    """Journal order key of each range (its time; ties broken by beacon id, one beacon here)."""
    white_m: FloatArray | None = None
    first_pass_m: FloatArray | None = None
    position_m: FloatArray | None = None
    covariance_m2: FloatArray | None = None
    residual_rms_m: float = 0.0
    check: tuple[FloatArray, float, bool] | None = None
    dirty: bool = False
    fresh: bool = True  # fit from scratch (first fit, or old ranges re-aligned)

    @property
    def n(self) -> int:
        return self.t.n


class SurveyState:
    """The records of a survey in memory and their current estimates, updated per appended record.

    Parameters
    ----------
    settings : JournalSettings
        The survey's settings (origin, beacons, sigma, prior, planner, ``max_gap_s``).

    Records are appended with :meth:`add_fixes`, :meth:`add_headings` and :meth:`add_ranges` (arrays or
    single values, any order; a record whose key is already held is ignored, as the journal ignores a
    re-add). :meth:`estimates` gives the same :class:`SurveyEstimates` as
    :func:`~oceanloc.field.survey.estimates.survey_estimates` on the same records (module docstring), and
    :meth:`next_waypoint` the planner's next site from them.
    """

    def __init__(self, settings: JournalSettings) -> None:
        self.settings = settings
        self._origin: EnuOrigin | None = settings.origin
        self._fix = _Rows(4)  # t, lat, lon, h (time order)
        self._enu = _Rows(3)
        self._head = _Rows(2)  # t of the fix it follows, heading (order of arrival within a time)
        self._rng = _Rows(3)  # t, beacon, range: every range held, aligned or not (journal order)
        self._pending = np.zeros((0, 3))  # ranges (t, beacon, range) not aligned yet
        self._beacons: dict[int, _Beacon] = {}
        self._estimates: SurveyEstimates | None = None

    # -- construction -----------------------------------------------------------------------------------

    @classmethod
    def from_records(cls, records: JournalRecords, settings: JournalSettings) -> SurveyState:
        """A state holding a journal's records (one fit per beacon, as the batch estimate)."""
        state = cls(settings)
        state.add_fixes(records.fix_t_unix_s, records.lat_deg, records.lon_deg, records.h_m)
        state.add_headings(records.heading_t_unix_s, records.heading_deg)
        state.add_ranges(records.range_t_unix_s, records.beacon, records.range_m)
        return state

    @classmethod
    def from_journal(cls, journal: Journal) -> SurveyState:
        """A state holding an open journal's settings and records (resuming a survey)."""
        settings = JournalSettings.from_meta(journal.meta(), str(journal.path))
        return cls.from_records(journal.records(), settings)

    # -- appending --------------------------------------------------------------------------------------

    @property
    def n_fixes(self) -> int:
        return self._fix.n

    @property
    def n_ranges(self) -> int:
        return self._rng.n

    @property
    def track_enu_m(self) -> FloatArray:
        """Every fix held in the survey's ENU frame, ``(n, 3)`` metres (a view: do not modify)."""
        return self._enu.view

    @property
    def n_records(self) -> int:
        """Fixes, headings and ranges held."""
        return self._fix.n + self._head.n + self._rng.n

    def add_fixes(self, t_unix_s: ArrayLike, lat_deg: ArrayLike, lon_deg: ArrayLike, h_m: ArrayLike) -> None:
        """Append GPS fixes (UTC Unix seconds, WGS84 degrees, ellipsoidal metres; arrays or scalars)."""
        rows = np.column_stack(
            [np.atleast_1d(np.asarray(a, dtype=float)) for a in (t_unix_s, lat_deg, lon_deg, h_m)]
        )
        if rows.shape[0] == 0:
            return
        rows = rows[np.argsort(rows[:, 0], kind="stable")]
        rows = rows[np.concatenate([[True], np.diff(rows[:, 0]) > 0.0])]  # first of equal times
        held = self._fix.view[:, 0]
        if held.size:
            at = np.searchsorted(held, rows[:, 0])
            dup = (at < held.size) & (held[np.minimum(at, held.size - 1)] == rows[:, 0])
            rows = rows[~dup]
            if rows.shape[0] == 0:
                return
        in_order = held.size == 0 or rows[0, 0] > held[-1]
        self._estimates = None  # the track changed
        if self._origin is None:
            self._origin = EnuOrigin(
                lat_deg=float(rows[0, 1]), lon_deg=float(rows[0, 2]), h_m=float(rows[0, 3])
            )
        elif self.settings.origin is None and rows[0, 0] < held[0]:
            # A fix earlier than the earliest: the frame (the earliest fix) moves; everything anew.
            self._origin = EnuOrigin(
                lat_deg=float(rows[0, 1]), lon_deg=float(rows[0, 2]), h_m=float(rows[0, 3])
            )
            merged = np.concatenate([self._fix.view, rows])
            self._rebuild_track(merged[np.argsort(merged[:, 0], kind="stable")])
            return
        enu = geodetic_to_enu(rows[:, 1], rows[:, 2], rows[:, 3], self._origin).reshape(-1, 3)
        if in_order:
            t_prev = held[-1] if held.size else -np.inf
            self._fix.append(rows)
            self._enu.append(enu)
            # Ranges after the previous last fix may now have a fix after them.
            self._align(t_prev, np.inf)
            return
        merged = np.concatenate([self._fix.view, rows])
        order = np.argsort(merged[:, 0], kind="stable")
        self._fix.replace(merged[order])
        self._enu.replace(np.concatenate([self._enu.view, enu])[order])
        t = self._fix.view[:, 0]
        lo = np.searchsorted(t, rows[0, 0]) - 1
        hi = np.searchsorted(t, rows[-1, 0]) + 1
        self._align(t[max(lo, 0)], t[min(hi, t.size - 1)] if hi < t.size else np.inf, realign=True)

    def add_headings(self, t_unix_s: ArrayLike, heading_deg: ArrayLike) -> None:
        """Append HDT true headings (degrees clockwise from north), each with the time of the fix it
        follows (the journal's key; several after one fix keep their order)."""
        rows = np.column_stack([np.atleast_1d(np.asarray(a, dtype=float)) for a in (t_unix_s, heading_deg)])
        if rows.shape[0] == 0:
            return
        held = self._head.view
        if (held.shape[0] and rows[0, 0] < held[-1, 0]) or np.any(np.diff(rows[:, 0]) < 0.0):
            merged = np.concatenate([held, rows])
            self._head.replace(merged[np.argsort(merged[:, 0], kind="stable")])
        else:
            self._head.append(rows)

    def add_ranges(self, t_unix_s: ArrayLike, beacon: ArrayLike, range_m: ArrayLike) -> None:
        """Append ranges (UTC Unix seconds, beacon id, metres; arrays or scalars). A range is aligned and
        used once a fix within ``max_gap_s`` after it is held."""
        t = np.atleast_1d(np.asarray(t_unix_s, dtype=float))
        b = np.atleast_1d(np.asarray(beacon)).astype(np.int64)
        r = np.atleast_1d(np.asarray(range_m, dtype=float))
        rows = np.column_stack([t, b.astype(float), r])
        if rows.shape[0] == 0:
            return
        rows = rows[np.lexsort((rows[:, 1], rows[:, 0]))]
        keep = np.concatenate([[True], (np.diff(rows[:, 0]) != 0.0) | (np.diff(rows[:, 1]) != 0.0)])
        rows = rows[keep]
        held = self._rng.view
        lo = int(np.searchsorted(held[:, 0], rows[0, 0], side="left"))
        hi = int(np.searchsorted(held[:, 0], rows[-1, 0], side="right"))
        if hi > lo:  # drop keys already held (t, beacon): a re-add changes nothing
            both = np.concatenate([held[lo:hi, :2], rows[:, :2]])
            _, first = np.unique(both, axis=0, return_index=True)
            new = np.zeros(both.shape[0], dtype=bool)
            new[first] = True
            rows = rows[new[hi - lo :]]
            if rows.shape[0] == 0:
                return
        if held.shape[0] and (rows[0, 0], rows[0, 1]) < (held[-1, 0], held[-1, 1]):
            merged = np.concatenate([held, rows])  # journal order (t, beacon)
            self._rng.replace(merged[np.lexsort((merged[:, 1], merged[:, 0]))])
        else:
            self._rng.append(rows)
        self._pending = np.concatenate([self._pending, rows])
        self._align(rows[0, 0], np.inf)

    # -- alignment --------------------------------------------------------------------------------------

    def _rebuild_track(self, fixes: FloatArray) -> None:
        assert self._origin is not None
        self._fix.replace(fixes)
        self._enu.replace(geodetic_to_enu(fixes[:, 1], fixes[:, 2], fixes[:, 3], self._origin).reshape(-1, 3))
        self._beacons = {}
        self._pending = self._rng.view.copy()
        self._align(-np.inf, np.inf)

    def _align(self, t_lo: float, t_hi: float, *, realign: bool = False) -> None:
        """Align the pending ranges (and, with ``realign``, the aligned ones in ``[t_lo, t_hi]``)."""
        fixes = self._fix.view
        if fixes.shape[0] == 0:
            return
        if realign:
            t_all = self._rng.view[:, 0]
            window = np.flatnonzero((t_all >= t_lo) & (t_all <= t_hi))
            moved = {int(b) for b in np.unique(self._rng.view[window, 1])}
            for b in moved:
                self._beacons.pop(b, None)  # aligned afresh below
            ids = list(moved)
            redo = self._rng.view[np.isin(self._rng.view[:, 1], ids)]
            self._pending = np.concatenate([self._pending[~np.isin(self._pending[:, 1], ids)], redo])
        if self._pending.shape[0] == 0:
            return
        rows = self._pending
        ft, enu = fixes[:, 0], self._enu.view
        t = rows[:, 0]
        right = np.searchsorted(ft, t, side="left")
        left = np.clip(right - 1, 0, ft.size - 1)
        right_c = np.clip(right, 0, ft.size - 1)
        exact = ft[right_c] == t
        gap_l, gap_r = t - ft[left], ft[right_c] - t
        gap = self.settings.max_gap_s
        ok = exact | ((right > 0) & (right < ft.size) & (gap_l <= gap) & (gap_r <= gap))
        self._pending = rows[~ok]  # a later fix (or one out of order) may still align them
        rows = rows[ok]
        if rows.shape[0]:
            # np.interp on the bracketing pair gives align_ranges' value to the bit.
            pos = np.stack([np.interp(rows[:, 0], ft, enu[:, k]) for k in range(3)], axis=1)
            for b in np.unique(rows[:, 1]).astype(np.int64):
                sel = rows[:, 1] == b
                tr = self._beacons.setdefault(int(b), _Beacon())
                key = rows[sel, 0]
                if tr.n and key[0] < tr.key.view[-1, 0]:  # before ranges it holds: journal order afresh
                    keys = np.concatenate([tr.key.view[:, 0], key])
                    order = np.argsort(keys, kind="stable")
                    for buf, new in ((tr.t, key), (tr.z, rows[sel, 2]), (tr.key, key)):
                        buf.replace(np.concatenate([buf.view[:, 0], new])[order][:, None])
                    tr.sensor.replace(np.concatenate([tr.sensor.view, pos[sel]])[order])
                    tr.used.replace(np.ones((tr.t.n, 1), dtype=bool))
                    tr.fresh = True
                else:
                    tr.t.append(key[:, None])
                    tr.z.append(rows[sel, 2][:, None])
                    tr.key.append(key[:, None])
                    tr.sensor.append(pos[sel])
                    tr.used.append(np.ones((key.size, 1), dtype=bool))
                tr.dirty = True
            self._estimates = None

    # -- estimates --------------------------------------------------------------------------------------

    @property
    def origin(self) -> EnuOrigin:
        if self._origin is None:
            raise DataError("no GPS fix yet: no ENU frame (add fixes, or start with --origin)")
        return self._origin

    def _surface_m(self, ready: list[int]) -> float:
        heights = [self._beacons[b].sensor.view[:, 2] for b in ready]
        return float(np.median(np.concatenate(heights))) if heights else 0.0

    def _fit(self, beacon: int, tr: _Beacon, surface: float) -> None:
        """Re-estimate one beacon (module docstring): outlier rule from its mask, then GLS."""
        s = self.settings
        sensors, z, t = tr.sensor.view, tr.z.view[:, 0], tr.t.view[:, 0]
        drop = drop_means_enu_m(s, self.origin, surface).get(beacon) if s.drops else None
        prior = beacon_prior(sensors, z, surface, s.prior_sigma_enu_m, s.prior_depth_m, drop)
        opts = MapOptions(surface_z_m=surface)
        cap = int(MAX_OUTLIER_FRACTION * z.size) + 1
        tr.fresh = tr.fresh or z.size < FRESH_BELOW
        if tr.fresh or tr.white_m is None:
            fit = robust_white_fit(
                sensors, z, s.sigma_range_m, prior, opts, initial_m=prior.mean[0], max_removals=cap
            )
            used, white = fit.used, fit.estimate_m
        else:
            used, white = tr.used.view[:, 0].copy(), tr.white_m
            for _ in range(2):  # the mask carried over, new ranges tested; then the excluded retested
                left = cap - int((~used).sum())
                if left <= 0:
                    break
                fit = robust_white_fit(
                    sensors, z, s.sigma_range_m, prior, opts, initial_m=white, used=used, max_removals=left
                )
                used, white = fit.used, fit.estimate_m
                back = self._readmit(sensors, z, used, white)
                if not back.any():
                    break
                used = used | back
        first: list[FloatArray] = []
        gps = s.gps_sigma_m
        if gps > 0.0 and s.gps_correlation_s is not None:
            res = correlated_fit(
                sensors, z, t - t[0], used, prior, opts,
                initial_m=white if tr.fresh or tr.first_pass_m is None else tr.first_pass_m,
                sigma_range_m=s.sigma_range_m, sigma_gps_m=gps, gps_correlation_s=s.gps_correlation_s,
                linearize_at=white, first_pass=first,
                warm_start=not (tr.fresh or tr.first_pass_m is None), last_start_m=tr.position_m,
            )  # fmt: skip
        else:  # white GPS error: the white solve on the final mask is the estimate
            res = robust_white_fit(
                sensors, z, s.sigma_range_m, prior, opts, initial_m=white, used=used, max_removals=0
            ).result
        tr.first_pass_m = first[0].copy() if first else None
        x = res.estimate[0]
        tr.used.replace(used[:, None])
        tr.white_m, tr.position_m, tr.covariance_m2 = white.copy(), x.copy(), res.covariance[0]
        resid = z - np.linalg.norm(sensors - x, axis=1)
        tr.residual_rms_m = float(np.sqrt(np.mean(resid[used] ** 2)))
        mean = prior.mean
        check = range_linearization_check(
            x[None], tr.covariance_m2[None], sensors[None], z[None], used[None], s.sigma_range_m, mean,
            np.diag(np.square(s.prior_sigma_enu_m)),
        )  # fmt: skip
        tr.check = (check.ratio[0], float(check.statistic[0]), bool(check.trusted[0]))
        tr.dirty = tr.fresh = False

    def _readmit(self, sensors: FloatArray, z: FloatArray, used: BoolArray, x: FloatArray) -> BoolArray:
        """Excluded ranges whose normalized residual at ``x`` is now within the threshold."""
        out = np.zeros(z.size, dtype=bool)
        excl = np.flatnonzero(~used)
        if excl.size == 0:
            return out
        resid = z - np.linalg.norm(sensors - x, axis=1)
        scale = max(float(np.sqrt(np.mean(resid[used] ** 2))), self.settings.sigma_range_m)
        out[excl] = np.abs(resid[excl]) / scale <= OUTLIER_THRESHOLD
        return out

    def estimates(self) -> SurveyEstimates:
        """The current estimates (the same type and content as
        :func:`~oceanloc.field.survey.estimates.survey_estimates` on the same records).

        Raises
        ------
        DataError
            If no GPS fix is held yet.
        """
        if self._fix.n == 0:
            raise DataError("no GPS fix in the journal yet: nothing to estimate")
        if self._estimates is not None:
            return self._estimates
        origin = self.origin
        counts = {b: tr.n for b, tr in self._beacons.items()}
        ready = sorted(b for b, c in counts.items() if c >= MIN_RANGES)
        surface = self._surface_m(ready)
        for b in ready:
            tr = self._beacons[b]
            if tr.dirty or tr.position_m is None:
                self._fit(b, tr, surface)
        waiting = {int(b): 0 for b in self.settings.beacons}
        waiting |= {b: c for b, c in counts.items() if 0 < c < MIN_RANGES}
        for b in ready:
            waiting.pop(b, None)
        tracks = [self._beacons[b] for b in ready]
        pos = np.array([tr.position_m for tr in tracks]).reshape(-1, 3)
        cov = np.array([tr.covariance_m2 for tr in tracks]).reshape(-1, 3, 3)
        check = LinearizationCheck(
            ratio=np.array([tr.check[0] for tr in tracks]).reshape(len(tracks), 6),  # type: ignore[index]
            statistic=np.array([tr.check[1] for tr in tracks], dtype=float),  # type: ignore[index]
            trusted=np.array([tr.check[2] for tr in tracks], dtype=bool),  # type: ignore[index]
            confidence=ELLIPSE_CONFIDENCE,
        )
        wait_ids = np.array(sorted(waiting), dtype=np.int64)
        self._estimates = SurveyEstimates(
            origin=origin,
            beacons=np.array(ready, dtype=np.int64),
            positions_enu_m=pos,
            covariances_m2=cov,
            positions_geodetic=enu_to_geodetic(pos, origin).reshape(-1, 3),
            ellipses=confidence_ellipse(pos[:, :2], cov[:, :2, :2], ELLIPSE_CONFIDENCE),
            ranges_used=np.array([int(tr.used.view.sum()) for tr in tracks], dtype=np.int64),
            ranges_excluded=np.array([int((~tr.used.view).sum()) for tr in tracks], dtype=np.int64),
            residual_rms_m=np.array([tr.residual_rms_m for tr in tracks], dtype=float),
            waiting_beacons=wait_ids,
            waiting_ranges=np.array([waiting[int(b)] for b in wait_ids], dtype=np.int64),
            track_enu_m=self._enu.view,
            range_status=self._range_status(ready),
            trusted=check.trusted,
            linearity=check.statistic,
            trust_messages=tuple(check.messages()),
        )
        return self._estimates

    def _range_status(self, ready: list[int]) -> IntArray:
        """Index into :data:`RANGE_STATUS` of every range held (journal order)."""
        held = self._rng.view
        status = np.full(held.shape[0], RANGE_STATUS.index("no-gps"), dtype=np.int64)
        for b, tr in self._beacons.items():
            if tr.n == 0:
                continue
            rows = np.flatnonzero(held[:, 1] == b)
            lines = rows[np.searchsorted(held[rows, 0], tr.key.view[:, 0])]
            if b in ready:
                used = tr.used.view[:, 0]
                status[lines] = np.where(used, RANGE_STATUS.index("used"), RANGE_STATUS.index("outlier"))
            else:
                status[lines] = RANGE_STATUS.index("waiting")
        return status

    def records(self) -> JournalRecords:
        """The records held, as the journal would return them (arrays are views: do not modify)."""
        fix, head, rng = self._fix.view, self._head.view, self._rng.view
        return JournalRecords(
            fix_t_unix_s=fix[:, 0],
            lat_deg=fix[:, 1],
            lon_deg=fix[:, 2],
            h_m=fix[:, 3],
            range_t_unix_s=rng[:, 0],
            beacon=rng[:, 1].astype(np.int64),
            range_m=rng[:, 2],
            heading_t_unix_s=head[:, 0],
            heading_deg=head[:, 1],
        )

    def next_waypoint(self, rng: np.random.Generator | None = None) -> Waypoint:
        """The survey planner's next site from the last fix with the current estimates
        (:func:`~oceanloc.field.survey.estimates.next_waypoint`)."""
        return next_waypoint(self.records(), self.settings, estimates=self.estimates(), rng=rng)
