"""Which kind of source a file is (SQLite journal or which JSON record), and its :class:`Report`.

A survey journal is recognized by the SQLite header; a JSON record by its keys, with the provenance's
command line as a tie-breaker (``simulate survey``, ``localize gnssa``, ``localize gnssa --format gnatss``,
``reproduce garcia2019``, ``drift-plan``).
"""

from __future__ import annotations

import json
from pathlib import Path

from oceanloc.errors import DataError
from oceanloc.report.html import records
from oceanloc.report.html.model import Report

SQLITE_HEADER = b"SQLite format 3\x00"
KINDS = ("journal", "survey", "montecarlo", "gnssa", "gnssa-array", "reproduction", "drift")


def _json_kind(rec: dict) -> str | None:
    command = [str(c) for c in rec.get("provenance", {}).get("command") or []]
    if "transponders" in rec and "sites_enu_m" in rec:
        return "survey"
    if "rmsee_m" in rec and "logdet_mean" in rec:
        return "montecarlo"
    if "surveys" in rec and "spread" in rec:
        return "gnssa"
    if "transponders" in rec and "centre" in rec and "pings" in rec and "details" in rec:
        return "gnssa-array"
    if "checks" in rec and ("studies" in rec or "reproduce" in command):
        return "reproduction"
    if "result" in rec and "energy" in rec and "start_m" in rec:
        return "drift"
    return None


def detect_kind(path: str | Path) -> tuple[str, dict | None]:
    """The source's kind (one of :data:`KINDS`) and, for JSON, the parsed record.

    Raises
    ------
    DataError
        If the file is missing, neither SQLite nor JSON, or a JSON record of no known kind.
    """
    p = Path(path)
    if not p.is_file():
        raise DataError(f"{p}: no such file")
    with p.open("rb") as f:
        head = f.read(16)
    if head == SQLITE_HEADER:
        return "journal", None
    try:
        rec = json.loads(p.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise DataError(f"{p}: neither a survey journal (SQLite) nor a JSON record ({exc})") from None
    kind = _json_kind(rec) if isinstance(rec, dict) else None
    if kind is None:
        raise DataError(
            f"{p}: a JSON file, but not a record oceanloc report knows (simulate survey, localize gnssa, "
            "localize gnssa --format gnatss, reproduce, drift-plan)"
        )
    return kind, rec


def load_report(path: str | Path) -> Report:
    """The :class:`Report` of a journal or JSON record."""
    kind, rec = detect_kind(path)
    if kind == "journal":
        from oceanloc.report.html.journal import journal_report

        return journal_report(path)
    assert rec is not None
    try:
        if kind == "drift":
            return records.drift_report(rec, _drift_scenario(rec))
        build = {
            "survey": records.survey_report,
            "montecarlo": records.montecarlo_report,
            "gnssa": records.gnssa_report,
            "gnssa-array": records.gnssa_array_report,
            "reproduction": records.reproduction_report,
        }[kind]
        return build(rec)
    except (KeyError, TypeError, IndexError, ValueError) as exc:
        raise DataError(f"{path}: a {kind} record with a missing or malformed field ({exc!r})") from None


def _drift_scenario(rec: dict) -> object | None:
    """The built-in drift scenario named in the record (obstacles, currents), if it still loads."""
    from oceanloc.config.drift import builtin_drift_scenarios, load_drift_scenario

    name = rec.get("scenario")
    if name not in builtin_drift_scenarios():
        return None
    return load_drift_scenario(name)
