"""Every scenario kind in one place: list the built-in scenarios and load one by name or file.

The kind of a file is told by its tables: ``[[transponders]]`` (survey), ``[nodes]`` (flock) or
``[currents]`` (drift).
"""

from __future__ import annotations

from pathlib import Path

from oceanloc.config.builtin import ScenarioKind, builtin_names
from oceanloc.config.drift import DriftScenario, load_drift_scenario
from oceanloc.config.flock import FlockScenario, load_flock_scenario
from oceanloc.config.survey import SurveyScenario, load_survey_scenario
from oceanloc.config.toml_fields import read_toml
from oceanloc.errors import ConfigError

AnyScenario = SurveyScenario | FlockScenario | DriftScenario
SCENARIO_KINDS: tuple[ScenarioKind, ...] = ("survey", "flock", "drift")
_LOADERS = {"survey": load_survey_scenario, "flock": load_flock_scenario, "drift": load_drift_scenario}
_MARKERS = {"transponders": "survey", "nodes": "flock", "currents": "drift"}


def builtin_scenarios() -> list[AnyScenario]:
    """Every built-in scenario, survey first, then flock, then drift, each kind sorted by name."""
    return [_LOADERS[kind](name) for kind in SCENARIO_KINDS for name in builtin_names(kind)]


def load_scenario(name_or_path: str | Path) -> AnyScenario:
    """A built-in scenario of any kind by name, or a scenario TOML file of any kind by path."""
    path = Path(name_or_path)
    if path.suffix == ".toml" or path.exists():
        root = read_toml(path)
        kinds = [kind for marker, kind in _MARKERS.items() if root.has(marker)]
        if len(kinds) != 1:
            raise ConfigError(
                f"{path}: cannot tell the scenario kind (a survey has [[transponders]], a flock [nodes], "
                "a drift scenario [currents])"
            )
        return _LOADERS[kinds[0]](path)
    for kind in SCENARIO_KINDS:
        if str(name_or_path) in builtin_names(kind):
            return _LOADERS[kind](str(name_or_path))
    names = [n for kind in SCENARIO_KINDS for n in builtin_names(kind)]
    raise ConfigError(
        f"'{name_or_path}' is neither a scenario file nor a built-in scenario (built-in: {', '.join(names)})"
    )
