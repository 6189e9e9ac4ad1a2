"""A forecast file in each supported layout plans end to end from the installed command line and exports a
QGroundControl ``.plan`` that its documented format accepts (issue 26, acceptance); ensembles report the
spread of every candidate plan; bad products and options are one-line errors."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.models import product_layouts as lay

jsonschema = pytest.importorskip("jsonschema")
SCHEMA = json.loads((Path(__file__).parents[1] / "io" / "data" / "qgc_plan.schema.json").read_text())

# Start 6 km west and 2.5 km north of the gyres' centre, goal 6 km east and 2.5 km south.
START = "32.62252706,-117.36393242"
GOAL = "32.57744034,-117.2360996"


def _entry() -> list[str]:
    beside = Path(sys.executable).with_name("oceanloc")
    if beside.exists():
        return [str(beside)]
    found = shutil.which("oceanloc")
    return [found] if found else [sys.executable, "-m", "oceanloc"]


def _plan(tmp_path: Path, products: list[Path], *extra: str) -> subprocess.CompletedProcess:
    args = [*_entry(), "drift-plan"]
    for p in products:
        args += ["--currents", str(p)]
    args += [
        "--start",
        START,
        "--goal",
        GOAL,
        "--out",
        str(tmp_path / "out"),
        "--json",
        str(tmp_path / "plan.json"),
    ]
    return subprocess.run([*args, *extra], capture_output=True, text=True, timeout=600)


@pytest.mark.parametrize("layout", ["copernicus-netcdf", "copernicus-zarr", "hycom", "roms"])
def test_each_layout_plans_from_the_command_line_and_exports_a_valid_plan(tmp_path, layout):
    writers = {
        "copernicus-netcdf": (lay.write_copernicus_netcdf, "cmems.nc"),
        "copernicus-zarr": (lay.write_copernicus_zarr, "cmems.zarr"),
        "hycom": (lay.write_hycom_netcdf, "hycom.nc"),
        "roms": (lay.write_roms, "roms_his.nc"),
    }
    if layout == "copernicus-zarr":
        pytest.importorskip("zarr")
    write, name = writers[layout]
    product = write(tmp_path / name)
    proc = _plan(
        tmp_path, [product], "--start-time", "2024-03-01T03:00:00", "--depth", "0",
        "--time-window", "2024-03-01T00:00:00,2024-03-02T06:00:00",
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    record = json.loads((tmp_path / "plan.json").read_text())
    assert record["result"]["status"] == "exact"
    assert record["time_origin"].startswith("2024-03-01T00:00:00") and record["start_time_s"] == 10_800.0
    assert record["provenance"]["inputs"][0]["path"] == str(product)
    out = tmp_path / "out"
    plan_file = next(out.glob("*.plan"))
    plan = json.loads(plan_file.read_text())
    jsonschema.validate(plan, SCHEMA)
    assert plan["mission"]["plannedHomePosition"][:2] == pytest.approx([32.62252706, -117.36393242], abs=1e-6)
    for suffix in (".png", ".csv", ".geojson", ".kml", ".waypoints"):
        assert next(out.glob(f"*{suffix}")).stat().st_size > 0


def test_a_boat_in_the_water_gets_holds_and_waypoints(tmp_path):
    product = lay.write_copernicus_netcdf(tmp_path / "cmems.nc")
    proc = _plan(
        tmp_path,
        [product],
        "--propulsion",
        "water",
        "--objective",
        "time",
        "--start-time",
        "2024-03-01T03:00:00",
    )
    assert proc.returncode == 0, proc.stderr
    plan = json.loads(next((tmp_path / "out").glob("*.plan")).read_text())
    jsonschema.validate(plan, SCHEMA)
    assert plan["mission"]["vehicleType"] == 11  # MAV_TYPE_SURFACE_BOAT
    assert {it["command"] for it in plan["mission"]["items"]} <= {16, 93}


def test_an_ensemble_reports_every_candidate_and_its_spread(tmp_path):
    product = lay.write_copernicus_netcdf(tmp_path / "ens.nc", members=3)
    proc = _plan(tmp_path, [product], "--start-time", "2024-03-01T03:00:00", "--deadline-h", "20")
    assert proc.returncode == 0, proc.stderr
    assert "Ensemble of 3 members" in proc.stdout and "(chosen)" in proc.stdout
    ens = json.loads((tmp_path / "plan.json").read_text())["ensemble"]
    assert ens["members"] == 3 and len(ens["candidates"]) == 4
    means = [c["objective_mean"] for c in ens["candidates"]]
    chosen = next(c for c in ens["candidates"] if c["chosen"])
    assert chosen["objective_mean"] == min(means)
    assert all(c["energy_wh_min"] <= c["energy_wh_mean"] <= c["energy_wh_max"] for c in ens["candidates"])


def test_ensemble_members_as_separate_files(tmp_path):
    from oceanloc.models.currents_cf import open_current_product

    a = lay.write_copernicus_netcdf(tmp_path / "a.nc")
    b = lay.write_copernicus_netcdf(tmp_path / "b.nc")
    proc = _plan(tmp_path, [a, b], "--start-time", "2024-03-01T03:00:00", "--deadline-h", "20")
    assert proc.returncode == 0, proc.stderr
    assert json.loads((tmp_path / "plan.json").read_text())["ensemble"]["members"] == 2
    assert open_current_product(a).members == ()


@pytest.mark.parametrize(
    ("make", "extra", "message"),
    [
        (lay.write_fvcom, (), "an FVCOM subset"),
        (lay.write_copernicus_netcdf, ("--depth", "500"), "below the deepest level"),
        (lay.write_copernicus_netcdf, ("--start-time", "2025-01-01T00:00:00"), "--start-time"),
        (lay.write_copernicus_netcdf, ("--time-window", "2024-03-01"), "--time-window must be START,END"),
    ],
)
def test_bad_products_and_options_are_one_line_errors(tmp_path, make, extra, message):
    product = make(tmp_path / "p.nc")
    proc = _plan(tmp_path, [product], *extra)
    assert proc.returncode != 0 and "Traceback" not in proc.stderr
    assert message in proc.stderr and proc.stderr.count("\n") <= 2


def test_currents_need_start_and_goal(tmp_path):
    product = lay.write_copernicus_netcdf(tmp_path / "p.nc")
    proc = subprocess.run(
        [*_entry(), "drift-plan", "--currents", str(product), "--out", str(tmp_path)],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert proc.returncode == 2 and "--currents needs --start LAT,LON and --goal LAT,LON" in proc.stderr
