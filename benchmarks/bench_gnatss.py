"""oceanloc against GNATSS on the same synthetic three-transponder array survey (10,000 interrogations).

GNATSS runs in its own environment (``make gnatss``) as a subprocess; its solver's wall time is measured
inside that process (loading and writing excluded), oceanloc's in this one. Rows:

* GNATSS 0.4.2, its solver (``run_solver``: cuts, harmonic means, iterations, outlier limits);
* oceanloc, GNATSS's settings (:func:`~oceanloc.estimation.gnatss_compat.gnatss_solve`: the same
  estimate, batched in numpy); target: at least as fast as GNATSS, positions within 1 mm of GNATSS's;
* oceanloc, its defaults (ray tracing, sound-speed scale and gradient, noise, outlier loop, common
  shift); target: at least as fast as GNATSS.

Each row also gives the error of the array centre against the truth (the survey has no sound-speed drift:
GNATSS's fixed speed is right, and both should land within a few centimetres).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np
import pymap3d

from oceanloc.estimation.gnatss_compat import GnatssSettings
from oceanloc.field.gnatss_input import load_gnatss_input, localize_gnatss_input
from oceanloc.reproduce.gnatss_oracle import GNATSS_VERSION, gnatss_python, run_gnatss
from oceanloc.sim.gnatss_survey import ArraySurveySpec, write_gnatss_survey

N_PINGS = 10_000


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        spec = ArraySurveySpec(n_pings=N_PINGS, residual_limit_cm=20.0, seed=10)
        truth, files = write_gnatss_survey(spec, folder)
        centre = truth.transponders_enu_m.mean(axis=0)
        rows: list[tuple[str, float, float, float]] = []
        gn_enu = None
        if gnatss_python() is None:
            print("gnatss is not installed (`make gnatss` builds .venv-gnatss): GNATSS row skipped")
        else:
            run = run_gnatss(files.config, folder / "gnatss-output")
            o = truth.origin
            gn_enu = np.stack(pymap3d.ecef2enu(*run.position_xyz_m.T, o.lat_deg, o.lon_deg, o.h_m), axis=-1)
            err = float(np.linalg.norm(gn_enu.mean(axis=0) - centre))
            rows.append((f"GNATSS {run.version} solver", run.load_s, run.solve_s, err))
        t0 = time.perf_counter()
        data = load_gnatss_input(files.config)
        load_s = time.perf_counter() - t0
        one_run = GnatssSettings.from_config(data.config, outlier_rounds=1)  # as one GNATSS run
        for label, kwargs in (
            ("oceanloc, GNATSS's settings", {"method": "gnatss", "settings": one_run}),
            ("oceanloc, its defaults (common shift)", {"method": "oceanloc", "solution": "common_shift"}),
        ):
            t0 = time.perf_counter()
            loc = localize_gnatss_input(data, **kwargs)
            solve_s = time.perf_counter() - t0
            rows.append((label, load_s, solve_s, float(np.linalg.norm(loc.centre_enu_m - centre))))
            print(f"{label}: {solve_s:.2f} s", flush=True)
            if kwargs["method"] == "gnatss" and gn_enu is not None:
                diff = np.max(np.abs(loc.positions_enu_m - gn_enu))
                print(
                    f"oceanloc (GNATSS's settings) - GNATSS: {1e3 * diff:.6f} mm max per axis (target < 1 mm)"
                )
    print(f"{N_PINGS} interrogations x 3 transponders; GNATSS {GNATSS_VERSION}")
    print(f"{'':40s} {'load s':>8s} {'solve s':>8s} {'centre error mm':>16s}")
    for label, load, solve, err in rows:
        print(f"{label:40s} {load:8.2f} {solve:8.2f} {1e3 * err:16.1f}")
    if rows and rows[0][0].startswith("GNATSS"):
        g = rows[0][2]
        for label, _, solve, _ in rows[1:]:
            verdict = "at least as fast: ok" if solve <= g else "SLOWER than GNATSS"
            print(f"{label}: {g / solve:.1f}x GNATSS's solver speed ({verdict})")
