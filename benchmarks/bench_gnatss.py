"""oceanloc against GNATSS on the same synthetic three-transponder array survey (10,000 interrogations).

Both packages run in a process of their own, started by this one with one BLAS and OpenMP thread
(``OPENBLAS_NUM_THREADS=OMP_NUM_THREADS=MKL_NUM_THREADS=1``: on a small shared machine extra BLAS
threads spin and make both slower and noisier; the variable has to be set before numpy loads, hence the
processes). GNATSS runs in its own environment (``make gnatss``); each process times its solver alone,
wall and CPU, after its imports and the loading of the inputs. Rows:

* GNATSS 0.4.2, its solver (``run_solver``: cuts, harmonic means, iterations, outlier limits);
* oceanloc, GNATSS's settings (:func:`~oceanloc.estimation.gnatss_compat.gnatss_solve`: the same
  estimate, batched in numpy); target: at least as fast as GNATSS, positions within 1 mm of GNATSS's;
* oceanloc, its defaults (ray tracing, sound-speed knots piecewise linear in time with their prior,
  gradient, variance components, outlier loop, jackknife, common shift); target: at least as fast as
  GNATSS.

Each row also gives the error of the array centre against the truth. The survey has no sound-speed drift;
its travel times are ray traced through the profile (a stratified ocean), so GNATSS's straight ray at the
vertical harmonic-mean speed is about 1 cm off in depth, and oceanloc's ray model is exact (on surveys
made with GNATSS's own straight-ray model, ``ray_traced=False``, it is the other way round: oceanloc's
defaults are then 20 mm off in depth, the speed knots turning the angle-dependent misfit into depth).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

N_PINGS = 10_000
ONE_THREAD = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
VARIANTS = (
    ("oceanloc, GNATSS's settings", "gnatss"),
    ("oceanloc, its defaults (common shift)", "oceanloc"),
)


def _oceanloc_worker(config: str) -> None:
    """Time oceanloc's two variants on the survey of ``config`` (run in a process of its own) and print
    one JSON line per variant: wall and CPU seconds of the solve, positions, centre."""
    import numpy as np
    import scipy.optimize  # noqa: F401  (imported lazily by the noise estimate: an import, not solving)

    from oceanloc.estimation.gnatss_compat import GnatssSettings
    from oceanloc.field.gnatss_input import load_gnatss_input, localize_gnatss_input

    t0 = time.perf_counter()
    data = load_gnatss_input(config)
    load_s = time.perf_counter() - t0
    one_run = GnatssSettings.from_config(data.config, outlier_rounds=1)  # as one GNATSS run
    for label, method in VARIANTS:
        kwargs = (
            {"method": "gnatss", "settings": one_run}
            if method == "gnatss"
            else {"method": "oceanloc", "solution": "common_shift"}
        )
        t0, c0 = time.perf_counter(), time.process_time()
        loc = localize_gnatss_input(data, **kwargs)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        out = {
            "label": label,
            "load_s": load_s,
            "solve_s": wall,
            "solve_cpu_s": cpu,
            "positions_enu_m": np.asarray(loc.positions_enu_m).tolist(),
            "centre_enu_m": np.asarray(loc.centre_enu_m).tolist(),
        }
        print("OCEANLOC " + json.dumps(out), flush=True)


def _run_oceanloc(config: Path) -> list[dict]:
    env = {**os.environ, **ONE_THREAD}
    proc = subprocess.run(
        [sys.executable, __file__, "--oceanloc-worker", str(config)],
        capture_output=True, text=True, env=env, check=False,
    )  # fmt: skip
    marker = "OCEANLOC "
    rows = [json.loads(x.removeprefix(marker)) for x in proc.stdout.splitlines() if x.startswith(marker)]
    if proc.returncode != 0 or len(rows) != len(VARIANTS):
        raise RuntimeError(f"the oceanloc timing process failed: {proc.stderr.strip()[-2000:]}")
    return rows


def main() -> None:
    import numpy as np
    import pymap3d

    from oceanloc.reproduce.gnatss_oracle import GNATSS_VERSION, gnatss_python, run_gnatss
    from oceanloc.sim.gnatss_survey import ArraySurveySpec, write_gnatss_survey

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        spec = ArraySurveySpec(n_pings=N_PINGS, residual_limit_cm=20.0, ray_traced=True, seed=10)
        truth, files = write_gnatss_survey(spec, folder)
        centre = truth.transponders_enu_m.mean(axis=0)
        rows: list[tuple[str, float, float, float, float]] = []
        gn_enu = None
        if gnatss_python() is None:
            print("gnatss is not installed (`make gnatss` builds .venv-gnatss): GNATSS row skipped")
        else:
            run = run_gnatss(files.config, folder / "gnatss-output", extra_env=ONE_THREAD)
            o = truth.origin
            gn_enu = np.stack(pymap3d.ecef2enu(*run.position_xyz_m.T, o.lat_deg, o.lon_deg, o.h_m), axis=-1)
            err = float(np.linalg.norm(gn_enu.mean(axis=0) - centre))
            rows.append((f"GNATSS {run.version} solver", run.load_s, run.solve_s, run.solve_cpu_s, err))
        for res in _run_oceanloc(files.config):
            err = float(np.linalg.norm(np.asarray(res["centre_enu_m"]) - centre))
            rows.append((res["label"], res["load_s"], res["solve_s"], res["solve_cpu_s"], err))
            if res["label"] == VARIANTS[0][0] and gn_enu is not None:
                diff = np.max(np.abs(np.asarray(res["positions_enu_m"]) - gn_enu))
                print(
                    f"oceanloc (GNATSS's settings) - GNATSS: {1e3 * diff:.6f} mm max per axis (target < 1 mm)"
                )
    print(f"{N_PINGS} interrogations x 3 transponders; GNATSS {GNATSS_VERSION}; one BLAS/OpenMP thread each")
    print(f"{'':40s} {'load s':>8s} {'solve s':>8s} {'CPU s':>8s} {'centre error mm':>16s}")
    for label, load, solve, cpu, err in rows:
        print(f"{label:40s} {load:8.2f} {solve:8.2f} {cpu:8.2f} {1e3 * err:16.1f}")
    if rows and rows[0][0].startswith("GNATSS"):
        g_wall, g_cpu = rows[0][2], rows[0][3]
        for label, _, solve, cpu, _ in rows[1:]:
            verdict = "ok" if solve <= g_wall else "SLOWER than GNATSS"
            print(
                f"{label}: solve {solve:.2f} s wall, {cpu:.2f} s CPU; target <= GNATSS's {g_wall:.2f} s wall "
                f"({g_cpu:.2f} s CPU): {g_wall / solve:.1f}x GNATSS's speed, {verdict}"
            )


if __name__ == "__main__" and sys.argv[1:2] == ["--oceanloc-worker"]:
    _oceanloc_worker(sys.argv[2])
