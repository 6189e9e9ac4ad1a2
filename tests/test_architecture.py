"""The one-way data flow of ``docs/architecture.md``, checked on the code's own imports.

Every module of a layer may import only from layers below it (and from its own subpackage). The layer list
here and the picture in the architecture page are kept the same by :func:`test_the_page_lists_every_layer`.
"""

from __future__ import annotations

import ast
from pathlib import Path

import oceanloc

PACKAGE = Path(oceanloc.__file__).parent
DOCS = PACKAGE.parents[1] / "docs" / "architecture.md"

LAYERS: tuple[tuple[str, ...], ...] = (
    ("_typing", "_version", "units", "errors", "_random", "_validate", "data"),
    ("geo",),
    ("models",),
    ("io",),
    ("estimation",),
    ("planning",),
    ("config",),
    ("sim",),
    ("field",),
    ("evaluation",),
    ("reproduce",),
    ("report",),
    ("cli",),
)
RANK = {name: i for i, names in enumerate(LAYERS) for name in names}


def _top(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if parts[0] == "oceanloc" and len(parts) > 1 else None


def _imports(path: Path) -> list[tuple[int, str]]:
    """``(line, module)`` of every absolute ``oceanloc.*`` import and every relative import, resolved."""
    rel = path.relative_to(PACKAGE.parent).with_suffix("")
    here = list(rel.parts[:-1])
    out = []
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = here[: len(here) - node.level + 1]
                out.append((node.lineno, ".".join([*base, *([node.module] if node.module else [])])))
            elif node.module:
                out.append((node.lineno, node.module))
    return out


def _layer_of(path: Path) -> str:
    rel = path.relative_to(PACKAGE)
    return rel.parts[0] if len(rel.parts) > 1 else rel.stem


def test_every_subpackage_has_a_layer():
    names = {_layer_of(p) for p in PACKAGE.rglob("*.py")} - {"__init__", "__main__"}
    assert names <= set(RANK), f"modules with no layer in docs/architecture.md: {sorted(names - set(RANK))}"


def test_no_module_imports_from_a_layer_above_it():
    violations = []
    for path in sorted(PACKAGE.rglob("*.py")):
        layer = _layer_of(path)
        if layer in ("__init__", "__main__"):
            continue
        for line, module in _imports(path):
            target = _top(module)
            if target is None or target == layer or target not in RANK:
                continue
            if RANK[target] > RANK[layer]:
                violations.append(f"{path.relative_to(PACKAGE)}:{line}: {layer} imports {module}")
    assert not violations, "imports against the flow:\n" + "\n".join(violations)


def test_the_page_lists_every_layer():
    text = DOCS.read_text()
    missing = [n for names in LAYERS[1:] for n in names if f"{n}/" not in text]
    assert not missing, f"docs/architecture.md does not describe {missing}"
