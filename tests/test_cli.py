"""The dgraph command: run (closed loop converges), check, show, entities, error exits."""

from __future__ import annotations

import os
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from dgraph.cli import main
from dgraph.registry import entity_types
from tests.conftest import stop_process

ROOT = Path(__file__).resolve().parents[1]
PD = str(ROOT / "graphs" / "pd_double_integrator.yaml")


def dgraph_cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    exe = Path(sys.executable).with_name("dgraph")
    return subprocess.run([str(exe), *args], capture_output=True, text=True, cwd=cwd, timeout=300)


def test_run_pd_loop_converges_to_the_setpoint(tmp_path):
    result = dgraph_cli("run", PD, "--save", "pd.rrd", "--npz", "pd.npz", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "3000 ticks" in result.stdout and "pd.rrd" in result.stdout
    data = np.load(tmp_path / "pd.npz")
    q = data["robot.q"]
    assert np.allclose(q[-1], [1.0, -0.5], atol=1e-3)
    err = np.abs(q - [1.0, -0.5]).max(axis=1)
    assert err[0] == pytest.approx(1.0) and np.all(np.diff(err) <= 1e-12)  # critically damped: monotone
    assert (tmp_path / "pd.rrd").stat().st_size > 0


def test_run_with_overrides_changes_the_result(tmp_path):
    result = dgraph_cli("run", PD, "--duration", "1.0", "--set", "setpoint.value=[2.0, 0.0]",
                        "--set", "kp.gain=100.0", "--set", "kd.gain=20.0", "--no-rerun",
                        "--npz", "fast.npz", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    q = np.load(tmp_path / "fast.npz")["robot.q"]
    # critically damped at 10 rad/s: |e(1 s)| = 2 (1 + 10) exp(-10) = 1.0e-3
    assert len(q) == 1000 and abs(q[-1, 0] - 2.0) < 2e-3 and abs(q[-1, 0] - 2.0) > 5e-4


def test_default_recording_goes_to_out(tmp_path):
    result = dgraph_cli("run", PD, "--ticks", "10", "-q", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "out" / "pd_double_integrator.rrd").exists()


def test_errors_exit_2_with_file_and_line(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text("entities:\n  a: {type: Gian}\n")
    assert main(["check", str(bad)]) == 2
    err = capsys.readouterr().err
    assert f"{bad}:2" in err and "did you mean Gain" in err
    assert main(["run", PD, "--set", "nope"]) == 2
    assert main(["run", PD, "--set", "kp.gain=[1, 2, 3]", "--no-rerun", "--ticks", "1"]) == 2
    assert "kp" in capsys.readouterr().err


def test_check_reports_problems(tmp_path, capsys):
    unplugged = tmp_path / "unplugged.yaml"
    unplugged.write_text("entities:\n  k: {type: Gain, params: {size: 2}}\n")
    assert main(["check", str(unplugged)]) == 1
    assert "input k.input is not plugged" in capsys.readouterr().out
    assert main(["check", PD]) == 0
    assert "OK (7 entities, 7 plugs" in capsys.readouterr().out


def test_check_lists_every_plug_of_the_wrong_type_with_its_line(tmp_path, capsys):
    scenario = tmp_path / "wrong_plugs.yaml"
    scenario.write_text(f"extends: {ROOT / 'graphs' / 'talos_standing.yaml'}\nplugs:\n"
                        "  - com.feature -> solver.com_task\n  - left_foot.contact -> solver.waist_task\n")
    assert main(["check", str(scenario)]) == 1
    out = capsys.readouterr().out
    assert "2 problem(s)" in out
    assert f"{scenario}:3 [plugs.0]: cannot plug com.feature FeatureValue into solver.com_task TaskEquation" in out
    assert f"{scenario}:4 [plugs.1]: cannot plug left_foot.contact ContactConstraint into solver.waist_task " \
           "TaskEquation" in out


def test_profile_lists_every_entity(tmp_path, capsys):
    assert main(["profile", PD, "--ticks", "200"]) == 0
    out = capsys.readouterr().out
    assert "200 ticks" in out and "us per tick" in out
    for name in ("robot", "error", "kp", "kd", "command", "recorder"):
        assert name in out
    assert not (tmp_path / "out").exists()  # profiling records nothing


def test_show_and_entities(tmp_path, capsys):
    assert main(["show", PD, "--format", "mermaid"]) == 0
    assert "flowchart LR" in capsys.readouterr().out
    assert main(["show", PD, "--format", "dot", "--signals", "-o", str(tmp_path / "g.dot")]) == 0
    assert "cluster_robot" in (tmp_path / "g.dot").read_text()
    assert main(["entities"]) == 0
    listing = capsys.readouterr().out
    assert "KinematicDevice:" in listing and "Recorder:" in listing
    assert main(["entities", "Nope"]) == 2


def test_a_run_that_fails_keeps_what_was_recorded(tmp_path, capsys):
    import dgraph as dg

    @dg.register(name="TestFailAtTick")
    class FailAtTick(dg.Entity):
        """Raises at a given tick (to test error paths)."""

        tick = dg.Param(kind="int")
        u = dg.Input(shape=(2,))

        @dg.output(shape=(2,), depends=("u", "t"))
        def y(self, t):
            if t == self.tick:
                raise RuntimeError("boom")
            return self.u(t)

    text = Path(PD).read_text().replace(
        "  - command.output -> robot.control",
        "  - command.output -> fail.u\n  - fail.y -> robot.control").replace(
        "entities:\n", "entities:\n  fail: {type: TestFailAtTick, params: {tick: 250}}\n")
    graph_file = tmp_path / "failing.yaml"
    graph_file.write_text(text)
    assert main(["run", str(graph_file), "--save", str(tmp_path / "f.rrd"),
                 "--npz", str(tmp_path / "f.npz")]) == 2
    err = capsys.readouterr().err
    assert "fail.y failed at tick 250: RuntimeError: boom" in err
    data = np.load(tmp_path / "f.npz")
    assert len(data["tick"]) == 250 and data["tick"][-1] == 249
    assert (tmp_path / "f.rrd").stat().st_size > 0


def test_command_line_mistakes_are_one_line_errors(tmp_path, capsys):
    assert main(["run", "missing.yaml", "--ticks", "1"]) == 2
    assert "missing.yaml: cannot read" in capsys.readouterr().err
    assert main(["run", PD, "--duration", "inf", "--no-rerun"]) == 2
    assert "finite number of seconds" in capsys.readouterr().err
    assert main(["run", PD, "--ticks", "5", "--npz", "/proc/none/x.npz", "--no-rerun"]) == 2
    assert "cannot write /proc/none/x.npz" in capsys.readouterr().err
    assert main(["run", PD, "--set", "kp.gain=abc"]) == 2
    assert "<command line> [--set kp.gain]" in capsys.readouterr().err


def test_sink_option_before_the_file_and_file_settings_kept(tmp_path):
    assert main(["run", "--no-rerun", PD, "--ticks", "5", "--npz", "plain"]) == 0
    assert (tmp_path / "plain.npz").exists() and not (tmp_path / "out").exists()
    assert main(["run", "--save", "first.rrd", PD, "--ticks", "5", "-q"]) == 0  # --save does not take the file
    assert (tmp_path / "first.rrd").stat().st_size > 0 and not (tmp_path / "out").exists()
    own = tmp_path / "own.yaml"
    text = Path(PD).read_text().replace("record: [robot.q, robot.v, command.output, error.output]\n", "")
    own.write_text(text.replace("entities:\n", "entities:\n  rec: {type: Recorder, params: "
                                "{signals: [robot.q], rrd_path: mine/rec.rrd}}\n"))
    assert main(["run", str(own), "--ticks", "5"]) == 0  # no sink option: the file's own path is used
    assert (tmp_path / "mine" / "rec.rrd").exists() and not (tmp_path / "out").exists()
    off = tmp_path / "off.yaml"
    text = Path(PD).read_text().replace("set:\n", "set:\n  recorder.rerun: 'off'\n")
    off.write_text(text)
    assert main(["run", str(off), "--ticks", "5"]) == 0  # the file says off: nothing
    assert not (tmp_path / "out").exists()
    assert main(["run", str(off), "--ticks", "5", "--save", "over.rrd"]) == 0  # the command line wins
    assert (tmp_path / "over.rrd").stat().st_size > 0


def test_the_sink_options_exclude_each_other_and_the_old_option_is_gone(tmp_path):
    for args in (["--save", "a.rrd", "--serve"], ["--spawn", "--no-rerun"], ["--serve", "--save", "b.rrd"]):
        result = dgraph_cli("run", PD, "--ticks", "1", *args, cwd=tmp_path)
        assert result.returncode == 2 and "not allowed with argument" in result.stderr, (args, result.stderr)
    result = dgraph_cli("run", PD, "--rerun", "off", cwd=tmp_path)
    assert result.returncode == 2 and "unrecognized arguments: --rerun off" in result.stderr
    result = dgraph_cli("run", "--save", PD, cwd=tmp_path)  # --save takes a path: the file is missing
    assert result.returncode == 2 and "the following arguments are required: file" in result.stderr
    for bad in ("0", "65536", "http"):
        result = dgraph_cli("run", PD, "--serve", "--port", bad, cwd=tmp_path)
        assert result.returncode == 2 and f"--port: expected a TCP port in 1..65535, got '{bad}'" in result.stderr
    result = dgraph_cli("run", PD, "--web-viewer-port", "-1", cwd=tmp_path)
    assert result.returncode == 2 and "--web-viewer-port: expected a TCP port" in result.stderr
    assert list(tmp_path.iterdir()) == []  # nothing ran


def test_two_recorders_get_a_file_each_from_one_save_option(tmp_path):
    two = tmp_path / "two.yaml"
    two.write_text(Path(PD).read_text().replace("entities:\n", "entities:\n  second: {type: Recorder, params: "
                                                "{signals: [robot.v]}}\n"))
    assert main(["run", str(two), "--ticks", "5", "-q", "--save", "r.rrd", "--npz", "r.npz"]) == 0
    assert {p.name for p in tmp_path.iterdir()} == {"two.yaml", "r_recorder.rrd", "r_second.rrd",
                                                    "r_recorder.npz", "r_second.npz"}


def test_bind_and_ports_choose_where_serve_listens(ports, monkeypatch, capsys):
    from dgraph.entities.recording import rerun_stream
    from tests.entities.test_rerun_stream import listening

    assert rerun_stream.SERVE.bind == "127.0.0.1"  # without the option: this machine only
    default = rerun_stream.SERVE
    grpc, web = ports
    assert main(["run", PD, "--ticks", "5", "--serve", "--bind", "127.0.0.2", "--port", str(grpc),
                 "--web-viewer-port", str(web), "-q"]) == 0
    assert rerun_stream.SERVE == default  # for this run only
    assert f"rerun: web viewer at http://127.0.0.2:{web}/?url=rerun%2Bhttp%3A%2F%2F127.0.0.2%3A{grpc}" \
           in capsys.readouterr().err
    assert listening(grpc) == set() and listening(web) == set()  # the run is over: so is the server
    assert main(["run", PD, "--ticks", "5", "--serve", "--bind", "everywhere"]) == 2
    assert "'everywhere': not an IP address" in capsys.readouterr().err


def test_keep_serving_without_a_server_says_so_and_ends(tmp_path, capsys):
    assert main(["run", PD, "--ticks", "5", "-q", "--no-rerun", "--keep-serving"]) == 0
    assert "--keep-serving: nothing is served" in capsys.readouterr().err


def serve_and_keep(tmp_path: Path, grpc: int, web: int, ticks: int = 500) -> subprocess.Popen[bytes]:
    """``dgraph run`` of the PD loop serving on ``grpc`` and ``web`` with ``--keep-serving`` (binary pipes)."""
    exe = Path(sys.executable).with_name("dgraph")
    return subprocess.Popen([str(exe), "run", PD, "--ticks", str(ticks), "-q", "--serve", "--port", str(grpc),
                             "--web-viewer-port", str(web), "--keep-serving"],
                            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=tmp_path)


def read_until(process: subprocess.Popen[bytes], text: str, timeout: float) -> str:
    """What ``process`` printed on its standard error (a binary pipe) until a whole line holding
    ``text`` came (that line and what came with it); fails naming what it printed if that takes
    over ``timeout`` seconds or the process ends first (never blocks past the deadline: ``select``)."""
    assert process.stderr is not None
    fd, said, deadline = process.stderr.fileno(), b"", time.monotonic() + timeout
    while b"\n" not in said.partition(text.encode())[2]:  # until text and the end of its line
        left = deadline - time.monotonic()
        if left <= 0:
            pytest.fail(f"no {text!r} from {process.args} after {timeout:g} s; it printed: {said.decode()!r}")
        if select.select([fd], [], [], left)[0]:
            chunk = os.read(fd, 1 << 16)
            if not chunk:
                pytest.fail(f"{process.args} ended (status {process.wait()}) before {text!r}: {said.decode()!r}")
            said += chunk
    return said.decode()


def stop_cli(process: subprocess.Popen[bytes], grpc: int | None = None) -> None:
    """End ``process`` (a ``dgraph run``) if it still runs: SIGTERM first, which stops its Rerun
    servers, then SIGKILL if it has not ended 10 s later; close its pipes. With ``grpc``, also kill
    a Rerun server left serving on that port (what a failure of the code under test would leave)."""
    stop_process(process)
    for pipe in (process.stdout, process.stderr):
        if pipe is not None:
            pipe.close()
    for pid in _rerun_servers_on(grpc) if grpc is not None else []:
        os.kill(pid, signal.SIGKILL)


def wait_closed(ports: tuple[int, ...], timeout: float) -> float:
    """Seconds until nothing listens on ``ports`` (any process, any address); fails after ``timeout``."""
    from tests.entities.test_rerun_stream import listening

    start = time.monotonic()
    while any(listening(port) for port in ports):
        if time.monotonic() - start > timeout:
            pytest.fail(f"still listening after {timeout:g} s: {[(p, listening(p)) for p in ports]}")
        time.sleep(0.05)
    return time.monotonic() - start


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGHUP], ids=["SIGTERM", "SIGHUP"])
def test_a_terminated_run_stops_its_rerun_server_and_exits_128_plus_the_signal(tmp_path, ports, signum):
    """``kill``, ``timeout``, systemd (SIGTERM) and a closed terminal (SIGHUP) end ``dgraph run``
    as Ctrl-C does: its ``finally`` blocks run, the Rerun server stops, the ports are free."""
    from tests.entities.test_rerun_stream import listening

    grpc, web = ports
    run = serve_and_keep(tmp_path, grpc, web)
    try:
        read_until(run, "until Ctrl-C", timeout=60)
        assert listening(grpc) and listening(web)
        run.send_signal(signum)
        assert run.wait(timeout=10) == 128 + signum
        assert f"{signal.Signals(signum).name}: stopped serving" in run.stderr.read().decode()
        assert wait_closed((grpc, web), timeout=0.5) < 0.5  # stopped before the command ended
    finally:
        stop_cli(run, grpc)


def test_a_killed_run_takes_its_rerun_server_with_it(tmp_path, ports):
    """SIGKILL runs no Python at all: the server, told by the kernel to die with its parent
    (PR_SET_PDEATHSIG), ends anyway and frees the ports for the next ``--serve``."""
    grpc, web = ports
    run = serve_and_keep(tmp_path, grpc, web)
    try:
        read_until(run, "until Ctrl-C", timeout=60)
        run.kill()
        run.wait(timeout=10)
        wait_closed((grpc, web), timeout=5)
    finally:
        stop_cli(run, grpc)


def _rerun_servers_on(grpc: int) -> list[int]:
    """The pids of the ``rerun --serve-web`` processes started with ``--port grpc``."""
    found = []
    for proc in Path("/proc").iterdir():
        try:
            argv = (proc / "cmdline").read_bytes()
        except OSError:
            continue
        if b"\0--serve-web\0" in argv and f"\0--port\0{grpc}\0".encode() in argv:
            found.append(int(proc.name))
    return found


def test_run_a_10000_deep_chain(tmp_path):
    """A velocity-controlled integrator closed through 10,000 gains: v = -2 q, q(k) = (1 - 2 dt)^k."""
    depth, gains = 10_000, ["1.0"] * 9_999 + ["-2.0"]
    lines = ["name: deep_chain", "dt: 0.01", "entities:",
             "  robot: {type: KinematicDevice, params: {control_mode: velocity, size: 1, q0: [1.0]}}"]
    lines += [f"  g{i}: {{type: Gain, params: {{size: 1}}}}" for i in range(depth)]
    lines += ["plugs:", "  - robot.q -> g0.input"]
    lines += [f"  - g{i}.output -> g{i + 1}.input" for i in range(depth - 1)]
    lines += [f"  - g{depth - 1}.output -> robot.control", "set:"]
    lines += [f"  g{i}.gain: {gain}" for i, gain in enumerate(gains)]
    lines += ["record: [robot.q]"]
    (tmp_path / "deep.yaml").write_text("\n".join(lines) + "\n")
    result = dgraph_cli("run", "deep.yaml", "--ticks", "5", "--no-rerun", "--npz", "deep.npz", "-q", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    q = np.load(tmp_path / "deep.npz")["robot.q"][:, 0]
    assert np.allclose(q, 0.98 ** np.arange(5), rtol=1e-12)


@pytest.mark.filterwarnings("ignore:invalid value")
def test_debug_checks_name_the_first_signal_that_computes_a_non_finite_value(tmp_path):
    """An infinite setpoint: by default the infinity is caught where it would become the device's
    state; the debug switch names where it starts (an infinity is refused like a NaN)."""
    args = ("run", PD, "--ticks", "5", "--no-rerun", "-q", "--set", "setpoint.value=[.inf, 0.0]")
    plain = dgraph_cli(*args, cwd=tmp_path)
    checked = dgraph_cli(*args, "--debug-checks", cwd=tmp_path)
    assert plain.returncode == 2 and "robot.q: staged value contains inf" in plain.stderr, plain.stderr
    assert checked.returncode == 2 and "setpoint.output at tick 0: computed a value containing inf" in checked.stderr


def test_version_prints_the_installed_version(tmp_path, capsys):
    from importlib.metadata import version

    result = dgraph_cli("--version", cwd=tmp_path)
    assert result.returncode == 0 and result.stderr == ""
    assert result.stdout == f"dgraph {version('dgraph')}\n"
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0 and capsys.readouterr().out == f"dgraph {version('dgraph')}\n"


def test_version_falls_back_to_the_package_version(monkeypatch):
    import importlib.metadata

    import dgraph
    from dgraph import cli

    def not_installed(name):
        raise importlib.metadata.PackageNotFoundError(name)

    monkeypatch.setattr(importlib.metadata, "version", not_installed)
    assert cli.version() == dgraph.__version__


def test_python_m_dgraph_is_the_dgraph_command(tmp_path):
    def module(*args):
        return subprocess.run([sys.executable, "-m", "dgraph", *args], capture_output=True, text=True,
                              cwd=tmp_path, timeout=300)

    for args in (["--version"], ["check", PD], ["entities", "Gain"], ["entities", "Nope"], []):
        by_module, by_script = module(*args), dgraph_cli(*args, cwd=tmp_path)
        assert (by_module.returncode, by_module.stdout, by_module.stderr) == \
               (by_script.returncode, by_script.stdout, by_script.stderr), args
    assert module("check", PD).returncode == 0 and module("entities", "Nope").returncode == 2
    assert module().returncode == 2 and "usage: dgraph" in module().stderr


def test_every_argument_of_every_subcommand_has_help():
    import argparse

    from dgraph.cli import build_parser

    def walk(parser, where):
        for action in parser._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            name = "/".join(action.option_strings) or action.dest
            yield f"{where} {name}", action.help
            if isinstance(action, argparse._SubParsersAction):
                for choice in action._choices_actions:
                    yield f"{where} {choice.dest}", choice.help
                for command, sub in action.choices.items():
                    yield from walk(sub, f"{where} {command}")

    found = dict(walk(build_parser(), "dgraph"))
    assert {"dgraph run file", "dgraph profile --duration", "dgraph check file", "dgraph --version",
            "dgraph entities type", "dgraph show --format"} <= set(found)
    assert [name for name, text in found.items() if not (text and text.strip())] == []


def test_a_closed_pipe_ends_quietly_with_status_0(tmp_path):
    exe = Path(sys.executable).with_name("dgraph")
    for args in (["entities"], ["show", PD, "--signals"], ["profile", PD, "--ticks", "50"]):
        shell = subprocess.run(["bash", "-c", 'set -o pipefail; "$@" | head -1', "-", str(exe), *args],
                               capture_output=True, text=True, cwd=tmp_path, timeout=300)
        assert shell.returncode == 0 and shell.stderr == "", (args, shell.stderr)
        assert len(shell.stdout.splitlines()) == 1
    # the pipe closed by the reader after one line, with dgraph's own status
    proc = subprocess.Popen([str(exe), "entities"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            cwd=tmp_path)
    first = next(iter(entity_types()))  # the listing's first type
    assert proc.stdout.readline().startswith(f"{first}:".encode())
    proc.stdout.close()
    assert proc.wait(timeout=300) == 0
    assert proc.stderr.read() == b""
    proc.stderr.close()


def test_an_unwritable_stdout_is_still_an_error(tmp_path):
    with open("/dev/full", "w") as full:
        result = subprocess.run([str(Path(sys.executable).with_name("dgraph")), "entities"], stdout=full,
                                stderr=subprocess.PIPE, text=True, cwd=tmp_path, timeout=300)
    assert result.returncode == 2 and "dgraph entities: error: [Errno 28]" in result.stderr


def test_profile_takes_a_duration_or_the_files_duration(tmp_path, capsys):
    assert main(["profile", PD, "--duration", "0.25"]) == 0
    assert "250 ticks" in capsys.readouterr().out
    assert main(["profile", PD]) == 0  # the file says duration: 3.0
    assert "3000 ticks" in capsys.readouterr().out
    assert main(["profile", PD, "--duration", "inf"]) == 2
    assert "finite number of seconds" in capsys.readouterr().err
    assert main(["profile", PD, "--ticks", "-1"]) == 2
    assert "ticks must be an int >= 0" in capsys.readouterr().err
    no_duration = tmp_path / "no_duration.yaml"
    no_duration.write_text(Path(PD).read_text().replace("duration: 3.0\n", ""))
    assert main(["profile", str(no_duration)]) == 0
    assert "1000 ticks" in capsys.readouterr().out
    result = dgraph_cli("profile", PD, "--ticks", "5", "--duration", "1", cwd=tmp_path)
    assert result.returncode == 2 and "not allowed with argument" in result.stderr


def test_check_refuses_what_run_refuses_a_graph_with_nothing_to_step(tmp_path, capsys):
    stateless = tmp_path / "stateless.yaml"
    stateless.write_text("entities:\n  c: {type: Constant, params: {value: [1.0]}}\n")
    assert main(["run", str(stateless), "--ticks", "1"]) == 2
    assert "has no device or stateful entity to step" in capsys.readouterr().err
    assert main(["check", str(stateless)]) == 1
    out = capsys.readouterr().out
    assert "1 problem(s)" in out and "OK" not in out
    assert f"{stateless}: graph 'stateless' has no device or stateful entity to step" in out


def test_a_set_option_error_names_the_option_not_a_line_of_a_made_up_document(tmp_path):
    result = dgraph_cli("run", PD, "--ticks", "2", "--no-rerun", "--set", "setpoint.value=[1,", cwd=tmp_path)
    assert result.returncode == 2
    assert "<command line> [--set setpoint.value]: '[1,': invalid YAML" in result.stderr, result.stderr
    assert "<command line>:" not in result.stderr, result.stderr  # no line number of a synthetic text
    ok = dgraph_cli("run", PD, "--ticks", "2", "--no-rerun", "-q", "--set", "setpoint.value=[2.5e1, 0.0]",
                    cwd=tmp_path)
    assert ok.returncode == 0, ok.stderr  # 2.5e1 is a number, as YAML 1.2 reads it


def test_video_films_every_mujoco_device_of_the_file(tmp_path):
    pytest.importorskip("mujoco")
    from PIL import Image

    result = dgraph_cli("run", str(ROOT / "graphs" / "talos_standing.yaml"), "--ticks", "60", "-q", "--no-rerun",
                        "--video", "film/standing.gif", "--set", "device.video_fps=100",
                        "--set", "device.video_size=[32, 24]", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "device: video -> film/standing.gif" in result.stdout
    with Image.open(tmp_path / "film" / "standing.gif") as video:
        assert video.size == (32, 24) and video.n_frames == 6  # 60 ms at 100 frames per second
    again = dgraph_cli("run", str(ROOT / "graphs" / "talos_standing.yaml"), "--ticks", "5", "-q", "--no-rerun",
                       "--video", "film/standing.gif", "--set", "device.video_start=1.0", cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    assert "video ->" not in again.stdout, again.stdout  # no frame this run: the file there is the last run's
    result = dgraph_cli("run", PD, "--ticks", "5", "--video", "pd.gif", cwd=tmp_path)
    assert result.returncode == 2
    assert f"{PD}: --video pd.gif: the graph has no MujocoDevice to film" in result.stderr
    assert not (tmp_path / "pd.gif").exists() and not (tmp_path / "out").exists()


def test_serve_keeps_serving_a_web_viewer_that_draws_the_recording_until_ctrl_c(tmp_path, ports):
    """The served web viewer, loaded by headless Chromium after the run, draws the recording (WebGL
    through SwiftShader): its plot area shows the series' colours, which Rerun's welcome page (what
    the viewer shows without a recording) does not. Skipped only outside CI without Chromium; every
    wait has a deadline, and a failure stops the command with SIGTERM (which stops its server)."""
    from tests.browser import Chromium, series_colours, wait_for_series
    from tests.entities.test_rerun_stream import listening

    executable = required_chromium()
    grpc, web = ports
    run = serve_and_keep(tmp_path, grpc, web)
    try:
        said = read_until(run, "until Ctrl-C", timeout=60).splitlines()
        url = next(line for line in said if "until Ctrl-C" in line).split(" at ", 1)[1].split(" until", 1)[0]
        assert url == f"http://127.0.0.1:{web}/?url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3A{grpc}%2Fproxy"
        assert run.poll() is None and listening(grpc) and listening(web)  # the run is over, the server is not
        with Chromium(executable, timeout=30) as browser:
            # measured (1280x800): the welcome page, the same viewer without ?url=, 148 pixels of the
            # plot area in series colours, in 1 hue (the orange icon of its "failed to load examples"
            # notice); the viewer showing this recording (4 plots of 2 series each, their legends)
            # 3100 pixels in 8 hues. Both are measured here, so that the measure is seen to tell them apart.
            browser.open(f"http://127.0.0.1:{web}/")
            time.sleep(2.0)  # the welcome page is drawn within ~1.5 s
            welcome = browser.screenshot()
            (tmp_path / "welcome.png").write_bytes(welcome)
            welcome_pixels, welcome_hues = series_colours(welcome)
            assert welcome_pixels < 1000 or welcome_hues < 4, (welcome_pixels, welcome_hues, tmp_path / "welcome.png")
            browser.open(url)
            png, pixels, hues = wait_for_series(browser, pixels=1000, hues=4, timeout=30)
            (tmp_path / "viewer.png").write_bytes(png)
        assert pixels >= 1000 and hues >= 4, (pixels, hues, welcome_pixels, welcome_hues, tmp_path / "viewer.png")
        run.send_signal(signal.SIGINT)
        assert run.wait(timeout=30) == 0
        assert "Ctrl-C: stopped serving" in run.stderr.read().decode()
        assert "pd_double_integrator: 500 ticks" in run.stdout.read().decode()
        assert listening(grpc) == set() and listening(web) == set()
    finally:
        stop_cli(run, grpc)


def required_chromium() -> str:
    """Chromium's path; without it the test is skipped, or fails when ``CI`` is set (.ci/run installs it)."""
    from tests.browser import chromium_path

    executable = chromium_path()
    if executable is None:
        if os.environ.get("CI"):
            pytest.fail("CI is set and Chromium is missing: .ci/run installs it (apt-get install chromium)")
        pytest.skip("Chromium is not installed (apt-get install chromium)")
    return executable


def test_the_browser_gives_up_at_its_deadline():
    """A DevTools command with no reply (a promise that never settles) raises after ``timeout``
    seconds instead of blocking the test run."""
    from tests.browser import Chromium

    executable = required_chromium()
    with Chromium(executable, timeout=10) as browser:
        browser.open("about:blank")
        assert browser.call("Runtime.evaluate", {"expression": "6 * 7"})["result"]["value"] == 42
        browser.timeout = 0.5
        start = time.monotonic()
        with pytest.raises(TimeoutError, match="no reply to Runtime.evaluate in 0.5 s"):
            browser.call("Runtime.evaluate", {"expression": "new Promise(() => {})", "awaitPromise": True})
        assert time.monotonic() - start < 5


def test_run_and_profile_share_their_options_and_every_command_its_file_argument():
    import argparse

    from dgraph.cli import build_parser

    commands = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)).choices

    def options(command):
        return {name: action.help for action in commands[command]._actions for name in action.option_strings}

    shared = ("--duration", "--ticks", "--set")
    assert {k: options("run")[k] for k in shared} == {k: options("profile")[k] for k in shared}
    for command in ("run", "check", "profile", "show"):
        assert [a.dest for a in commands[command]._actions if not a.option_strings] == ["file"], command
    assert {"--save", "--serve", "--spawn", "--no-rerun", "--bind", "--port", "--web-viewer-port",
            "--keep-serving", "--video"} <= set(options("run")) and "--save" not in options("profile")
