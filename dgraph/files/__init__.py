"""Graph files: YAML descriptions of graphs, composed from one another, loaded safely and
written back identically.

A graph file::

    name: pd_double_integrator
    dt: 0.001
    entities:
      robot: {type: KinematicDevice, params: {control_mode: acceleration, size: 1}}
      kp:    {type: Gain, params: {size: 1}}
    plugs:
      - robot.q -> kp.input
    set:
      kp.gain: 25.0
    record: [robot.q]          # shorthand for a Recorder entity named "recorder"

``set`` names input constants and parameters alike (``entity.name: value``, as
``dgraph run --set``). ``robot: talos`` gives its model to every entity with a ``model``
parameter that does not set its own; ``robot: arm.urdf``, a path, is taken from the file's
folder, as every path a file gives (``path``, ``name_or_path`` and ``path_list`` parameters:
``mjcf``, a ``model`` that is a URDF path, ``package_dirs``).

A file can build on another: ``extends`` (a path relative to the file, or a list of them, each
one's chain applied in order and every file once, at its first place; at most ``MAX_EXTENDS``
distinct files, no cycles) applies the file, in this order, to the graph the bases describe::

    extends: base/talos.yaml
    name: talos_sway           # name, dt, duration, robot: the nearest file's
    remove:                    # what the base has and this graph does not
      entities: [view]         # with every plug, setting and record that names them
      plugs: [device.q -> view.q]          # or only the input: [view.q]
      set: [waist_task.kd]
      record: [com.error]
    entities:                  # new, or replacing the base's entity of that name (in its place;
      com_reference: {type: Sinusoid, params: {frequency: 0.5}}   # its plugs, settings, records stay)
    set:                       # merged: replaces the base's setting, or its plug, of that input
      com_task.kp: 30.0
    plugs:                     # appended; a plug into an input the base plugs replaces that plug
      - com_reference.velocity -> com.reference_velocity
    record: [com_reference.velocity]       # appended

``overrides`` is the older name of ``set`` in such a file. ``--set`` on the command line is
applied last, over every file (its texts read by ``command_line_settings``, whose errors name
the option).

Safety: the YAML is composed with the safe loader and converted node by node; only plain
scalars, lists and mappings are accepted (no tags, anchors, aliases or merge keys), so a file
can never construct objects or run code. Entity types come only from the registry. Every
error is a :class:`~dgraph.errors.GraphFileError` carrying the file, line and key of the file
that wrote what is wrong.

Bounds: only regular files are read (a FIFO, a device, a directory, a socket or a ``/proc``
file of size 0 is refused, named by ``extends`` or by a ``path`` parameter alike); a graph file
is at most ``MAX_BYTES``, ``MAX_DEPTH`` levels of lists and mappings deep and ``MAX_NODES``
values, a data file at most ``MAX_DATA_BYTES``, so loading a file always ends, soon.

The package, one concept a module: :mod:`~dgraph.files.source` (the text read safely, YAML
converted to plain data with its line map, the places errors point at),
:mod:`~dgraph.files.schema` (what one file may say), :mod:`~dgraph.files.composition` (a chain
of files laid over one another; ``parse``), :mod:`~dgraph.files.build` (the graph built from
a composition; ``load``, ``loads``, ``check``), :mod:`~dgraph.files.paths` (paths in
parameters from and to a file's folder) and :mod:`~dgraph.files.writing` (``dumps``, ``save``).
"""

from dgraph.files.build import check, load, loads
from dgraph.files.composition import (
    MAX_EXTENDS,
    RECORDER_NAME,
    SCALARS,
    command_line_settings,
    command_line_value,
    declared_entities,
    parse,
)
from dgraph.files.paths import MAX_DATA_BYTES
from dgraph.files.schema import NAME_RE, PLUG_PATTERN, PLUG_RE, SCHEMA, SIGNAL_RE, UNPLUG_PATTERN
from dgraph.files.source import COMMAND_LINE, MAX_BYTES, MAX_DEPTH, MAX_NODES, MAX_NUMBER_CHARS, read_text
from dgraph.files.writing import dumps, save, to_plain

__all__ = ["COMMAND_LINE", "MAX_BYTES", "MAX_DATA_BYTES", "MAX_DEPTH", "MAX_EXTENDS", "MAX_NODES", "MAX_NUMBER_CHARS",
           "NAME_RE", "PLUG_PATTERN", "PLUG_RE", "RECORDER_NAME", "SCALARS", "SCHEMA", "SIGNAL_RE", "UNPLUG_PATTERN",
           "check", "command_line_settings", "command_line_value", "declared_entities", "dumps", "load", "loads",
           "parse", "read_text", "save", "to_plain"]
