"""GNATSS as an oracle: run the community's GNSS-A package in its own virtual environment.

GNATSS pins versions that clash with oceanloc's (``xarray < 2025``, ``pydantic == 2.8.2``, numba), so
it lives in a separate environment (``make gnatss`` builds ``.venv-gnatss``) and is called as a
subprocess: a short Python program in that environment loads a configuration, times GNATSS's solver
and writes its usual outputs (``residuals.csv``, ``outliers.csv``, ``deletions.csv``,
``process_dataset.nc``), which oceanloc then reads with :mod:`oceanloc.io.gnatss`.

:func:`gnatss_python` finds the environment (``OCEANLOC_GNATSS_PYTHON``, else ``.venv-gnatss`` in the
working directory or a parent); callers skip with a message naming gnatss when it is absent.
"""

from __future__ import annotations

import json
import os
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.errors import DataError
from oceanloc.io.gnatss import EpochResiduals, read_epoch_residuals

GNATSS_VERSION = "0.4.2"
"""The GNATSS release the oracle tests were written against (``make gnatss`` installs it)."""

_RUNNER = r"""
import json, sys, time, warnings
warnings.simplefilter("ignore")
t0 = time.perf_counter()
from gnatss.configs.io import CSVOutput
from gnatss.ops.data import data_loading
from gnatss.ops.io import to_file
from gnatss.solver.run import run_solver
import gnatss
t1 = time.perf_counter()
for index, path in enumerate(sys.argv[2:]):
    t2 = time.perf_counter()
    config, data = data_loading(path, remove_outliers=sys.argv[1] == "1", skip_posfilter=True)
    t3 = time.perf_counter()
    c3 = time.process_time()
    data = run_solver(config, data)
    t4 = time.perf_counter()
    c4 = time.process_time()
    to_file(config, data, "residuals", CSVOutput.residuals)
    to_file(config, data, "outliers", CSVOutput.outliers)
    to_file(config, data, "process_dataset", "process_dataset.nc", file_format="netcdf")
    print("ORACLE " + json.dumps({"index": index, "version": gnatss.__version__, "import_s": t1 - t0,
          "load_s": t3 - t2, "solve_s": t4 - t3, "solve_cpu_s": c4 - c3,
          "total_s": time.perf_counter() - t2}), flush=True)
"""


def gnatss_python() -> Path | None:
    """The Python of GNATSS's environment, or None if it is not built."""
    env = os.environ.get("OCEANLOC_GNATSS_PYTHON")
    if env:
        return Path(env) if Path(env).exists() else None
    here = Path.cwd().resolve()
    for folder in [here, *here.parents, *Path(__file__).resolve().parents]:
        candidate = folder / ".venv-gnatss" / "bin" / "python"
        if candidate.exists():
            return candidate
    return None


@dataclass(frozen=True, slots=True, kw_only=True)
class GnatssRun:
    """One run of GNATSS's solver.

    Attributes
    ----------
    output : Path
        GNATSS's output folder.
    version : str
    solve_s, load_s, total_s : float
        Wall time of its solver, of loading its inputs, and of the whole program (imports included), s.
    solve_cpu_s : float
        CPU time of its process during the solver (all threads), s.
    position_xyz_m : (m, 3) float
        Final transponder positions (``transponders_xyz`` of the last iteration), Earth-fixed, m.
    delta_enu_m, sigma_enu_m : (m, 3) float
        Offsets from the a-priori positions and their sigmas, ENU, metres.
    iterations : int
    residuals : EpochResiduals
        ``residuals.csv``.
    outliers : EpochResiduals or None
        ``outliers.csv`` (None when GNATSS found none).
    deletions : (d, 2) float
        ``deletions.csv`` windows (empty when none).
    """

    output: Path
    version: str
    solve_s: float
    load_s: float
    total_s: float
    position_xyz_m: FloatArray
    delta_enu_m: FloatArray
    sigma_enu_m: FloatArray
    iterations: int
    residuals: EpochResiduals
    outliers: EpochResiduals | None
    deletions: FloatArray
    solve_cpu_s: float = float("nan")


