import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

from typer.testing import CliRunner

from oceanloc.cli.app import app
from oceanloc.io.kml import KML_NS
from tests.report.html.conftest import make_journal

Q = {"k": KML_NS}


def _run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "oceanloc", *args], capture_output=True, text=True, env=os.environ
    )


def test_report_of_a_journal_writes_html_and_kml(tmp_path: Path):
    db = make_journal(tmp_path, duration_s=450.0)
    res = CliRunner().invoke(
        app, ["report", str(db), "--html", str(tmp_path / "r.html"), "--kml", str(tmp_path / "r.kml")]
    )
    assert res.exit_code == 0, res.output
    page = (tmp_path / "r.html").read_text()
    assert 'data-report-kind="journal"' in page and "95% ellipse beacon 2" in page
    root = ET.parse(tmp_path / "r.kml").getroot()
    folders = [f.findtext("k:name", namespaces=Q) for f in root.iterfind("k:Document/k:Folder", Q)]
    assert folders == ["track", "sites", "estimates", "95% ellipses"]
    assert len(root.findall(".//k:Polygon", Q)) == 2
    track = root.find(".//k:LineString/k:coordinates", Q).text.split()
    assert len(track) == 450  # every fix, not the thinned drawing


def test_local_record_needs_origin_for_kml(tmp_path: Path):
    rec = tmp_path / "s.json"
    assert (
        CliRunner()
        .invoke(
            app,
            [
                "simulate",
                "survey",
                "--scenario",
                "garcia2019-m1",
                "--runs",
                "1",
                "--epochs",
                "5",
                "--json",
                str(rec),
            ],
        )
        .exit_code
        == 0
    )
    res = _run("report", str(rec), "--html", str(tmp_path / "s.html"), "--kml", str(tmp_path / "s.kml"))
    assert res.returncode == 2 and "Traceback" not in res.stderr
    assert "local frame: pass --origin LAT,LON" in res.stderr and not (tmp_path / "s.html").exists()
    res = _run(
        "report",
        str(rec),
        "--html",
        str(tmp_path / "s.html"),
        "--kml",
        str(tmp_path / "s.kml"),
        "--origin",
        "32.7,-117.2",
    )
    assert res.returncode == 0, res.stderr
    root = ET.parse(tmp_path / "s.kml").getroot()
    assert (
        len(root.findall(".//k:Polygon", Q)) == 1 and len(root.findall(".//k:Point", Q)) == 6
    )  # 5 sites + 1


def test_unknown_source_exits_2_with_one_line(tmp_path: Path):
    (tmp_path / "x.json").write_text("[1, 2]")
    res = _run("report", str(tmp_path / "x.json"), "--html", str(tmp_path / "x.html"))
    assert res.returncode == 2 and "Traceback" not in res.stderr
    assert "not a record oceanloc report knows" in res.stderr
    res = _run("report", str(tmp_path / "nothing.db"), "--html", str(tmp_path / "x.html"))
    assert res.returncode == 2 and "no such file" in res.stderr
