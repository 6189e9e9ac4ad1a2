"""The README's commands exist as printed, and its links to docs/ resolve.

Every ``$ oceanloc ...`` line of the README's walk-through is checked against the command tree: each
command and subcommand exists and each ``--option`` it uses is one that command accepts. (Running them is
the walk-through itself; their library functions are tested where they live.)
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest
import typer

from oceanloc.cli.app import app

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def readme_commands() -> list[str]:
    """The ``$ oceanloc ...`` lines of the README's code blocks, continuation lines joined."""
    text = README.replace("\\\n", " ")
    return [m.group(1) for m in re.finditer(r"^\$ oceanloc (.+)$", text, flags=re.MULTILINE)]


def test_the_walk_through_shows_commands() -> None:
    commands = readme_commands()
    assert len(commands) >= 15
    for group in ("demo", "simulate", "reproduce", "dop", "drift-plan", "localize", "survey", "replay"):
        assert any(c.split()[0] == group for c in commands), group


@pytest.mark.parametrize("line", readme_commands())
def test_readme_command_exists_with_its_options(line: str) -> None:
    command = typer.main.get_command(app)
    words = shlex.split(line)
    while words and hasattr(command, "commands") and words[0] in command.commands:
        command = command.commands[words.pop(0)]
    assert not hasattr(command, "commands"), f"'{line}' names a group, not a command"
    accepted = {opt for param in command.params for opt in param.opts}
    unknown = [w for w in words if w.startswith("--") and w.split("=")[0] not in accepted]
    assert unknown == [], f"'oceanloc {line}': unknown options {unknown}"


def test_readme_links_resolve() -> None:
    links = re.findall(r"\]\(((?:docs|examples)/[^)#]+)", README)
    assert {"docs/garcia2019.md", "docs/dillard-aquaquad.md", "docs/architecture.md"} <= set(links)
    missing = [link for link in links if not (ROOT / link).is_file()]
    assert missing == []


def test_docs_pages_link_to_existing_pages() -> None:
    for page in (ROOT / "docs").glob("*.md"):
        for link in re.findall(r"\]\(([a-z0-9-]+\.md)", page.read_text()):
            assert (page.parent / link).is_file(), f"{page.name} links to missing {link}"
