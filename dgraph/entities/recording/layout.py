"""The Rerun blueprint of a recording: which views the viewer opens, and what each one shows.

A :class:`~dgraph.entities.recording.Recorder` sends one blueprint with its recording (its
``layout`` parameter): the robot's 3D view large on the left (when a ``RobotView`` draws into
the same recording), time-series panels on the right, and the ``faults`` text log under them.

The default panels group the recorded signals ``entity.signal`` by their names, first rule first:

1. **reference and measured, overlaid**: a signal whose entity or signal name is
   ``<K>_reference`` is a reference of the quantity ``K`` (``com_reference.output``,
   ``stabilizer.zmp_reference``; its derivatives, signals named ``velocity``, ``acceleration``
   or ``*_rate``, are not); a signal named ``K`` or ``K_*`` (``robot.com_position``, ``zmp.zmp``)
   is a measurement of ``K`` when ``K`` has a reference. One panel ``K`` per quantity.
2. **contact forces**: signal names containing ``force`` or ``wrench``, or starting with ``ft_``.
3. **torques**: ``tau``, or names containing ``torque``.
4. **solver status**: ``status``, ``*_status`` and ``iterations``.
5. **solve time**: ``solve_time``.
6. every other signal in a panel of its own.

A layout can also be given as a list of panels ``{title: ..., signals: [entity.signal, ...]}``
(recorded signals, overlaid in one time-series plot), or ``none`` (no blueprint: Rerun's own).
"""

from __future__ import annotations

import uuid
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from dgraph.errors import ParamError

LAYOUTS = ("default", "none")
"""The layouts named by a string; a list of panels is the other form."""
DERIVATIVES = ("velocity", "acceleration")
"""Signal names of a reference's derivatives, which are not overlaid with its value."""
CONTAINER_KINDS = {1: "tabs", 2: "horizontal", 3: "vertical", 4: "grid"}
"""Rerun's ``ContainerKind`` values, as stored in a blueprint."""
FAULTS_PATH = "/faults"
"""The entity path of the faults text log (see :meth:`RerunStream.send_faults`)."""


@dataclass(frozen=True)
class Panel:
    """A time-series plot: its title and the recorded signals (``entity.signal``) it overlays."""

    title: str
    signals: tuple[str, ...]


def signal_path(name: str) -> str:
    """The Rerun entity path of the recorded signal ``entity.signal``: ``/signals/entity/signal``."""
    return f"/signals/{name.replace('.', '/')}"


def parse_layout(value: Any, recorded: Sequence[str], entity: str) -> list[Panel] | str:
    """The layout parameter checked: ``"default"``, ``"none"``, or the panels of a list of
    ``{title, signals}`` mappings naming recorded signals. Raises :class:`ParamError` naming
    the panel and what is wrong with it."""
    where = f"{entity}: parameter 'layout'"
    if isinstance(value, str):
        if value not in LAYOUTS:
            raise ParamError(f"{where} must be 'default', 'none' or a list of panels {{title, signals}}, "
                             f"got {value!r}", entity=entity)
        return value
    if not isinstance(value, Sequence) or not value:
        raise ParamError(f"{where} must be 'default', 'none' or a non-empty list of panels {{title, signals}}, "
                         f"got {type(value).__name__}", entity=entity)
    panels = []
    for i, panel in enumerate(value):
        at = f"{where}: panel {i}"
        if not isinstance(panel, dict):
            raise ParamError(f"{at}: expected a mapping {{title, signals}}, got {type(panel).__name__}", entity=entity)
        unknown = sorted(set(panel) - {"title", "signals"})
        if unknown:
            raise ParamError(f"{at}: unknown key(s) {', '.join(map(str, unknown))}; a panel has title and signals",
                             entity=entity)
        title, signals = panel.get("title"), panel.get("signals")
        if not isinstance(title, str) or not title.strip():
            raise ParamError(f"{at}: title must be a non-empty string, got {title!r}", entity=entity)
        if isinstance(signals, str) or not isinstance(signals, Sequence) or not signals \
                or not all(isinstance(s, str) for s in signals):
            raise ParamError(f"{at} ({title}): signals must be a non-empty list of 'entity.signal' names, "
                             f"got {signals!r}", entity=entity)
        missing = [s for s in signals if s not in recorded]
        if missing:
            raise ParamError(f"{at} ({title}): {', '.join(map(repr, missing))} not recorded; recorded: "
                             f"{', '.join(recorded)}", entity=entity)
        panels.append(Panel(title, tuple(signals)))
    return panels


def _quantity_of_reference(name: str) -> str | None:
    """``K`` if ``entity.signal`` is a reference of the quantity ``K`` (rule 1), else ``None``."""
    entity, _, signal = name.partition(".")
    if signal.endswith("_reference"):
        return signal[: -len("_reference")] or None
    if entity.endswith("_reference") and signal not in DERIVATIVES and not signal.endswith("_rate"):
        return entity[: -len("_reference")] or None
    return None


