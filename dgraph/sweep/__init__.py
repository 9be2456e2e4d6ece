"""Sweeps over graph-file settings: a grid, or a bisection, of runs of graph files with the
settings ``dgraph run --set`` takes, each run in a fresh process of its own, on this machine or on a
Ray cluster; every outcome (a fall, a divergence, an error are outcomes, not failures of the sweep)
written to a CSV table as it comes, so that an interrupted sweep resumes where it stopped; a
picture at the end. ``dgraph sweep`` is its command.

    >>> from dgraph.sweep import Sweep, run_sweep
    >>> sweep = Sweep(["graphs/pd_double_integrator.yaml"], grid={"kp.gain": [25.0, 1e8]},
    ...               measures=["robot.q[0]"], duration=1.0)
    >>> result = run_sweep(sweep, "out/pd.csv", plot="out/pd.png")     # doctest: +SKIP
    >>> [o.status for o in result.outcomes]                             # doctest: +SKIP
    ['ok', 'diverged']

One concept a module: :mod:`~dgraph.sweep.spec` (what a sweep asks for, its grid),
:mod:`~dgraph.sweep.outcome` (one run in this process, and what came of it),
:mod:`~dgraph.sweep.isolation` (each run in a fresh process), :mod:`~dgraph.sweep.executors`
(a local pool of processes, Ray), :mod:`~dgraph.sweep.plan` (the runs checked before any starts),
:mod:`~dgraph.sweep.table` (the results file), :mod:`~dgraph.sweep.bisection`,
:mod:`~dgraph.sweep.runner` (``run_sweep``) and :mod:`~dgraph.sweep.plot`. Nothing here imports
a robotics library: a run loads its graph file with :func:`dgraph.load`, whose registry finds the
entity types.
"""

from dgraph.sweep.bisection import Threshold
from dgraph.sweep.executors import LocalPool, RayPool, make_pool
from dgraph.sweep.isolation import IsolatedRun, run_isolated
from dgraph.sweep.outcome import STATUSES, Outcome, Run, run_graph
from dgraph.sweep.plan import planned_runs
from dgraph.sweep.runner import SweepResult, run_sweep
from dgraph.sweep.spec import AUTO, Bisection, Sweep, SweepError, bisection_option, grid_axes, grid_axis
from dgraph.sweep.table import ResultsTable, read_table

__all__ = ["AUTO", "STATUSES", "Bisection", "IsolatedRun", "LocalPool", "Outcome", "RayPool", "ResultsTable", "Run",
           "Sweep", "SweepError", "SweepResult", "Threshold", "bisection_option", "grid_axes", "grid_axis", "make_pool",
           "planned_runs", "read_table", "run_graph", "run_isolated", "run_sweep"]
