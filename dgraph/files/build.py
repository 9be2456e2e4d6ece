"""Building the graph that a composition of files describes: the entities made, plugged, set
and checked, every refusal located at the file, line and key that wrote what is refused
(``load``, ``loads``, and ``check``, which collects the refused plugs instead)."""

from __future__ import annotations

import math
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from dgraph.errors import DGraphError, GraphError, GraphFileError, ParamError
from dgraph.files.composition import Composition, EntitySpec, Setting, compose, owner, split_settings, suggest
from dgraph.files.paths import ROBOT, check_data_file, from_file
from dgraph.files.source import At, latest, read_text
from dgraph.graph import Graph
from dgraph.params import Param
from dgraph.registry import get_type
from dgraph.signals.signal import Input

Refused = list[tuple[str, GraphFileError]]
"""The plugs a graph refused: each one's input and its error."""


def load(path: str | Path, overrides: dict[str, Any] | None = None) -> Graph:
    """Build the graph described by the file at ``path`` (and the files it extends).

    ``overrides`` maps ``entity.name`` to a value: a parameter (applied before the entity is
    built) or an input constant, as ``dgraph run --set`` does; they win over every file.
    """
    return loads(read_text(path), str(path), overrides)


def loads(text: str, file: str = "<string>", overrides: dict[str, Any] | None = None) -> Graph:
    """Build a graph from graph-file text (see :func:`load`)."""
    return _located_build(compose(text, file, overrides), file)


def check(path: str | Path) -> tuple[Graph, list[str]]:
    """Everything wrong with the graph file at ``path``, one line each, without running a tick:
    every plug the graph refuses (a structured type or a shape that does not fit, a loop), each
    located at its file and line, then what :meth:`Graph.problems` finds in the graph built from
    the rest (an input left unplugged by a refused plug is not listed again), with that graph.
    A mistake that stops the build (YAML, schema, an unknown type or parameter) raises
    :class:`GraphFileError`, as :func:`load` does.
    """
    refused: Refused = []
    file = str(path)
    graph = _located_build(compose(read_text(path), file), file, refused)
    return graph, [str(error) for _, error in refused] + graph.problems(reported={target for target, _ in refused})


def _located_build(composition: Composition, file: str, refused: Refused | None = None) -> Graph:
    """:func:`_build`, what the library (or a value no check foresaw) refuses without a place
    located at the file: :func:`load` and :func:`check` give the same error."""
    try:
        return _build(composition, file, refused)
    except GraphFileError:
        raise
    except DGraphError as exc:  # anything the library refused, located at the file level
        raise GraphFileError(str(exc), file=file, entity=exc.entity, signal=exc.signal) from exc
    except (ValueError, TypeError, OverflowError, MemoryError) as exc:  # a value no check foresaw
        raise GraphFileError(f"could not build the graph: {type(exc).__name__}: {exc}", file=file) from exc


def _build(composition: Composition, file: str, refused: Refused | None = None) -> Graph:
    """Make the entities, plug them, set the constants, check what is recorded. With a
    ``refused`` list, a refused plug is added to it (with its target) and the build goes on
    without it; otherwise it is raised."""
    entities = composition.declared()
    _check_settings(composition.sets, entities, file)
    params, constants = split_settings(composition.sets, entities)
    graph = _new_graph(composition, file)
    robot = composition.scalars.get("robot")
    if robot is not None:  # a name, or a path from the folder of the file that gives it
        robot = (from_file(robot[0], ROBOT, robot[1].doc), robot[1])
    for name, spec in entities.items():
        graph.add(_make_entity(name, spec, params.get(name, {}), robot))
    _plug(graph, composition, entities, refused)
    _set_constants(graph, constants, entities)
    _check_records(graph, composition, entities)
    for entity in graph:
        problems = entity.check()
        if problems:
            raise entities[entity.name].at.error("; ".join(problems))
    return graph


def _plug(graph: Graph, composition: Composition, entities: dict[str, EntitySpec], refused: Refused | None) -> None:
    for target, (source, at) in composition.plugs.items():
        try:
            graph.plug(source, target)
        except DGraphError as exc:
            error = _refusal(exc, at, (source, target), entities, hint=_did_you_mean(graph, (source, target)))
            if refused is None:
                raise error from None
            refused.append((target, error))


def _set_constants(graph: Graph, constants: dict[str, Setting], entities: dict[str, EntitySpec]) -> None:
    for key, (value, at) in constants.items():
        error = _set_constant(graph, key, value)
        if error:
            raise _refusal(error, at, (key,), entities, hint=_did_you_mean(graph, (key,), params=True))


def _check_records(graph: Graph, composition: Composition, entities: dict[str, EntitySpec]) -> None:
    for key, at in composition.records.items():
        try:
            graph.signal(key)
        except DGraphError as exc:
            raise _refusal(exc, at, (key,), entities, f"recorded signal {key!r}: ",
                           _did_you_mean(graph, (key,))) from None


