"""The ``dgraph`` command: run, check and draw graph files, list entity types.

    dgraph run FILE [--duration S | --ticks N] [--set entity.name=value ...]
                    [--save PATH | --serve | --spawn | --no-rerun]
                    [--bind ADDRESS] [--port PORT] [--web-viewer-port PORT] [--keep-serving]
                    [--npz PATH] [--video PATH] [-q] [--debug-checks]
    dgraph check FILE
    dgraph profile FILE [--duration S | --ticks N] [--set entity.name=value ...]
    dgraph show FILE --format dot|mermaid [--signals] [-o OUT]
    dgraph sweep FILE [FILE ...] [--set entity.name=value ...] [--grid KEY=V1,V2,... ...]
                 [--bisect KEY=LOW:HIGH [--tolerance R]] [--duration S] [--fall-signal SIGNAL|none]
                 [--measure SIGNAL ...] [--workers N] [--ray [ADDRESS]] [--timeout S]
                 [--out CSV] [--plot PNG | --no-plot] [--resume | --fresh] [-q]
    dgraph entities [TYPE]
    dgraph identify RECORDING [--payload-recording P --payload-mass KG --payload-arm M | --drive-gain NM_PER_A]
                    [--time C] [--position C] [--velocity C] [--current C] [--torque C] [--joint J]
                    [--cutoff HZ] [--order N] [--decimation N] [--min-velocity RAD_S] [--yaml OUT]
    dgraph --version

``python -m dgraph ...`` is the same command. The Rerun sink options are those of Rerun's own
scripts (``--save``, ``--serve``; ``--spawn`` opens a viewer) and its server's (``--bind``,
``--port`` for gRPC, ``--web-viewer-port``); without one, ``run`` saves ``out/NAME.rrd`` unless
the file chooses its recorders' sinks. Output piped into a command that stops reading
(``dgraph entities | head -1``) ends the command quietly, with status 0. SIGTERM and SIGHUP
(``kill``, ``timeout``, systemd, a closed terminal) end it as Ctrl-C does: a run stops after its
tick, what it recorded is closed, its Rerun servers stop, and the status is 128 + the signal's number.

Values given to ``--set`` are parsed as YAML scalars or flow lists (``1.5``, ``[0, 0.05, 0]``,
``true``), with the same safe loader as graph files. Errors print one line naming the file,
line, entity and signal, and exit with status 2.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import select
import signal
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

from dgraph.errors import DGraphError, GraphError, GraphFileError

if TYPE_CHECKING:
    from dgraph.graph import Graph

EXIT_ERROR = 2
PROFILE_TICKS = 1000  # what `profile` times when neither the command line nor the file gives a length
TERMINATIONS = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name))
"""The signals that end a command as Ctrl-C does (:func:`terminations_as_ctrl_c`)."""


def version() -> str:
    """The installed version of dgraph (its package metadata), else ``dgraph.__version__``."""
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as installed

    try:
        return installed("dgraph")
    except PackageNotFoundError:
        import dgraph

        return str(getattr(dgraph, "__version__", "unknown"))


def _recorder_names(path: str, types: tuple[str, ...] = ("Recorder",)) -> tuple[list[str], str]:
    """The entities of the given types (recorders) a graph file declares, and its file-safe name."""
    from dgraph.entities.recording.rerun_stream import safe_file_stem
    from dgraph.files import declared_entities, parse, read_text

    data = parse(read_text(path), path)
    names = [n for n, spec in declared_entities(data).items() if spec["type"] in types]
    return names, safe_file_stem(data.get("name", Path(path).stem))


def _sink(args: argparse.Namespace) -> str | None:
    """The Rerun sink chosen on the command line, or ``None`` (the file's, else ``save``)."""
    if args.save is not None:
        return "save"
    return "serve" if args.serve else "spawn" if args.spawn else "off" if args.no_rerun else None


def _suffixed(path: str, name: str, names: list[str]) -> str:
    """``path`` for the entity ``name``: as given if it is the only one, else with ``_name`` added
    to its stem (two recorders, or two devices, never write one file)."""
    return path if len(names) == 1 else str(Path(path).with_stem(Path(path).stem + f"_{name}"))


def _recorder_overrides(path: str, args: argparse.Namespace) -> dict[str, Any]:
    """Point every recorder and robot view of the file at the sink chosen on the command line, and
    every MuJoCo device at ``--video`` (what the command line does not say is left as the file says)."""
    names, _ = _recorder_names(path)
    mode = _sink(args)
    out: dict[str, Any] = {}
    for name in names:
        if mode is not None:
            out[f"{name}.rerun"] = mode
            if mode == "save":
                out[f"{name}.rrd_path"] = _suffixed(args.save, name, names)
        if args.npz:
            out[f"{name}.npz_path"] = _suffixed(args.npz, name, names)
    if mode is not None:  # robot views draw into the (first) recorder's recording
        for view in _recorder_names(path, ("RobotView",))[0]:
            out[f"{view}.rerun"] = mode
            if mode == "save":
                out[f"{view}.rrd_path"] = out[f"{names[0]}.rrd_path"] if names else args.save
    if args.video:
        devices = _recorder_names(path, ("MujocoDevice",))[0]
        if not devices:
            raise GraphFileError(f"--video {args.video}: the graph has no MujocoDevice to film", file=path)
        out.update({f"{device}.video_path": _suffixed(args.video, device, devices) for device in devices})
    return out


def cmd_run(args: argparse.Namespace) -> int:
    """Load, validate and run a graph file, then report what was written. Recorders that do not
    choose their Rerun sink save ``out/NAME.rrd``; ``--bind``, ``--port`` and ``--web-viewer-port``
    are where ``serve`` sinks listen during this run (loopback, 9876 and 9090 unless given); with
    ``--keep-serving`` their servers serve the recording after the run, until Ctrl-C."""
    from dgraph.entities.recording.rerun_stream import kept_servers, recording_by_default, serving_on

    with serving_on(args.bind, args.port, args.web_viewer_port, keep=args.keep_serving), \
            recording_by_default("save"):
        code = _run(args)
        if args.keep_serving:
            servers = kept_servers()
            if not servers:
                print("--keep-serving: nothing is served (no recorder of this run serves: add --serve)",
                      file=sys.stderr)
                return code
            for server in servers:
                print(f"serving the recording at {server.viewer_url} until Ctrl-C", file=sys.stderr, flush=True)
            try:
                while any(server.running() for server in servers):
                    time.sleep(0.2)
            except KeyboardInterrupt:
                print(f"{_interruption(args)}: stopped serving", file=sys.stderr)
                return code
            print("the Rerun server stopped", file=sys.stderr)
    return code


def _interruption(args: argparse.Namespace) -> str:
    """What interrupted the command: the name of the termination signal it received, else Ctrl-C."""
    received = getattr(args, "terminated_by", [])
    return signal.Signals(received[0]).name if received else "Ctrl-C"


@contextlib.contextmanager
def terminations_as_ctrl_c() -> Iterator[list[int]]:
    """Within the block, SIGTERM and SIGHUP do what SIGINT (Ctrl-C) does: whatever handles SIGINT
    at that moment is called (a run stops after its tick, see ``dgraph.loop``; elsewhere
    ``KeyboardInterrupt`` is raised), so ``finally`` blocks run and Rerun servers stop; Python's
    default would end the process at once and leave them running. Yields the signals received, in
    order. Only in the main thread (elsewhere signals cannot be handled); the handlers are restored
    after the block."""
    received: list[int] = []
    if threading.current_thread() is not threading.main_thread():
        yield received
        return

    def as_ctrl_c(signum: int, frame: Any) -> None:
        received.append(signum)
        handler = signal.getsignal(signal.SIGINT)
        if callable(handler):
            handler(signal.SIGINT, frame)
        else:  # SIGINT ignored or left to the system: still end the command, cleanly
            raise KeyboardInterrupt

    previous = {signum: signal.signal(signum, as_ctrl_c) for signum in TERMINATIONS}
    try:
        yield received
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


def _run(args: argparse.Namespace) -> int:
    import dgraph
    from dgraph.files import command_line_settings

    overrides = {**_recorder_overrides(args.file, args), **command_line_settings(args.set)}
    graph = dgraph.load(args.file, overrides)
    graph.validate()
    if args.debug_checks:
        graph.check_values = graph.check_dependencies = True
    duration = args.duration if args.duration is not None else graph.duration
    if args.ticks is None and duration is None:
        raise GraphFileError("no run length: give --duration or --ticks, or 'duration' in the file", file=args.file)
    start = time.perf_counter()
    try:
        if args.ticks is not None:
            graph.run(ticks=args.ticks, progress=not args.quiet and None)
        else:
            graph.run(duration=duration, progress=not args.quiet and None)
    finally:
        graph.close()
        wall = time.perf_counter() - start
        simulated = graph.t * graph.dt
        print(f"{graph.name}: {graph.t} ticks, {simulated:.3f} s simulated in {wall:.2f} s "
              f"(real-time factor {simulated / wall if wall > 0 else float('inf'):.1f})")
        _print_faults(graph)
        for entity in graph:
            video = _video_written(entity)
            if video is not None:
                print(f"  {entity.name}: video -> {video}")
            if entity.type_name == "Recorder":
                for label, target in (("rerun", entity.rrd_path), ("npz", entity.npz_path)):
                    if target and (label == "npz" or entity.rerun == "save") and Path(target).is_file():
                        print(f"  {entity.name}: {label} -> {target}")
    return 0


def _video_written(entity: Any) -> str | None:
    """The video file this run of ``entity`` (a device with ``write_video()``, e.g. a MujocoDevice)
    wrote: what its ``write_video()`` returns once the device is closed (idempotent: the path, or
    ``None`` if it took no frame or failed), not whether a file is there (an earlier run's)."""
    write_video = getattr(entity, "write_video", None)
    if not callable(write_video):
        return None
    try:
        written = write_video()
    except DGraphError:  # a video that failed: reported by the close that failed
        return None
    return written if isinstance(written, str) else None


def _print_faults(graph: Graph) -> None:
    """The degraded ticks of a run (bad data survived, see dgraph.faults), and the most frequent faults."""
    log = graph.fault_log
    if log.degraded_ticks:
        print(f"  degraded ticks: {log.degraded_ticks} of {graph.t} (first: {log.faults[0]})")
        print("\n".join(f"    {line}" for line in log.summary().splitlines()))


def cmd_check(args: argparse.Namespace) -> int:
    """Load and validate without running a tick; list every problem (refused plugs with their
    file and line, unplugged inputs, loops, what entities report, plugins that failed)."""
    from dgraph.files import check
    from dgraph.registry import plugin_errors

    graph, problems = check(args.file)
    if not graph.roles()["stateful"]:  # what `run` refuses before its first tick
        problems.append(f"{args.file}: graph {graph.name!r} has no device or stateful entity to step "
                        "(dgraph run would refuse it)")
    problems += list(plugin_errors().values())
    if problems:
        print(f"{args.file}: {len(problems)} problem(s)")
        for p in problems:
            print(f"  {p}")
        return 1
    print(f"{args.file}: OK ({len(graph)} entities, {len(graph.plugs())} plugs, dt={graph.dt})")
    return 0


def cmd_profile(args: argparse.Namespace) -> int:
    """Run a graph file with timing on and print where each tick's time goes (no recording:
    recorders, views and videos off, as in a sweep's runs)."""
    import dgraph
    from dgraph.files import command_line_settings
    from dgraph.sweep.outcome import quiet_overrides

    graph = dgraph.load(args.file, {**quiet_overrides(args.file), **command_line_settings(args.set)})
    graph.validate()
    with graph:
        print(graph.profile(_profile_ticks(args, graph)))
    return 0


def _profile_ticks(args: argparse.Namespace, graph: Graph) -> int:
    """The ticks to profile: ``--ticks``, else ``--duration`` or the file's ``duration`` in ticks
    (checked as ``run`` checks them), else :data:`PROFILE_TICKS`."""
    if args.ticks is not None:
        if args.ticks < 0:
            raise GraphError(f"ticks must be an int >= 0, got {args.ticks!r}")
        return args.ticks
    duration = args.duration if args.duration is not None else graph.duration
    if duration is None:
        return PROFILE_TICKS
    if not (duration >= 0 and math.isfinite(duration / graph.dt)):
        raise GraphError(f"duration must be a finite number of seconds >= 0, got {duration!r}")
    return round(duration / graph.dt)


def cmd_show(args: argparse.Namespace) -> int:
    """Print (or write) the graph drawing."""
    import dgraph

    graph = dgraph.load(args.file)
    text = graph.to_dot(args.signals) if args.format == "dot" else graph.to_mermaid(args.signals)
    if args.output:
        Path(args.output).write_text(text)
    else:
        sys.stdout.write(text)
    return 0


def cmd_sweep(args: argparse.Namespace) -> int:
    """Run a grid (or a bisection) of runs of graph files over ``--set`` keys, each in a fresh
    process, locally or on Ray (see :mod:`dgraph.sweep`); the outcomes to a CSV table as they
    come (a run of the table is not made again: an interrupted sweep resumes), a plot at the end."""
    from dgraph.files import command_line_settings
    from dgraph.sweep import Sweep, SweepError, bisection_option, grid_axes, run_sweep

    if args.tolerance is not None and not args.bisect:
        raise SweepError("--tolerance: only with --bisect")
    tolerance = 0.05 if args.tolerance is None else args.tolerance
    sweep = Sweep(args.files, settings=command_line_settings(args.set), grid=grid_axes(args.grid),
                  bisection=bisection_option(args.bisect, tolerance) if args.bisect else None,
                  duration=args.duration, fall_signal=None if args.fall_signal == "none" else args.fall_signal,
                  measures=args.measure, timeout=args.timeout)
    out = Path(args.out or Path("out") / f"sweep_{Path(args.files[0]).stem}.csv")
    plot = None if args.no_plot else Path(args.plot or out.with_suffix(".png"))
    try:
        result = run_sweep(sweep, out, ray=args.ray, workers=args.workers, fresh=args.fresh, plot=plot,
                           progress=not args.quiet)
    except KeyboardInterrupt:
        print(f"{out}: the runs that finished are kept; the same command resumes the sweep", file=sys.stderr)
        raise
    print(result.summary())
    return 0


def _add_sweep(sub: argparse._SubParsersAction, shared: dict[str, argparse.ArgumentParser]) -> None:
    """The ``sweep`` subcommand's options."""
    sweep = sub.add_parser("sweep", help="run a grid or a bisection of runs over --set keys, each in its own "
                                         "process, locally or on Ray", parents=[shared["set"]])
    sweep.add_argument("files", nargs="+", metavar="FILE", help="graph files (several: one more grid axis)")
    sweep.add_argument("--grid", action="extend", nargs="+", default=[], metavar="KEY=V1,V2",
                       help="a grid axis: KEY=V1,V2,... or KEY=[V1, V2, ...], values read as --set reads them "
                            "(a vector in brackets: KEY=[1,0,0],[0,1,0]); repeatable")
    sweep.add_argument("--bisect", metavar="KEY=LOW:HIGH", help="in every grid cell, the largest value of KEY that "
                                                                "survives: LOW must, HIGH must not (0 <= LOW < HIGH)")
    sweep.add_argument("--tolerance", type=float, metavar="R",
                       help="relative width at which a bisection stops, HIGH - LOW <= R HIGH (default 0.05)")
    sweep.add_argument("--duration", type=float, metavar="S", help="seconds per run (default: each file's duration)")
    sweep.add_argument("--fall-signal", default="auto", metavar="SIGNAL",
                       help="bool signal that ends a run as fallen (default: device.fallen if the graph has it; "
                            "none: no fall)")
    sweep.add_argument("--measure", action="extend", nargs="+", default=[], metavar="SIGNAL",
                       help="record a signal's final value: a scalar, a vector's norm, or SIGNAL[i] (repeatable)")
    run = sweep.add_argument_group("execution")
    run.add_argument("--workers", type=int, metavar="N", help="runs at a time (default: one per CPU, or the "
                                                              "Ray cluster's CPUs)")
    run.add_argument("--ray", nargs="?", const=True, default=False, metavar="ADDRESS",
                     help="run on a Ray cluster: a local one, or the one at ADDRESS (write --ray=ADDRESS "
                          "before the files)")
    run.add_argument("--timeout", type=float, metavar="S", help="kill a run after S seconds of wall time")
    run.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    out = sweep.add_argument_group("results")
    out.add_argument("--out", metavar="CSV", help="the results table (default out/sweep_NAME.csv, NAME the first "
                                                  "file's)")
    plot = out.add_mutually_exclusive_group()
    plot.add_argument("--plot", metavar="PNG", help="the plot (default: the table's name with .png)")
    plot.add_argument("--no-plot", action="store_true", help="no plot")
    again = out.add_mutually_exclusive_group()
    again.add_argument("--resume", action="store_true", help="reuse the runs the table has (the default)")
    again.add_argument("--fresh", action="store_true", help="start the table over: every run is made again")
    sweep.set_defaults(func=cmd_sweep)


def cmd_entities(args: argparse.Namespace) -> int:
    """List registered entity types with their documentation."""
    from dgraph.registry import entity_types, get_type

    if args.type:
        print(get_type(args.type).describe())
        return 0
    for cls in entity_types().values():
        print(cls.describe())
        print()
    return 0


def cmd_identify(args: argparse.Namespace) -> int:
    """Identify an actuator chain's parameters from recordings (thesis Eqs. 3.9-3.12) and print
    Table 3.1's columns; optionally write them as YAML."""
    from dgraph.entities.actuators.identification import Payload, RecordingError, identify_recordings

    payload_args = (args.payload_recording, args.payload_mass, args.payload_arm)
    if any(a is not None for a in payload_args) and not all(a is not None for a in payload_args):
        raise RecordingError("--payload-recording, --payload-mass and --payload-arm go together")
    if args.payload_recording and args.drive_gain is not None:
        raise RecordingError("the scale comes from the payload or from --drive-gain, not both")
    if args.yaml and (not args.joint_name or args.i_max is None):
        raise RecordingError("--yaml writes an actuator file: it needs --joint-name (the robot's joint) and --i-max "
                             "(the drive's current limit, A: not identified)")
    if args.i_max is not None and not args.i_max > 0:
        raise RecordingError(f"--i-max must be positive (A), got {args.i_max}")
    payload = Payload(args.payload_mass, args.payload_arm) if args.payload_recording else None
    columns = {"time": args.time, "position": args.position, "current": args.current, "torque": args.torque,
               "velocity": args.velocity}
    options = {"cutoff": args.cutoff, "order": args.order, "decimation": args.decimation,
               "min_velocity": args.min_velocity}
    result = identify_recordings(args.recording, args.payload_recording, payload, columns=columns,
                                 joint=args.joint, drive_gain=args.drive_gain, **options)
    print(f"{args.recording}" + (f" + {args.payload_recording} ({args.payload_mass:g} kg at {args.payload_arm:g} m)"
                                 if payload else ""))
    print(result.table())
    if args.yaml:
        import yaml

        Path(args.yaml).write_text(yaml.safe_dump(result.actuator_file(args.joint_name, args.i_max), sort_keys=False))
        print(f"wrote {args.yaml} (actuator file: joint {args.joint_name}, i_max {args.i_max:g} A)")
    return 0


def _add_identify(sub: argparse._SubParsersAction) -> None:
    """The ``identify`` subcommand's options."""
    ident = sub.add_parser("identify", help="identify an actuator chain's parameters from .npz recordings "
                                            "(total least squares, thesis Eqs. 3.9-3.12, Table 3.1)")
    ident.add_argument("recording", help="the .npz recording without payload (double S-curve motions)")
    scale = ident.add_argument_group("scale (the payload experiment, or a known R K_m)")
    scale.add_argument("--payload-recording", metavar="PATH", help="the .npz recording of the same motions "
                                                                   "with the payload")
    scale.add_argument("--payload-mass", type=float, metavar="KG", help="the payload's mass (kg)")
    scale.add_argument("--payload-arm", type=float, metavar="M",
                       help="distance of the payload's centre of mass from the joint axis along the link's Y (m)")
    scale.add_argument("--drive-gain", type=float, metavar="NM_PER_A",
                       help="a known R K_m (N m/A) instead of a payload experiment")
    cols = ident.add_argument_group("columns of the recordings (a 2-D column gives its --joint component)")
    cols.add_argument("--time", default="time", metavar="COLUMN", help="time (s) (default: time)")
    cols.add_argument("--position", default="position", metavar="COLUMN",
                      help="joint position (rad) (default: position)")
    cols.add_argument("--velocity", metavar="COLUMN",
                      help="joint velocity (rad/s) (default: centred differences of the position)")
    cols.add_argument("--current", default="current", metavar="COLUMN", help="motor current (A) (default: current)")
    cols.add_argument("--torque", default="torque", metavar="COLUMN",
                      help="joint torque sensor reading (N m) (default: torque)")
    cols.add_argument("--joint", type=int, default=0, metavar="J", help="component of 2-D columns (default 0)")
    proc = ident.add_argument_group("processing")
    proc.add_argument("--cutoff", type=float, default=5.0, metavar="HZ",
                      help="zero-phase Butterworth low-pass cutoff (default 5 Hz, as the thesis)")
    proc.add_argument("--order", type=int, default=5, metavar="N", help="Butterworth order (default 5)")
    proc.add_argument("--decimation", type=int, metavar="N",
                      help="keep one sample in N after filtering (default: 4 samples per cutoff period)")
    proc.add_argument("--min-velocity", type=float, default=0.05, metavar="RAD_S",
                      help="leave out samples slower than this, where sign(q_dot) is undefined (default 0.05)")
    out = ident.add_argument_group("actuator file")
    out.add_argument("--yaml", metavar="OUT", help="also write the identified parameters as an actuator file "
                                                   "(load_chain_file's format: joints: {NAME: {...}}); needs "
                                                   "--joint-name and --i-max")
    out.add_argument("--joint-name", metavar="NAME", help="the robot joint the chain drives, e.g. arm_left_4_joint")
    out.add_argument("--i-max", type=float, metavar="A", help="the drive's current limit (A; not identified; inf "
                                                              "for none)")
    ident.set_defaults(func=cmd_identify)


def _port(text: str) -> int:
    """A TCP port number, for argparse."""
    try:
        port = int(text)
    except ValueError:
        port = -1
    if not 1 <= port <= 65535:
        raise argparse.ArgumentTypeError(f"expected a TCP port in 1..65535, got {text!r}")
    return port


def _shared_parsers() -> dict[str, argparse.ArgumentParser]:
    """The options that several subcommands share, as argparse parent parsers: the graph file,
    the run length, ``--set``."""
    graph_file = argparse.ArgumentParser(add_help=False)
    graph_file.add_argument("file", help="the graph file (YAML)")
    length = argparse.ArgumentParser(add_help=False)
    group = length.add_mutually_exclusive_group()
    group.add_argument("--duration", type=float, metavar="S",
                       help="seconds of control time (default: the file's duration; for profile, "
                            f"else {PROFILE_TICKS} ticks)")
    group.add_argument("--ticks", type=int, metavar="N", help="number of ticks")
    settings = argparse.ArgumentParser(add_help=False)
    settings.add_argument("--set", action="append", default=[], metavar="ENTITY.NAME=VALUE",
                          help="override a parameter or set an input constant (repeatable)")
    return {"file": graph_file, "length": length, "set": settings}


def _add_sink_options(run: argparse.ArgumentParser) -> None:
    """The Rerun sink options of ``run`` (named as Rerun's own scripts and server name them)."""
    sink = run.add_argument_group("Rerun recording (default: the file's sinks, else save out/NAME.rrd)")
    choice = sink.add_mutually_exclusive_group()
    choice.add_argument("--save", metavar="PATH", help="save the recording to this .rrd file")
    choice.add_argument("--serve", action="store_true",
                        help="serve a web viewer and Rerun's gRPC server (on loopback unless --bind) and "
                             "print the viewer's URL")
    choice.add_argument("--spawn", action="store_true", help="open a Rerun viewer on this machine")
    choice.add_argument("--no-rerun", action="store_true", help="no Rerun recording at all")
    sink.add_argument("--bind", metavar="ADDRESS",
                      help="IP address that --serve listens on (default 127.0.0.1, this machine only; "
                           "0.0.0.0 or :: opens the gRPC server and the web viewer to the network)")
    sink.add_argument("--port", type=_port, metavar="PORT", help="gRPC port of --serve (default 9876)")
    sink.add_argument("--web-viewer-port", type=_port, metavar="PORT",
                      help="web viewer port of --serve (default 9090)")
    sink.add_argument("--keep-serving", action="store_true",
                      help="after the run, keep serving the recording until Ctrl-C (with --serve)")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``dgraph`` command."""
    parser = argparse.ArgumentParser(prog="dgraph", description="Run, check and draw dgraph graph files.")
    parser.add_argument("--version", action="version", version=f"dgraph {version()}",
                        help="print the installed version of dgraph and exit")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND",
                                help="what to do (dgraph COMMAND -h for its options)")
    shared = _shared_parsers()
    run = sub.add_parser("run", help="run a graph file", parents=[shared["file"], shared["length"], shared["set"]])
    _add_sink_options(run)
    run.add_argument("--npz", metavar="PATH", help="also write the recorded signals to this .npz file")
    run.add_argument("--video", metavar="PATH",
                     help="film the run: the video_path of every MujocoDevice of the file")
    run.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    run.add_argument("--debug-checks", action="store_true",
                     help="check every computed value (shape, NaN) and every read against its declared "
                          "dependencies (slow; names the first signal that goes wrong)")
    run.set_defaults(func=cmd_run)
    check = sub.add_parser("check", help="load and validate a graph file", parents=[shared["file"]])
    check.set_defaults(func=cmd_check)
    prof = sub.add_parser("profile", help="time each entity over a run (per tick)",
                          parents=[shared["file"], shared["length"], shared["set"]])
    prof.set_defaults(func=cmd_profile)
    show = sub.add_parser("show", help="draw a graph file as Graphviz dot or Mermaid", parents=[shared["file"]])
    show.add_argument("--format", choices=("dot", "mermaid"), default="dot",
                      help="Graphviz dot or Mermaid flowchart (default dot)")
    show.add_argument("--signals", action="store_true", help="signal-level drawing")
    show.add_argument("-o", "--output", metavar="OUT", help="write to this file instead of stdout")
    show.set_defaults(func=cmd_show)
    _add_sweep(sub, shared)
    ents = sub.add_parser("entities", help="list the registered entity types")
    ents.add_argument("type", nargs="?", help="describe one type")
    ents.set_defaults(func=cmd_entities)
    _add_identify(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``dgraph`` command."""
    parser = build_parser()
    args = parser.parse_args(argv)
    with terminations_as_ctrl_c() as args.terminated_by:
        code = _main(args)
    if args.terminated_by:  # also when the command ended normally on it (--keep-serving)
        return 128 + args.terminated_by[0]
    return code


def _main(args: argparse.Namespace) -> int:
    """Run the subcommand of ``args``; its exit status, errors reported as one line."""
    try:
        code = int(args.func(args))
        sys.stdout.flush()  # a broken pipe shows here, not at exit
        return code
    except BrokenPipeError as exc:  # before OSError, which it is
        if _stdout_closed():  # output piped into `head` and closed: not an error
            _quiet_stdout()
            return 0
        print(f"dgraph {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    except DGraphError as exc:
        print(f"dgraph {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    except OSError as exc:  # an output file that cannot be written, a viewer that cannot start
        print(f"dgraph {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    except KeyboardInterrupt:
        print("interrupted" if not args.terminated_by else f"{_interruption(args)}: interrupted", file=sys.stderr)
        return 130


def _stdout_closed() -> bool:
    """Whether nothing reads standard output any more (a pipe whose reader has gone polls as an
    error); a broken pipe elsewhere (a viewer's socket) is an error to report."""
    try:
        poller = select.poll()
        poller.register(sys.stdout.fileno(), select.POLLOUT)
        return any(event & (select.POLLERR | select.POLLHUP) for _, event in poller.poll(0))
    except (AttributeError, OSError, ValueError):  # no poll (Windows), no file descriptor
        return True


def _quiet_stdout() -> None:
    """The Python documentation's way out of a broken pipe: point standard output at devnull, so
    that flushing it again at exit does not raise."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # stdout is not a file (captured in a test)
        pass


if __name__ == "__main__":
    sys.exit(main())