def _category(signal: str) -> str | None:
    """The shared panel of a signal name under rules 2 to 5, else ``None``."""
    if "force" in signal or "wrench" in signal or signal.startswith("ft_"):
        return "contact forces"
    if signal == "tau" or "torque" in signal:
        return "torques"
    if signal in ("status", "iterations") or signal.endswith("_status"):
        return "solver status"
    if signal == "solve_time" or signal.endswith("_solve_time"):
        return "solve time"
    return None


def default_panels(recorded: Sequence[str]) -> list[Panel]:
    """The panels of the default layout for the recorded signals (see the module docstring)."""
    quantities: dict[str, list[str]] = {}
    for name in recorded:
        quantity = _quantity_of_reference(name)
        if quantity is not None:
            quantities.setdefault(quantity, []).append(name)
    placed = {name for names in quantities.values() for name in names}
    for name in recorded:
        signal = name.partition(".")[2]
        if name in placed:
            continue
        for quantity, names in quantities.items():
            if signal == quantity or signal.startswith(f"{quantity}_"):
                names.append(name)
                placed.add(name)
                break
    panels = [Panel(quantity, tuple(names)) for quantity, names in quantities.items()]
    shared: dict[str, list[str]] = {}
    alone = []
    for name in recorded:
        if name in placed:
            continue
        category = _category(name.partition(".")[2])
        if category is None:
            alone.append(Panel(name, (name,)))
        else:
            shared.setdefault(category, []).append(name)
    order = ("contact forces", "torques", "solver status", "solve time")
    panels += [Panel(category, tuple(shared[category])) for category in order if category in shared]
    return panels + alone


def blueprint(panels: Sequence[Panel], spatial_origins: Sequence[str], faults: bool = True) -> Any:
    """The Rerun blueprint: a 3D view per origin (the robot, 3/5 of the width), the panels as
    time-series plots in a grid beside it, the faults text log under them."""
    import rerun.blueprint as rrb

    plots: list[Any] = [rrb.TimeSeriesView(name=panel.title, origin="/signals",
                                           contents=[signal_path(s) for s in panel.signals])
                        for panel in panels]
    right: Any = rrb.Grid(*plots) if len(plots) > 1 else (plots[0] if plots else None)
    if faults:
        log = rrb.TextLogView(name="faults", origin=FAULTS_PATH)
        right = rrb.Vertical(right, log, row_shares=[5, 1]) if right is not None else log
    spaces = [rrb.Spatial3DView(name="robot" if origin == "/world" else origin.strip("/"), origin=origin)
              for origin in spatial_origins]
    if not spaces:
        root = right
    else:
        left = spaces[0] if len(spaces) == 1 else rrb.Vertical(*spaces)
        root = rrb.Horizontal(left, right, column_shares=[3, 2]) if right is not None else left
    return rrb.Blueprint(root)


def read_blueprint(rrd_path: str) -> dict[str, Any]:
    """The blueprint stored in an .rrd file (its blueprint store, the last value of each part):
    ``views`` (id -> ``{"kind", "name", "origin", "contents"}``, kind ``3D``, ``TimeSeries``,
    ``TextLog``...), ``containers`` (id -> ``{"kind", "contents", "col_shares", "row_shares"}``,
    kind ``tabs``, ``horizontal``, ``vertical`` or ``grid``, contents as ``view/<id>`` or
    ``container/<id>``) and ``root`` (the root container's ``container/<id>``, or ``None``).
    Empty if the file holds no blueprint."""
    import rerun.chunk as chunk

    reader = chunk.RrdReader(rrd_path)
    out: dict[str, Any] = {"views": {}, "containers": {}, "root": None}
    stores = reader.blueprints()
    if not stores:
        return out
    fields = {"ViewBlueprint:class_identifier": ("view", "kind"), "ViewBlueprint:display_name": ("view", "name"),
              "ViewBlueprint:space_origin": ("view", "origin"), "ViewContents:query": ("contents", "contents"),
              "ContainerBlueprint:container_kind": ("container", "kind"),
              "ContainerBlueprint:contents": ("container", "contents"),
              "ContainerBlueprint:col_shares": ("container", "col_shares"),
              "ContainerBlueprint:row_shares": ("container", "row_shares"),
              "ViewportBlueprint:root_container": ("viewport", "root")}
    for ch in reader.stream(store=stores[-1]):
        batch = ch.to_record_batch()
        parts = str(ch.entity_path).strip("/").split("/")
        for column, (what, key) in fields.items():
            if column not in batch.schema.names:
                continue
            values = [v for v in batch.column(column).to_pylist() if v is not None]
            if not values:
                continue
            value = values[-1]
            single = key in ("kind", "name", "origin", "root")
            value = value[0] if single and isinstance(value, list) else value
            if what == "view":
                out["views"].setdefault(parts[1], {})[key] = value
            elif what == "contents":
                out["views"].setdefault(parts[1], {})["contents"] = value
            elif what == "container":
                out["containers"].setdefault(parts[1], {})[key] = value
            else:
                out["root"] = value
    for container in out["containers"].values():
        if isinstance(container.get("kind"), int):
            container["kind"] = CONTAINER_KINDS.get(container["kind"], str(container["kind"]))
    if isinstance(out["root"], list):  # the UUID's 16 bytes
        out["root"] = f"container/{uuid.UUID(bytes=bytes(out['root']))}"
    return out
