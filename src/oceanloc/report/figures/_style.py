"""Shared figure plumbing: object-oriented matplotlib (no pyplot state), PNG output."""

from __future__ import annotations

from pathlib import Path

from matplotlib.figure import Figure

from oceanloc.errors import ConfigError


def save_figure(fig: Figure, path: Path, *, dpi: int = 130) -> Path:
    """Write ``fig`` as PNG to ``path`` (creating folders); a ConfigError names an unwritable path."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=dpi, bbox_inches="tight")
    except OSError as exc:
        raise ConfigError(f"{path}: cannot write figure ({exc})") from None
    return path
