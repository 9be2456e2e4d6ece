"""The Rerun blueprint of a recording: which views the viewer opens, and what each one shows.

A :class:`~dgraph.entities.recording.Recorder` sends one blueprint with its recording (its
``layout`` parameter): the robot's 3D view large on the left (when a ``RobotView`` draws into
the same recording), time-series panels on the right, and the ``faults`` text log under them.

Given the graph's entities, a ``WalkingView`` drawing into the recording adds a 3D view of its
entities alone, seen from above (``<name> (top view)``, under the robot's view;
:func:`walking_top_views`): its footprints, support polygon and points are also in the robot's
view (they are under ``/world``), but there the robot's feet hide the ZMP, which lies under a
stance sole; from above, without the meshes, one sees the ZMP move inside the support polygon.

The default panels group the recorded signals ``entity.signal`` by their names, first rule first:

0. **planned and measured, of a walk** (given the graph's entities): for each ``WalkingView``,
   the panel ``ZMP x/y: planned vs measured`` overlays the recorded signals plugged into its
   ``zmp_reference`` (the pattern generator's ``zmp``) and ``zmp_measured`` (a ZmpEstimator's
   ``zmp``) inputs, when both are recorded, and ``CoM x/y: planned vs measured`` those plugged
   into ``com_reference`` and ``com_measured``; x and y only (z is the ground's height for the
   ZMP, the nearly constant CoM height for the CoM), named ``planned x``, ``measured y``... in
   the legend. A signal shown there gets no panel of its own under rule 6.
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
from collections.abc import Iterable, Sequence
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
class Series:
    """How a signal's components are drawn in a panel: their names in the legend and whether
    each one is shown."""

    names: tuple[str, ...]
    visible: tuple[bool, ...]


@dataclass(frozen=True)
class Panel:
    """A time-series plot: its title, the recorded signals (``entity.signal``) it overlays and,
    if given, how each one's components are drawn (default: all, named as recorded)."""

    title: str
    signals: tuple[str, ...]
    series: tuple[Series, ...] = ()


@dataclass(frozen=True)
class TopView:
    """A 3D view of the entities under ``origin``, its eye ``eye_distance`` (m) above
    ``look_target`` (the viewer's default eye if ``look_target`` is None)."""

    name: str
    origin: str
    look_target: tuple[float, ...] | None = None
    eye_distance: float = 0.0


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


PLANNED_VS_MEASURED = (("ZMP", "zmp_reference", "zmp_measured"), ("CoM", "com_reference", "com_measured"))
"""The panels of rule 0: the quantity, a WalkingView's input of the plan and of the measure."""
TOP_VIEW_DISTANCE = 1.5
"""The top view's eye height over the footprints' largest horizontal extent (it sees them all
with a field of view of 2 atan(1 / 3) = 37 degrees or more)."""
TOP_VIEW_MIN_DISTANCE = 1.0
"""The top view's lowest eye height (m), for a walk of a step or two."""
TOP_VIEW_TILT = 0.1
"""How far the top view's eye is behind the look target (along -x), per metre of height: the
view looks down with the walk's heading (+x) up, without the degenerate straight-down eye."""


def walking_panels(entities: Iterable[Any], recorded: Sequence[str]) -> list[Panel]:
    """The panels of rule 0 (see the module docstring) for the ``WalkingView`` entities among
    ``entities``, each panel once."""
    panels: list[Panel] = []
    for entity in entities:
        if entity.type_name != "WalkingView":
            continue
        for quantity, planned, measured in PLANNED_VS_MEASURED:
            sources = [entity.inputs[name].source for name in (planned, measured)]
            names = tuple(source.full_name for source in sources if source is not None)
            if len(names) == 2 and all(name in recorded for name in names) \
                    and all(panel.signals != names for panel in panels):
                series = tuple(Series((f"{role} x", f"{role} y", f"{role} z"), (True, True, False))
                               for role in ("planned", "measured"))
                panels.append(Panel(f"{quantity} x/y: planned vs measured", names, series))
    return panels


def walking_top_views(entities: Iterable[Any], stream: object) -> list[TopView]:
    """A :class:`TopView` of each ``WalkingView`` among ``entities`` that draws into ``stream``:
    origin its path, looking at the centre of its footprints from ``TOP_VIEW_DISTANCE`` times
    their largest horizontal extent above (at least ``TOP_VIEW_MIN_DISTANCE``)."""
    views = []
    for entity in entities:
        if entity.type_name != "WalkingView" or stream is None or entity.stream is not stream:
            continue
        bounds = entity.footprint_bounds()
        if bounds is None:
            views.append(TopView(f"{entity.name} (top view)", f"/{entity.path}"))
            continue
        extent = float(max(bounds[1, :2] - bounds[0, :2]))
        target = tuple(float(x) for x in bounds.mean(axis=0))
        views.append(TopView(f"{entity.name} (top view)", f"/{entity.path}", target,
                             max(TOP_VIEW_DISTANCE * extent, TOP_VIEW_MIN_DISTANCE)))
    return views


