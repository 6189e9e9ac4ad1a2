import click
import pytest
import typer.main
from typer.testing import CliRunner

from oceanloc.cli.app import app, main


def _all_commands(cmd: click.Command, prefix: tuple[str, ...] = ()):
    # Typer's group class is not always a click.Group subclass: walk anything with sub-commands.
    yield prefix
    for name, sub in getattr(cmd, "commands", {}).items():
        yield from _all_commands(sub, (*prefix, name))


COMMANDS = list(_all_commands(typer.main.get_command(app)))


def test_crawl_sees_every_group():
    names = {" ".join(p) for p in COMMANDS}
    assert {"scenarios list", "reproduce", "simulate"} <= names
    assert len(COMMANDS) > 10


@pytest.mark.parametrize("path", COMMANDS, ids=[" ".join(p) or "oceanloc" for p in COMMANDS])
def test_every_command_has_help(path):
    result = CliRunner().invoke(app, [*path, "--help"])
    assert result.exit_code == 0, result.output
    assert "Usage" in result.output


def test_user_error_is_one_line_without_traceback(capsys):
    with pytest.raises(SystemExit) as info:
        main(["scenarios", "show", "no-such-scenario"])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "error:" in err and "Traceback" not in err


def test_the_command_line_starts_without_scipy_or_matplotlib():
    # Every `oceanloc` call (e.g. `survey add` during a survey) pays for what the app imports at start;
    # scipy and matplotlib add seconds and are imported by the commands that use them.
    import subprocess
    import sys

    code = (
        "import sys, oceanloc.cli.app; heavy = {'scipy', 'matplotlib', 'xarray', 'distributed'}; "
        "print(sorted({m.split('.')[0] for m in sys.modules} & heavy))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
