"""The public API: ``import oceanloc`` is fast and exposes the main entry points; every package says what
it holds; the package ships its ``py.typed`` marker."""

from __future__ import annotations

import importlib
import os
import pkgutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

import oceanloc

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = Path(oceanloc.__file__).resolve().parent


def test_every_public_name_resolves() -> None:
    missing = [name for name in oceanloc.__all__ if getattr(oceanloc, name, None) is None]
    assert missing == []
    assert len(oceanloc.__all__) == len(set(oceanloc.__all__))
    assert oceanloc.__all__ == sorted(oceanloc.__all__, key=lambda n: (n[0].islower(), n))


def test_public_names_are_the_library_objects() -> None:
    from oceanloc.estimation.map_gauss_newton import solve_map
    from oceanloc.planning.drift_rrt.planner import make_planner

    assert oceanloc.solve_map is solve_map
    assert oceanloc.make_drift_planner is make_planner
    assert set(oceanloc.__all__) <= set(dir(oceanloc))


def test_unknown_attribute_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="module 'oceanloc' has no attribute 'no_such_name'"):
        _ = oceanloc.no_such_name


def test_import_oceanloc_loads_no_numerical_stack() -> None:
    # The entry points load on first use (PEP 562 __getattr__): a bare import pulls in neither numpy nor
    # any subpackage, so `import oceanloc` and `oceanloc --version` stay fast.
    code = (
        "import sys, oceanloc; print(sorted(m for m in sys.modules if m.startswith(('numpy', 'oceanloc.'))))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=os.environ, check=True
    )
    assert out.stdout.strip() == "[]"


def test_every_package_has_a_docstring() -> None:
    packages = ["oceanloc"] + [
        info.name for info in pkgutil.walk_packages([str(PACKAGE)], prefix="oceanloc.") if info.ispkg
    ]
    assert "oceanloc.planning.drift_rrt" in packages
    undocumented = [name for name in packages if not (importlib.import_module(name).__doc__ or "").strip()]
    assert undocumented == []


def test_py_typed_ships_with_the_package() -> None:
    assert (PACKAGE / "py.typed").is_file()
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert "py.typed" in config["tool"]["setuptools"]["package-data"]["oceanloc"]