def default_panels(recorded: Sequence[str], entities: Iterable[Any] = ()) -> list[Panel]:
    """The panels of the default layout for the recorded signals of a graph whose entities are
    ``entities`` (see the module docstring; rule 0 needs them)."""
    walking = walking_panels(entities, recorded)
    shown = {name for panel in walking for name in panel.signals}
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
            if name not in shown:
                alone.append(Panel(name, (name,)))
        else:
            shared.setdefault(category, []).append(name)
    order = ("contact forces", "torques", "solver status", "solve time")
    panels += [Panel(category, tuple(shared[category])) for category in order if category in shared]
    return walking + panels + alone


def blueprint(panels: Sequence[Panel], spatial_origins: Sequence[str], faults: bool = True,
              top_views: Sequence[TopView] = ()) -> Any:
    """The Rerun blueprint: a 3D view per origin (the robot, 3/5 of the width), under them the
    top views, the panels as time-series plots in a grid beside them, the faults text log under
    the plots."""
    import rerun.blueprint as rrb

    plots: list[Any] = [_time_series_view(panel) for panel in panels]
    right: Any = rrb.Grid(*plots) if len(plots) > 1 else (plots[0] if plots else None)
    if faults:
        log = rrb.TextLogView(name="faults", origin=FAULTS_PATH)
        right = rrb.Vertical(right, log, row_shares=[5, 1]) if right is not None else log
    spaces = [rrb.Spatial3DView(name="robot" if origin == "/world" else origin.strip("/"), origin=origin)
              for origin in spatial_origins]
    spaces += [_top_view(view) for view in top_views]
    if not spaces:
        root = right
    else:
        left = spaces[0] if len(spaces) == 1 else rrb.Vertical(*spaces)
        root = rrb.Horizontal(left, right, column_shares=[3, 2]) if right is not None else left
    return rrb.Blueprint(root)


def _time_series_view(panel: Panel) -> Any:
    """The time-series plot of ``panel``, its series drawn as the panel says (an override of
    each signal's ``SeriesLines``)."""
    import rerun as rr
    import rerun.blueprint as rrb

    overrides = {signal_path(signal): rr.SeriesLines(names=series.names, visible_series=series.visible).visualizer()
                 for signal, series in zip(panel.signals, panel.series, strict=False)}
    return rrb.TimeSeriesView(name=panel.title, origin="/signals", contents=[signal_path(s) for s in panel.signals],
                              overrides=overrides or None)


def _top_view(view: TopView) -> Any:
    """The 3D view of ``view``: its eye above the look target, slightly behind it, z up."""
    import rerun.blueprint as rrb

    eye = None
    if view.look_target is not None:
        x, y, z = view.look_target
        height = view.eye_distance
        eye = rrb.EyeControls3D(position=[x - TOP_VIEW_TILT * height, y, z + height], look_target=[x, y, z],
                                eye_up=[0.0, 0.0, 1.0])
    return rrb.Spatial3DView(name=view.name, origin=view.origin, eye_controls=eye)


def read_blueprint(rrd_path: str) -> dict[str, Any]:
    """The blueprint stored in an .rrd file (its blueprint store, the last value of each part):
    ``views`` (id -> ``{"kind", "name", "origin", "contents"}``, kind ``3D``, ``TimeSeries``,
    ``TextLog``..., and if set ``eye``, a 3D view's ``{"position", "look_target", "eye_up"}``, and
    ``overrides``, entity path -> component -> values, e.g. ``{"names": [...]}``), ``containers``
    (id -> ``{"kind", "contents", "col_shares", "row_shares"}``, kind ``tabs``, ``horizontal``,
    ``vertical`` or ``grid``, contents as ``view/<id>`` or ``container/<id>``) and ``root`` (the
    root container's ``container/<id>``, or ``None``).
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
        _read_view_properties(parts, batch, out["views"])
    for container in out["containers"].values():
        if isinstance(container.get("kind"), int):
            container["kind"] = CONTAINER_KINDS.get(container["kind"], str(container["kind"]))
    if isinstance(out["root"], list):  # the UUID's 16 bytes
        out["root"] = f"container/{uuid.UUID(bytes=bytes(out['root']))}"
    return out


def _read_view_properties(parts: list[str], batch: Any, views: dict[str, Any]) -> None:
    """Into ``views``, from the blueprint chunk of the entity path ``parts``: a 3D view's eye
    (one value per component), or the components a view overrides for an entity (their values)."""
    if len(parts) < 3 or parts[0] != "view":
        return
    if parts[2] == "EyeControls3D":
        properties, single = views.setdefault(parts[1], {}).setdefault("eye", {}), True
    elif "overrides" in parts and parts[-2] == "visualizers":  # .../overrides/<entity>/visualizers/<id>
        path = "/" + "/".join(parts[parts.index("overrides") + 1: -2])
        properties = views.setdefault(parts[1], {}).setdefault("overrides", {}).setdefault(path, {})
        single = False
    else:
        return
    for column in batch.schema.names:
        archetype, _, component = column.partition(":")
        if not component or archetype == "VisualizerInstruction":
            continue
        values = [v for v in batch.column(column).to_pylist() if v is not None]
        if values:
            properties[component] = values[-1][0] if single else values[-1]
