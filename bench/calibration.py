"""Machine calibration for the benchmarks: a fixed pure-Python loop, the machine line, the load.

    from calibration import calibrate, calibration_line
    print(calibration_line(calibrate()))

``calibrate()`` times :func:`reference_loop` (``LOOP_ITERATIONS`` iterations, ``REPEATS``
times) and returns the median nanoseconds per iteration, with the spread and the machine.
A time divided by this figure (``time / ns_per_iteration``, "calibration loops") is how a
timing carries across machines: on a machine twice as fast for the interpreter both halve.
It is a figure for CPython's interpreter speed (our ticks are mostly Python calling numpy,
Pinocchio and ProxQP); headline figures stay ratios against a peer measured in the same run.

**Never edit** :func:`reference_loop`, ``LOOP_ITERATIONS`` or ``REPEATS``: figures measured
with another loop do not compare.

``single_threaded()`` pins BLAS and OpenMP to one thread; it must run before numpy (or any
library linking OpenBLAS or libgomp) is imported, because those read the variables once when
they load. ``BusyMeter`` measures how much CPU other processes took during a measurement.

This module imports nothing outside the standard library.
"""

from __future__ import annotations

import os
import platform
import resource
import statistics
import sys
import time
from pathlib import Path

LOOP_ITERATIONS = 50_000
REPEATS = 21
THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def reference_loop(n: int) -> int:
    """The fixed loop: integer arithmetic, a modulo and a branch per iteration."""
    total = 0
    for i in range(n):
        total = (total + i * 7) % 1_000_003
        if total & 1:
            total += 1
    return total


def cpu_model() -> str:
    """The CPU's model name (``/proc/cpuinfo``), or what ``platform`` knows."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def machine() -> dict[str, object]:
    """CPU model, vCPUs, Python, and the 1-minute load average when the figures were taken."""
    return {"cpu": cpu_model(), "vcpus": os.cpu_count(),
            "python": f"{platform.python_implementation()} {platform.python_version()}",
            "load_1min": os.getloadavg()[0]}


def calibrate(iterations: int = LOOP_ITERATIONS, repeats: int = REPEATS) -> dict[str, object]:
    """Median wall ns per iteration of :func:`reference_loop` over ``repeats`` runs, spread, machine.

    ``cpu_ns_per_iteration`` is the same from the thread's CPU time: well below the wall figure,
    the loop was preempted (another job held the CPU) and the calibration reads the load too.
    """
    reference_loop(iterations // 10)  # warm the interpreter's caches
    wall, cpu = [], []
    for _ in range(repeats):
        start, start_cpu = time.perf_counter_ns(), time.thread_time_ns()
        reference_loop(iterations)
        cpu.append((time.thread_time_ns() - start_cpu) / iterations)
        wall.append((time.perf_counter_ns() - start) / iterations)
    return {"ns_per_iteration": statistics.median(wall), "min": min(wall), "max": max(wall),
            "cpu_ns_per_iteration": statistics.median(cpu), "iterations": iterations, "repeats": repeats,
            **machine()}


def calibration_line(cal: dict[str, object]) -> str:
    """One printable line: the calibration figure and the machine."""
    return (f"calibration: {cal['ns_per_iteration']:.1f} ns per iteration of the reference loop "
            f"(median of {cal['repeats']}, {cal['min']:.1f}-{cal['max']:.1f}; CPU time "
            f"{cal['cpu_ns_per_iteration']:.1f}); machine: {cal['cpu']}, {cal['vcpus']} vCPU, {cal['python']}, "
            f"load {cal['load_1min']:.2f}")


def in_loops(time_ns: float, cal: dict[str, object]) -> float:
    """A time in calibration loops: ``time_ns / ns_per_iteration`` (machine-independent, roughly)."""
    return time_ns / float(cal["ns_per_iteration"])


def single_threaded() -> None:
    """Pin OpenMP, OpenBLAS and MKL to one thread in this process (call before importing numpy)."""
    loaded = [name for name in ("numpy", "scipy", "pinocchio", "proxsuite") if name in sys.modules]
    if loaded:
        raise RuntimeError(f"single_threaded() must run before importing {', '.join(loaded)}")
    os.environ.update(dict.fromkeys(THREAD_VARIABLES, "1"))


def single_threaded_env(base: dict[str, str] | None = None) -> dict[str, str]:
    """A copy of ``base`` (default ``os.environ``) for a child process, BLAS and OpenMP on one thread."""
    env = dict(os.environ if base is None else base)
    env.update(dict.fromkeys(THREAD_VARIABLES, "1"))
    return env


def _busy_seconds() -> float:
    """CPU seconds spent by the whole machine (all CPUs, everything but idle and iowait)."""
    fields = [int(x) for x in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:]]
    idle = fields[3] + fields[4]
    return (sum(fields[:8]) - idle) / os.sysconf("SC_CLK_TCK")


def _own_seconds() -> float:
    """CPU seconds of this process and of its finished children."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


class BusyMeter:
    """How many CPUs other processes kept busy, on average, between ``start()`` and ``stop()``.

    Machine CPU time (``/proc/stat``) minus this process's and its waited-for children's, over
    the wall time: 0 on a quiet machine, about 1 when another job holds a whole vCPU. Linux only
    (elsewhere ``stop()`` returns NaN).
    """

    def start(self) -> BusyMeter:
        """Take the starting readings; returns self."""
        self._wall = time.perf_counter()
        try:
            self._busy = _busy_seconds()
        except (OSError, ValueError):
            self._busy = float("nan")
        self._own = _own_seconds()
        return self

    def stop(self) -> float:
        """Average number of CPUs used by other processes since ``start()``."""
        wall = time.perf_counter() - self._wall
        try:
            busy = _busy_seconds() - self._busy
        except (OSError, ValueError):
            return float("nan")
        return max(0.0, busy - (_own_seconds() - self._own)) / wall if wall > 0 else float("nan")


if __name__ == "__main__":
    print(calibration_line(calibrate()))
