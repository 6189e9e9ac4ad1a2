"""Terminal tables (rich) for the transponder-survey commands."""

from __future__ import annotations

from collections.abc import Sequence

from rich.table import Table

from oceanloc.reproduce.garcia2019 import Check, TableRow


def reproduction_table(rows: Sequence[TableRow], title: str, rmse_label: str = "RMSEE (m)") -> Table:
    """Our Monte Carlo beside the paper's values, one row per (epoch, k)."""
    table = Table(title=title)
    for col in (
        "epoch",
        "k",
        f"{rmse_label} ours",
        "paper",
        "log det ours",
        "paper",
        "std ours",
        "paper",
        "z",
    ):
        table.add_column(col, justify="right")
    last_epoch = None
    for r in rows:
        table.add_row(
            f"n = {r.epoch}" if r.epoch != last_epoch else "",
            "0 (random)" if r.k == 0 else str(r.k),
            f"{r.rmse_m:.2f}",
            f"{r.paper_rmse_m:.2f}",
            f"{r.logdet_mean:.2f}",
            f"{r.paper_logdet_mean:.2f}",
            f"{r.logdet_std:.2f}",
            f"{r.paper_logdet_std:.2f}",
            f"{r.logdet_z:+.1f}",
            end_section=r is not rows[-1] and rows[rows.index(r) + 1].epoch != r.epoch,
        )
        last_epoch = r.epoch
    return table


def checks_table(checks: Sequence[Check], title: str = "Acceptance checks") -> Table:
    """Pass/fail lines of a reproduction."""
    table = Table(title=title)
    table.add_column("check")
    table.add_column("result")
    table.add_column("figures", justify="right")
    for c in checks:
        table.add_row(c.name, "[green]pass[/green]" if c.passed else "[red]FAIL[/red]", c.detail)
    return table
