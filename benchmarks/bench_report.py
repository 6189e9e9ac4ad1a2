"""Size and load time of the HTML report of a 24-hour survey journal (about 100,000 records).

Targets (issue 14): the page opens in headless Chromium in under 3 s (navigation to every figure drawn,
network off) and weighs under 20 MB. The drawn track is thinned; the tables keep every row.

The load time is measured :data:`LOADS` times, each beside a load of a page holding only plotly's
bundle (the part every plotly report pays, whatever it draws), and printed as the median (the verdict)
and the best, with the machine's load average: on a shared machine the spread is the other processes'.
Run: ``python benchmarks/run.py report`` (needs chromium and websocket-client for the load time).
"""

from __future__ import annotations

import os
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from oceanloc.config.survey import PlannerSettings
from oceanloc.field.survey.journal import Journal, append_gps_log, append_range_log
from oceanloc.field.survey.settings import JournalSettings
from oceanloc.io.nmea import read_nmea
from oceanloc.io.usbl import read_usbl
from oceanloc.report.html.browser import PLOTLY_READY, find_chromium, load_page
from oceanloc.report.html.page import page_head, render_html
from oceanloc.report.html.sources import load_report
from oceanloc.sim.logs import PierLogSettings, simulate_pier_logs

TARGET_LOAD_S = 3.0
TARGET_SIZE_MB = 20.0
LOADS = 5


def make_day_journal(folder: Path) -> tuple[Path, int]:
    """24 h of simulated pier logs in a journal: 1 Hz GPS (and HDT) fixes, a range every 10 s.

    The range rate is kept low because the journal's estimator builds a dense ``n x n`` range covariance
    per beacon (GPS-correlated noise): at the pier logs' 0.67 Hz, 29,000 ranges per beacon need ~7 GB.
    Returns the journal and its fixes + ranges.
    """
    settings = PierLogSettings(duration_s=86_400.0, gps_rate_hz=1.0, range_rate_hz=0.1)
    logs = simulate_pier_logs(folder, settings, np.random.default_rng(24))
    path = folder / "day.db"
    journal_settings = JournalSettings(
        planner=PlannerSettings(kind="greedy", max_distance_m=4.0), beacons=(1, 2)
    )
    with Journal.start(path, journal_settings.to_meta()) as j:
        append_gps_log(j, read_nmea(logs.nmea_path), logs.nmea_path)
        append_range_log(j, read_usbl(logs.ranges_path, beacons=(1, 2)), logs.ranges_path)
        r = j.records()
    return path, r.n_fixes + r.n_ranges


def main() -> None:
    with tempfile.TemporaryDirectory(prefix="bench-report-") as tmp:
        folder = Path(tmp)
        t0 = time.perf_counter()
        db, n_records = make_day_journal(folder)
        took = time.perf_counter() - t0
        print(
            f"journal: {n_records} records (GPS fixes and ranges; an HDT heading per fix too), {took:.1f} s"
        )
        t0 = time.perf_counter()
        rep = load_report(db)
        page = folder / "day.html"
        page.write_text(render_html(rep), encoding="utf-8")
        build_s = time.perf_counter() - t0
        size_mb = page.stat().st_size / 1e6
        print(f"report written in {build_s:.1f} s (read journal, estimate, draw)")
        verdict = "ok" if size_mb < TARGET_SIZE_MB else "MISSED"
        print(f"size      {size_mb:8.2f} MB   target < {TARGET_SIZE_MB:.0f} MB   {verdict}")
        if find_chromium() is None:
            print("load time: chromium not installed, not measured")
            return
        bundle = folder / "bundle.html"
        bundle.write_text(page_head("plotly only", "none") + "</body></html>\n", encoding="utf-8")
        loads, bare = [], []
        load_avg = os.getloadavg()[0]
        for _ in range(LOADS):
            loads.append(load_page(page, "null", ready=PLOTLY_READY, timeout_s=60.0))
            bare.append(load_page(bundle, "null", ready="typeof Plotly === 'object'", timeout_s=60.0).load_s)
        load_avg = max(load_avg, os.getloadavg()[0])
        times = [x.load_s for x in loads]
        median = statistics.median(times)
        errors = sum(len(x.console_errors) + len(x.outside_requests) + len(x.failed_requests) for x in loads)
        verdict = "ok" if median < TARGET_LOAD_S else "MISSED"
        print(
            f"load time {median:8.2f} s    target < {TARGET_LOAD_S:.0f} s     {verdict}"
            f"   (median of {LOADS}; best {min(times):.2f} s; errors/requests {errors})"
        )
        print(
            f"          {statistics.median(bare):8.2f} s    of it plotly's bundle alone (median; best "
            f"{min(bare):.2f} s); load average {load_avg:.1f} on {os.cpu_count()} cores"
        )


if __name__ == "__main__":
    main()
