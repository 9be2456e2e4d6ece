"""The ``dgraph`` command: run, check and draw graph files, list entity types.

    dgraph run FILE [--duration S | --ticks N] [--set entity.name=value ...]
                    [--rerun save PATH | spawn | serve | off] [--rerun-bind ADDRESS]
                    [--npz PATH] [--debug-checks]
    dgraph check FILE
    dgraph profile FILE [--duration S | --ticks N] [--set entity.name=value ...]
    dgraph show FILE --format dot|mermaid [--signals] [-o OUT]
    dgraph entities [TYPE]
    dgraph --version

``python -m dgraph ...`` is the same command. Output piped into a command that stops reading
(``dgraph entities | head -1``) ends the command quietly, with status 0.

Values given to ``--set`` are parsed as YAML scalars or flow lists (``1.5``, ``[0, 0.05, 0]``,
``true``), with the same safe loader as graph files. Errors print one line naming the file,
line, entity and signal, and exit with status 2.
"""

from __future__ import annotations

import argparse
import math
import os
import select
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from dgraph.errors import DGraphError, GraphError, GraphFileError

if TYPE_CHECKING:
    from dgraph.graph import Graph

EXIT_ERROR = 2
PROFILE_TICKS = 1000  # what `profile` times when neither the command line nor the file gives a length


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


def _recorder_overrides(path: str, args: argparse.Namespace) -> dict[str, Any]:
    """Point every recorder of the file at the sinks chosen on the command line (what the
    command line does not say is left as the file says)."""
    names, stem = _recorder_names(path)
    out: dict[str, Any] = {}
    for name in names:
        suffix = "" if len(names) == 1 else f"_{name}"
        if args.rerun:
            mode, rrd = _rerun_mode(args.rerun, stem)
            out[f"{name}.rerun"] = mode
            if mode == "save":
                out[f"{name}.rrd_path"] = str(Path(rrd).with_stem(Path(rrd).stem + suffix))
        if args.npz:
            out[f"{name}.npz_path"] = str(Path(args.npz).with_stem(Path(args.npz).stem + suffix))
    if args.rerun:  # robot views draw into the (first) recorder's recording
        mode, rrd = _rerun_mode(args.rerun, stem)
        for view in _recorder_names(path, ("RobotView",))[0]:
            out[f"{view}.rerun"] = mode
            if mode == "save":
                out[f"{view}.rrd_path"] = out.get(f"{names[0]}.rrd_path", rrd) if names else rrd
    return out


def _rerun_mode(option: list[str], stem: str) -> tuple[str, str | None]:
    mode = option[0]
    if mode == "save":
        return "save", option[1] if len(option) > 1 else f"out/{stem}.rrd"
    if mode in ("spawn", "serve", "off") and len(option) == 1:
        return mode, None
    raise GraphFileError(f"--rerun {' '.join(option)}: expected 'save [PATH]', 'spawn', 'serve' or 'off'",
                         file="<command line>")


def cmd_run(args: argparse.Namespace) -> int:
    """Load, validate and run a graph file, then report what was written; ``--rerun-bind`` is
    where ``serve`` sinks listen during this run (loopback unless given)."""
    from dgraph.entities.recording.rerun_stream import serving_on

    with serving_on(args.rerun_bind):
        return _run(args)


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
            if entity.type_name == "Recorder":
                for label, target in (("rerun", entity.rrd_path), ("npz", entity.npz_path)):
                    if target and (label == "npz" or entity.rerun == "save") and Path(target).is_file():
                        print(f"  {entity.name}: {label} -> {target}")
    return 0


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
    """Run a graph file with timing on and print where each tick's time goes (no recording)."""
    import dgraph
    from dgraph.files import command_line_settings

    quiet = {f"{name}.rerun": "off" for name in _recorder_names(args.file, ("Recorder", "RobotView"))[0]}
    graph = dgraph.load(args.file, {**quiet, **command_line_settings(args.set)})
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


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``dgraph`` command."""
    parser = argparse.ArgumentParser(prog="dgraph", description="Run, check and draw dgraph graph files.")
    parser.add_argument("--version", action="version", version=f"dgraph {version()}",
                        help="print the installed version of dgraph and exit")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND",
                                help="what to do (dgraph COMMAND -h for its options)")
    file_help = "the graph file (YAML)"
    set_help = "override a parameter or set an input constant (repeatable)"
    run = sub.add_parser("run", help="run a graph file")
    run.add_argument("file", nargs="?", help=file_help)
    length = run.add_mutually_exclusive_group()
    length.add_argument("--duration", type=float, metavar="S",
                        help="seconds of control time (default: the file's duration)")
    length.add_argument("--ticks", type=int, metavar="N", help="number of ticks")
    run.add_argument("--set", action="append", default=[], metavar="ENTITY.NAME=VALUE", help=set_help)
    run.add_argument("--rerun", nargs="+", metavar="MODE",
                     help="save [PATH] (default out/NAME.rrd), spawn, serve or off")
    run.add_argument("--rerun-bind", metavar="ADDRESS",
                     help="IP address that --rerun serve listens on (default 127.0.0.1, this machine only; "
                          "0.0.0.0 or :: opens the gRPC server and the web viewer to the network)")
    run.add_argument("--npz", metavar="PATH", help="also write the recorded signals to this .npz file")
    run.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    run.add_argument("--debug-checks", action="store_true",
                     help="check every computed value (shape, NaN) and every read against its declared "
                          "dependencies (slow; names the first signal that goes wrong)")
    run.set_defaults(func=cmd_run)
    check = sub.add_parser("check", help="load and validate a graph file")
    check.add_argument("file", help=file_help)
    check.set_defaults(func=cmd_check)
    prof = sub.add_parser("profile", help="time each entity over a run (per tick)")
    prof.add_argument("file", help=file_help)
    prof_length = prof.add_mutually_exclusive_group()
    prof_length.add_argument("--duration", type=float, metavar="S",
                             help="seconds of control time (default: the file's duration, "
                                  f"else {PROFILE_TICKS} ticks)")
    prof_length.add_argument("--ticks", type=int, metavar="N", help="number of ticks")
    prof.add_argument("--set", action="append", default=[], metavar="ENTITY.NAME=VALUE", help=set_help)
    prof.set_defaults(func=cmd_profile)
    show = sub.add_parser("show", help="draw a graph file as Graphviz dot or Mermaid")
    show.add_argument("file", help=file_help)
    show.add_argument("--format", choices=("dot", "mermaid"), default="dot",
                      help="Graphviz dot or Mermaid flowchart (default dot)")
    show.add_argument("--signals", action="store_true", help="signal-level drawing")
    show.add_argument("-o", "--output", metavar="OUT", help="write to this file instead of stdout")
    show.set_defaults(func=cmd_show)
    ents = sub.add_parser("entities", help="list the registered entity types")
    ents.add_argument("type", nargs="?", help="describe one type")
    ents.set_defaults(func=cmd_entities)
    return parser


def _take_file_back(args: argparse.Namespace, parser: argparse.ArgumentParser) -> None:
    """``--rerun off FILE`` lets --rerun swallow FILE: give it back."""
    if getattr(args, "file", "") is None:
        tokens = args.rerun or []
        if len(tokens) > 1 and tokens[-1].endswith((".yaml", ".yml")):
            args.file = tokens.pop()
        else:
            parser.error("the following arguments are required: file")


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``dgraph`` command."""
    parser = build_parser()
    args = parser.parse_args(argv)
    _take_file_back(args, parser)
    try:
        code = args.func(args)
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
        print("interrupted", file=sys.stderr)
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
