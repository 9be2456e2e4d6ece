"""The maths layer imports no entity and no graph core, and the core never imports it."""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / "dgraph"
LAYER = PACKAGE / "control"
THIRD_PARTY = {"numpy", "scipy", "proxsuite"}
DGRAPH_ALLOWED = ("dgraph.control", "dgraph.signals.value_types")


def imported_modules(path: Path) -> list[str]:
    """Every module ``path`` imports, relative imports resolved to absolute names."""
    package = list(path.relative_to(PACKAGE.parent).parts[:-1])
    modules = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            modules += [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = package[:len(package) - node.level + 1] if node.level else []
            modules.append(".".join([*base, *([node.module] if node.module else [])]))
    return modules


@pytest.mark.parametrize("path", sorted(LAYER.rglob("*.py")), ids=lambda p: str(p.relative_to(PACKAGE)))
def test_the_layer_imports_numpy_scipy_proxsuite_the_value_types_and_itself_only(path):
    for module in imported_modules(path):
        top = module.split(".")[0]
        if top == "dgraph":
            assert module.startswith(DGRAPH_ALLOWED), f"{path.name} imports {module}"
        else:
            assert top in THIRD_PARTY or top in sys.stdlib_module_names, f"{path.name} imports {module}"


def test_the_core_never_imports_the_layer():
    """The core: every module of the package outside the entity families and the layer."""
    core = [p for p in PACKAGE.rglob("*.py") if p.relative_to(PACKAGE).parts[0] not in ("entities", "control")]
    assert PACKAGE / "graph.py" in core and PACKAGE / "signals" / "signal.py" in core
    for path in core:
        assert not [m for m in imported_modules(path) if m.startswith("dgraph.control")], path
