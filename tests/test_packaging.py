"""The distribution: every package folder is installed, the simulation part under its own name."""

import importlib.util
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _pyproject() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())


def test_every_package_folder_is_listed():
    setuptools = _pyproject()["tool"]["setuptools"]
    folders = {".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "dgraph").rglob("__init__.py")}
    listed = set(setuptools["packages"])
    assert folders - listed == set(), "package folders missing from pyproject's packages"
    assert listed - folders == {"dgraph_sim"}
    assert setuptools["package-dir"] == {"dgraph_sim": "sim"}


def test_the_simulation_part_is_imported_as_dgraph_sim():
    spec = importlib.util.find_spec("dgraph_sim")
    assert spec is not None and Path(spec.origin).parent == ROOT / "sim"
    entry_points = _pyproject()["project"]["entry-points"]["dgraph.entities"]
    assert all(not target.startswith("sim.") for target in entry_points.values())