def run_gnatss(
    config_path: str | Path,
    output: str | Path,
    remove_outliers: bool = False,
    timeout_s: float = 900.0,
    extra_env: dict[str, str] | None = None,
) -> GnatssRun:
    """Run GNATSS's solver on a configuration (its ``output.path`` must be ``output``) and read the outputs.

    ``extra_env`` is added to the subprocess's environment (the benchmark pins the BLAS threads there).

    Raises
    ------
    DataError
        If the environment is missing or GNATSS fails (the last lines of its output in the message).
    """
    return run_gnatss_many([config_path], [output], remove_outliers, timeout_s, extra_env)[0]


def run_gnatss_many(
    config_paths: list[str | Path],
    outputs: list[str | Path],
    remove_outliers: bool = False,
    timeout_s: float = 900.0,
    extra_env: dict[str, str] | None = None,
) -> list[GnatssRun]:
    """Run GNATSS's solver on several configurations in ONE subprocess (GNATSS's imports, about 4 s, are
    paid once: the oracle's Monte Carlo tests solve several surveys) and read each one's outputs.

    ``outputs[k]`` must be the ``output.path`` of ``config_paths[k]``. Each run's ``total_s`` is its own
    loading, solving and writing (without the shared imports).

    Raises
    ------
    DataError
        If the environment is missing or GNATSS fails on any configuration.
    """
    python = gnatss_python()
    if python is None:
        raise DataError("gnatss is not installed: run `make gnatss` (builds .venv-gnatss)")
    if len(config_paths) != len(outputs):
        raise DataError("run_gnatss_many needs one output folder per configuration")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env.update(extra_env or {})
    args = [str(python), "-c", _RUNNER, "1" if remove_outliers else "0", *map(str, config_paths)]
    proc = subprocess.run(args, capture_output=True, text=True, env=env, timeout=timeout_s, check=False)
    infos = [
        json.loads(x.removeprefix("ORACLE ")) for x in proc.stdout.splitlines() if x.startswith("ORACLE ")
    ]
    if proc.returncode != 0 or len(infos) != len(config_paths):
        tail = " | ".join((proc.stderr or proc.stdout).strip().splitlines()[-3:])
        failed = config_paths[len(infos)] if len(infos) < len(config_paths) else config_paths[-1]
        raise DataError(f"gnatss failed on {failed} (exit {proc.returncode}): {tail}")
    return [_read_run(Path(out), info) for out, info in zip(outputs, infos, strict=True)]


def _read_run(out: Path, info: dict) -> GnatssRun:
    """One GNATSS run's outputs (``process_dataset.nc`` and the CSV files in ``out``)."""
    import xarray as xr

    from oceanloc.io.gnatss import read_deletions

    with xr.open_dataset(out / "process_dataset.nc") as ds:
        last = ds.isel(iteration=-1)
        xyz = np.asarray(last["transponders_xyz"].values, dtype=float)
        d_enu = np.asarray(last["delta_enu"].values, dtype=float)
        s_enu = np.asarray(last["sigma_enu"].values, dtype=float)
        n_it = int(ds.sizes["iteration"])
    outliers = read_epoch_residuals(out / "outliers.csv") if (out / "outliers.csv").exists() else None
    deletions = (
        read_deletions(out / "deletions.csv") if (out / "deletions.csv").exists() else np.zeros((0, 2))
    )
    return GnatssRun(
        output=out, version=str(info["version"]), solve_s=float(info["solve_s"]),
        solve_cpu_s=float(info.get("solve_cpu_s", "nan")),
        load_s=float(info["load_s"]), total_s=float(info["total_s"]), position_xyz_m=xyz, delta_enu_m=d_enu,
        sigma_enu_m=s_enu, iterations=n_it,
        residuals=read_epoch_residuals(out / "residuals.csv"), outliers=outliers, deletions=deletions,
    )  # fmt: skip
