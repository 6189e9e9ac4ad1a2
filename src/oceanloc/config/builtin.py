"""The scenario files shipped with oceanloc, one folder per kind (``scenarios/survey``, ``flock``, ``drift``).

Every loader resolves a name the same way: a path to a TOML file is read as is; otherwise the name must be
one of the built-in scenarios of that kind.
"""

from __future__ import annotations

from importlib import resources
from importlib.resources.abc import Traversable
from pathlib import Path
from typing import Literal

from oceanloc.config.toml_fields import Table, parse_toml, read_toml
from oceanloc.errors import ConfigError

ScenarioKind = Literal["survey", "flock", "drift"]


def builtin_folder(kind: ScenarioKind) -> Traversable:
    """The package folder holding the built-in scenarios of ``kind`` (and the data files they name)."""
    return resources.files("oceanloc.config.scenarios").joinpath(kind)


def builtin_names(kind: ScenarioKind) -> list[str]:
    """Names of the built-in scenarios of ``kind``, sorted."""
    return sorted(
        f.name.removesuffix(".toml") for f in builtin_folder(kind).iterdir() if f.name.endswith(".toml")
    )


def resolve_scenario(name_or_path: str | Path, kind: ScenarioKind) -> tuple[Table, Path | None]:
    """Parse a scenario file or a built-in scenario of ``kind``.

    Returns the root table and the folder of the file (``None`` for built-ins, whose data files are
    found through :func:`builtin_folder`).
    """
    root, folder, _ = read_scenario(name_or_path, kind)
    return root, folder


def read_scenario(name_or_path: str | Path, kind: ScenarioKind) -> tuple[Table, Path | None, str]:
    """:func:`resolve_scenario` plus the scenario's TOML text (for its hash in the provenance of records)."""
    path = Path(name_or_path)
    if path.suffix == ".toml" or path.exists():
        root = read_toml(path)
        return root, path.resolve().parent, path.read_text(encoding="utf-8")
    name = str(name_or_path)
    names = builtin_names(kind)
    if name not in names:
        raise ConfigError(
            f"'{name}' is neither a scenario file nor a built-in {kind} scenario "
            f"(built-in: {', '.join(names)})"
        )
    text = builtin_folder(kind).joinpath(f"{name}.toml").read_text(encoding="utf-8")
    return parse_toml(text, source=f"{name}.toml"), None, text