def _refusal(exc: DGraphError, at: At, keys: Iterable[str], entities: dict[str, EntitySpec],
             prefix: str = "", hint: str = "") -> GraphFileError:
    """The error of a plug, setting or record that the graph refused, at its own place, or at
    the definition of an entity it names if a nearer file (re)defined that entity; ``hint``
    follows the refusal (``; did you mean 'x'?``)."""
    blame = latest(at, *(entities[owner(key)].at for key in keys if owner(key) in entities))
    note = "" if blame is at else f" (from {at.where()})"
    return blame.error(f"{prefix}{exc}{hint}{note}", exc)


def _did_you_mean(graph: Graph, keys: Iterable[str], params: bool = False) -> str:
    """``; did you mean 'x'?`` for the first of the ``entity.signal`` keys that names no entity
    of ``graph`` (the closest entity) or no signal of its entity (the closest signal, or
    parameter with ``params``, as a setting may name either); nothing if none is close."""
    for key in keys:
        name, _, signal = key.partition(".")
        if name not in graph:
            return suggest(name, graph.entities)
        entity = graph.entity(name)
        if signal not in entity.ports:
            return suggest(signal, [*entity.ports, *(entity._param_decls if params else ())])
    return ""


def _check_settings(settings: dict[str, Setting], entities: dict[str, EntitySpec], file: str) -> None:
    """Every setting names an entity of the graph."""
    for key, (_, at) in settings.items():
        entity, _, name = key.partition(".")
        if not name:
            raise at.error(f"{key!r} must read 'entity.name'")
        if entity not in entities:
            raise at.error(f"no entity {entity!r} in {file}{suggest(entity, entities)}")


def _new_graph(composition: Composition, file: str) -> Graph:
    """The empty graph with the chain's name, dt and duration."""
    top = At(composition.top, ())
    dt, dt_at = composition.scalars.get("dt", (0.001, top))
    name = composition.scalars.get("name", (Path(file).stem or "graph", top))[0]
    try:
        graph = Graph(dt=dt, name=name)
    except DGraphError as exc:
        raise dt_at.error(str(exc), exc) from None
    duration, at = composition.scalars.get("duration", (None, top))
    if duration is not None and not math.isfinite(duration):
        raise at.error(f"duration must be finite, got {duration!r}")
    graph.duration = duration
    return graph


def _make_entity(name: str, spec: EntitySpec, settings: dict[str, Setting], robot: Setting | None) -> Any:
    try:
        cls = get_type(spec.type)
    except DGraphError as exc:
        raise spec.where("type").error(str(exc), exc) from None
    params, blame = _params(name, spec, cls._param_decls, settings, robot)
    try:
        return cls(name, **params)
    except DGraphError as exc:
        raise blame.error(str(exc), exc) from None
    except Exception as exc:  # an entity constructor failing on odd values must not crash the loader
        raise blame.error(f"{name} ({spec.type}) could not be built: {type(exc).__name__}: {exc}") from exc


def _params(name: str, spec: EntitySpec, decls: dict[str, Param], settings: dict[str, Setting],
            robot: Setting | None) -> tuple[dict[str, Any], At]:
    """The entity's parameters: its definition's, over them the settings of the files and the
    command line, and the graph's robot as the ``model`` that none of them gives (a data file
    checked to be a regular file of a bounded size); and where a refusal of the constructor is
    reported (the nearest file that had a say)."""
    given = {key: (value, spec.where("params", key)) for key, value in spec.params.items()}
    for key, (_, at) in given.items():
        if key not in decls:
            raise at.error(f"{name} ({spec.type}): unknown parameter(s) {key}; known: "
                           f"{', '.join(decls) or 'none'}{suggest(key, decls)}", ParamError("", entity=name))
    extra = dict(settings)
    if robot is not None and "model" in decls and "model" not in given:
        extra.setdefault("model", robot)
    blame = spec.where("params")
    for key, (value, at) in extra.items():
        try:
            decls[key].convert(value, name)
        except DGraphError as exc:
            raise at.error(str(exc), exc) from None
        given[key] = (value, at)
        blame = latest(blame, at)
    params = {}
    for key, (value, at) in given.items():
        params[key] = from_file(value, decls.get(key), at.doc)
        check_data_file(params[key], decls.get(key), at)
    return params, blame


def _set_constant(graph: Graph, key: str, value: Any) -> DGraphError | None:
    """Set input ``key`` to ``value``; the refusal, if any (the caller locates it)."""
    try:
        sig = graph.signal(key)
        if not isinstance(sig, Input):
            return GraphError(f"{key} is an output: only inputs (and parameters, with --set) can be set",
                              entity=sig.entity.name, signal=sig.name)
        sig.set(value)
    except DGraphError as exc:
        return exc
    return None
