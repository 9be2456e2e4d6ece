"""Writing a built graph back as a graph file: its entities, plugs and constants as plain data,
the robot named once, paths relative to the file's folder."""

from __future__ import annotations

from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from dgraph.errors import GraphError
from dgraph.files.paths import ROBOT, relative
from dgraph.graph import Graph


def to_plain(value: Any, where: str) -> Any:
    """Convert a parameter or constant to YAML-safe plain data (lists, numbers, strings)."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        return value.item()
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    if isinstance(value, (list, tuple)):
        return [to_plain(v, where) for v in value]
    if isinstance(value, dict) and all(isinstance(k, str) for k in value):
        return {k: to_plain(v, f"{where}.{k}") for k, v in value.items()}
    raise GraphError(f"{where}: a {type(value).__name__} cannot be written to a graph file")


def dumps(graph: Graph, folder: str | Path | None = None) -> str:
    """The graph-file text of ``graph``: the robot named once (``robot``, for every ``model``
    that is that robot), paths (``path``, ``name_or_path`` and ``path_list`` parameters, a
    ``robot`` that is a path) relative to ``folder`` (default: the working directory, where
    :func:`~dgraph.files.loads` without a file name looks for them)."""
    robot = _robot(graph)
    folder = Path(folder) if folder is not None else None
    data: dict[str, Any] = {"name": graph.name, "dt": graph.dt}
    if graph.duration is not None:
        data["duration"] = graph.duration
    if robot is not None:
        data["robot"] = relative(robot, ROBOT, folder)
    data["entities"] = {e.name: _saved_entity(e, robot, folder) for e in graph}
    data["plugs"] = [f"{a} -> {b}" for a, b in graph.plugs()]
    constants = {inp.full_name: to_plain(inp.value, inp.full_name)
                 for e in graph for inp in e.inputs.values() if inp.is_set}
    if constants:
        data["set"] = constants
    return yaml.safe_dump(data, sort_keys=False, default_flow_style=None, width=100)


def save(graph: Graph, path: str | Path) -> None:
    """Write ``graph`` to ``path`` as a graph file (paths relative to the file's folder)."""
    Path(path).write_text(dumps(graph, Path(path).parent))


def _robot(graph: Graph) -> str | None:
    """The robot most entities give as their ``model`` (None if none names one)."""
    names = Counter(e.given_params["model"] for e in graph if isinstance(e.given_params.get("model"), str))
    return names.most_common(1)[0][0] if names else None


def _saved_entity(entity: Any, robot: str | None, folder: Path | None) -> dict[str, Any]:
    """An entity's type and given parameters, as a file with ``robot`` must say them."""
    decls = type(entity)._param_decls
    params = {key: to_plain(relative(value, decls[key], folder), f"{entity.name}.{key}")
              for key, value in entity.given_params.items() if not (key == "model" and _is(value, robot))}
    model = decls.get("model")
    if robot is not None and model is not None and "model" not in entity.given_params and model.default != robot:
        params["model"] = to_plain(model.default, f"{entity.name}.model")  # not the robot it would get
    spec: dict[str, Any] = {"type": entity.type_name}
    if params:
        spec["params"] = params
    return spec


def _is(value: Any, robot: str | None) -> bool:
    """``value`` names ``robot`` (a model may be a ``pinocchio.Model``, not comparable to text)."""
    return isinstance(value, str) and value == robot
