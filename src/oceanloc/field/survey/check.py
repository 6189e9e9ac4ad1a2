"""Check a survey journal: every page readable, every stored record valid; optionally remove the invalid ones.

This version never writes an out-of-range record (:mod:`.journal` checks each on the way in),
but a journal written by an older version or edited by hand may hold one; the commands reading the
journal skip it and say so, and :func:`check_journal` lists it (table, time, problem) and, asked to,
deletes every such record in one transaction, leaving every valid record as it was.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from oceanloc.field.survey.journal import InvalidRecord, Journal


@dataclass(frozen=True, slots=True, kw_only=True)
class JournalCheck:
    """What ``survey check`` found.

    Attributes
    ----------
    path : str
        The journal.
    damaged : tuple of str
        SQLite ``quick_check`` findings (empty when every page is readable).
    invalid : tuple of InvalidRecord
        Stored records failing the checks on the way in (before any removal).
    removed : int
        Invalid records deleted (0 unless removal was asked for).
    """

    path: str
    damaged: tuple[str, ...]
    invalid: tuple[InvalidRecord, ...]
    removed: int = 0

    @property
    def clean(self) -> bool:
        """True when nothing is damaged and no invalid record is left in the journal."""
        return not self.damaged and len(self.invalid) == self.removed

    def lines(self) -> list[str]:
        """One plain line per finding: ``table t=...: problem``, then what was removed."""
        out = [f"damaged: {d}" for d in self.damaged]
        out += [f"{r.table} t={r.values[0]!r}: {r.problem}" for r in self.invalid]
        return out

    def to_record(self) -> dict:
        return {
            "path": self.path,
            "damaged": list(self.damaged),
            "invalid": [
                {"table": r.table, "rowid": r.rowid, "t": str(r.values[0]), "problem": r.problem}
                for r in self.invalid
            ],
            "removed": self.removed,
            "clean": self.clean,
        }


def check_journal(path: str | Path, *, remove_invalid: bool = False) -> JournalCheck:
    """Check a started journal (pages and records); with ``remove_invalid`` delete the invalid records.

    Raises
    ------
    DataError
        If the file is not a started journal, or (removal only) cannot be written.
    """
    with Journal.open(path) as j:
        pages = [r.split(": damaged: ", 1)[1] for r in j.check() if ": damaged: " in r]
        invalid = tuple(j.invalid_records())
        removed = len(j.remove_invalid()) if remove_invalid and invalid else 0
    return JournalCheck(path=str(path), damaged=tuple(pages), invalid=invalid, removed=removed)


def journal_invalid_records(path: str | Path) -> tuple[InvalidRecord, ...]:
    """The invalid stored records of a started journal (what the reading commands skip)."""
    with Journal.open(path) as j:
        return tuple(j.invalid_records())
