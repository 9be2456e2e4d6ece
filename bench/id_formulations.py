"""Inverse-dynamics QP with torques eliminated (the library's choice) against torques as variables.

    python bench/id_formulations.py [--ticks 2000] [--warmup 200] [--tau-weight 1e-12] [--json PATH]

1. Record: run the TALOS sway graph (graphs/talos_sway.py) in closed loop in MuJoCo and, at each
   of ``--ticks`` ticks after ``--warmup`` ticks, copy the solver's inputs: the robot state's mass
   matrix and bias forces, the task equations and the active contacts.
2. Replay the recorded problems through three formulations, each with one ProxQP dense object
   reused, with the library's tolerance and proximal parameter (``DEFAULT_EPS_ABS`` 1e-6,
   ``PROXIMAL_RHO`` 1e-8; eps_rel 0, max_iter 1000); the library warm-starts from the previous
   tick's answer as in the loop, the explicit variants from the previous result
   (``WARM_START_WITH_PREVIOUS_RESULT``):

   * ``eliminated``: :class:`InverseDynamicsQP` (x = [a, f]; floating-base dynamics and contact
     rows as equalities; friction rows and torque limits as inequalities; tau = M_j a + h_j -
     (J^T T)_j f recovered after the solve);
   * ``explicit tau, general rows``: x = [a, f, tau]; equalities = full dynamics
     ``M a + h - J^T T f - S^T tau = 0`` and contact rows; inequalities = friction rows and
     ``-tau_max <= tau <= tau_max`` as general rows; cost = the same task terms and
     ``acceleration_weight ||a||^2`` on a, the same force regularisation, plus
     ``tau_weight ||tau||^2`` (``--tau-weight``, default 1e-12, which does not move the optimum
     measurably; 1e-8 already shifts tau by ~1e-2 N m: the force distribution over the sole
     corners is set only by the 1e-5 force regularisation, and a tau term competes with it);
   * ``explicit tau, box bounds``: the same, with the torque limits as ProxQP box constraints
     (``dense.QP(n, n_eq, n_in, box_constraints=True)``; a and f get +-1e20 box bounds).

   The variants are interleaved tick by tick (the order rotates every tick) to spread the VM's
   noise over all of them. Per tick and variant: ``assembly`` (filling H, g, A, b, C, l, u in
   preallocated arrays), ``solve`` (``qp.update`` + ``qp.solve``) and ``recover`` (reading a and
   tau from x: a mat-vec for ``eliminated``, slices otherwise) are timed with ``perf_counter_ns``;
   ``total`` is their sum.
3. Check: max |delta a|, |delta tau| and |delta f| of each explicit variant against
   ``eliminated``, tick by tick, and failures (status not solved, or non-finite x). When daqp
   (an exact dual active-set solver, in the test extra) is installed, every recorded problem is
   also solved exactly (eliminated form, cold), and each variant's distance to that solution is
   reported: it tells a formulation mismatch from ProxQP's tolerance (the force distribution is
   only weakly determined, by the 1e-5 force regularisation).
4. Print a markdown table and the machine; ``--json PATH`` writes the numbers.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import platform
import shlex
import statistics
import sys
import time
from pathlib import Path

import numpy as np
import proxsuite
from calibration import calibrate, calibration_line

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "graphs"))

from dgraph.control.contact import ContactConstraint  # noqa: E402
from dgraph.control.equation import TaskEquation  # noqa: E402
from dgraph.control.inverse_dynamics import DEFAULT_EPS_ABS, PROXIMAL_RHO, InverseDynamicsQP  # noqa: E402
from dgraph.control.proxqp import INFINITY  # noqa: E402

EPS_ABS = DEFAULT_EPS_ABS
MAX_ITERATIONS = 1000


# -- 1. recording -------------------------------------------------------------------------------
@dataclasses.dataclass(slots=True)
class Problem:
    """One tick's solver inputs (copies), and what the closed-loop solver returned."""

    mass_matrix: np.ndarray
    bias_forces: np.ndarray
    tasks: list[TaskEquation]
    contacts: list[ContactConstraint]
    closed_loop_tau: np.ndarray
    closed_loop_status: int


def _copy_task(task: TaskEquation) -> TaskEquation:
    return TaskEquation(task.matrix.copy(), task.vector.copy(), task.weight.copy())


def _copy_contact(contact: ContactConstraint) -> ContactConstraint:
    return dataclasses.replace(contact, **{f.name: getattr(contact, f.name).copy()
                                           for f in dataclasses.fields(contact)
                                           if isinstance(getattr(contact, f.name), np.ndarray)})


def record(ticks: int, warmup: int) -> tuple[list[Problem], dict]:
    """Run the TALOS sway closed loop and copy the solver's inputs at ``ticks`` ticks."""
    import talos_sway

    graph = talos_sway.build(record=False)
    problems = []
    with graph:
        graph.run(ticks=warmup)
        solver, robot = graph["solver"], graph["robot"]
        for _ in range(ticks):
            t = graph.t
            state = robot.state(t)
            tasks = [inp(t) for inp in solver._task_inputs]
            contacts = [c for c in (inp(t) for inp in solver._contact_inputs) if c.active]
            solution = solver.solution(t)  # computed now and cached: the tick below reuses it
            problems.append(Problem(state.mass_matrix.copy(), state.bias_forces.copy(),
                                    [_copy_task(task) for task in tasks], [_copy_contact(c) for c in contacts],
                                    np.array(solution.tau, copy=True), int(solution.status)))
            graph.run(ticks=1)
        fallen = bool(graph["device"].fallen(graph.t))
        info = {"nv": solver.nv, "n_unactuated": solver.n_unactuated,
                "effort_limit": solver._qp.effort_limit.copy(), "acceleration_weight": solver._qp.acceleration_weight,
                "fallen": fallen, "end_tick": graph.t}
    return problems, info


# -- 2. formulations ----------------------------------------------------------------------------
def _new_qp(n: int, n_eq: int, n_in: int, box: bool = False):
    qp = proxsuite.proxqp.dense.QP(n, n_eq, n_in, box_constraints=True) if box else \
        proxsuite.proxqp.dense.QP(n, n_eq, n_in)
    qp.settings.eps_abs = EPS_ABS
    qp.settings.eps_rel = 0.0
    qp.settings.max_iter = MAX_ITERATIONS
    qp.settings.default_rho = PROXIMAL_RHO
    # from the previous result: what the library does with an explicit guess when it solves once per tick
    qp.settings.initial_guess = proxsuite.proxqp.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
    return qp


class Eliminated:
    """The library's formulation: :meth:`InverseDynamicsQP.assemble`, then the ProxQP problem of
    its workspace *with* the torque-limit rows (the library solves without them unless a limit
    binds; here the formulations are compared with the limits as rows on every tick)."""

    name = "eliminated (library)"

    def __init__(self, nv: int, n_unactuated: int, effort_limit: np.ndarray, acceleration_weight: float):
        self.lib = InverseDynamicsQP(nv, n_unactuated, effort_limit, eps_abs=EPS_ABS, max_iterations=MAX_ITERATIONS,
                                     acceleration_weight=acceleration_weight)
        self.nv, self.n_unactuated, self.n_actuated = nv, n_unactuated, nv - n_unactuated
        self.ws = None

    def sizes(self) -> tuple[int, int, int]:
        return self.ws.H.shape[0], self.ws.A.shape[0], self.ws.C.shape[0]

    def assemble(self, p: Problem) -> None:
        self.ws = self.lib.assemble(p.mass_matrix, p.bias_forces, p.tasks, p.contacts)

    def solve(self) -> None:
        self.qp = self.ws.limited_qp(self.lib)
        self.qp.solve(self.ws.full, None)  # no tick: warm-started from the previous problem's answer

    def recover(self, p: Problem) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        x = self.qp.qp.results.x.copy()
        tau = self.ws.torque_rows @ x + p.bias_forces[self.n_unactuated:]
        return x[:self.nv], x[self.nv:], tau

    def result(self) -> tuple[str, int]:
        info = self.qp.qp.results.info
        return info.status.name, int(info.iter)


class Explicit:
    """x = [a, f, tau] with the full dynamics as equalities (module docstring).

    The matrices are preallocated for one contact set; the constant blocks (``-S^T`` in A, the
    tau rows of C or the box bounds, the tau regularisation) are written once, and each tick
    overwrites only the blocks that change.
    """

    def __init__(self, nv: int, n_unactuated: int, effort_limit: np.ndarray, acceleration_weight: float,
                 tau_weight: float, box: bool):
        self.nv, self.n_unactuated, self.n_actuated = nv, n_unactuated, nv - n_unactuated
        self.effort_limit = np.asarray(effort_limit, dtype=float)
        self.acceleration_weight, self.tau_weight, self.box = acceleration_weight, tau_weight, box
        self.name = "explicit tau, box bounds" if box else "explicit tau, general rows"
        self.key = None
        self.initialised = False

    def sizes(self) -> tuple[int, int, int]:
        return self.n, self.A.shape[0], self.C.shape[0]

    def _allocate(self, contacts: list[ContactConstraint]) -> None:
        nv, na = self.nv, self.n_actuated
        self.nf = sum(c.n_forces for c in contacts)
        n = self.n = nv + self.nf + na
        n_eq = nv + 6 * len(contacts)
        n_friction = sum(len(c.friction_lower) for c in contacts)
        n_in = n_friction if self.box else n_friction + na
        self.H, self.g = np.zeros((n, n)), np.zeros(n)
        self.A, self.b = np.zeros((n_eq, n)), np.zeros(n_eq)
        self.C, self.lower, self.upper = np.zeros((n_in, n)), np.zeros(n_in), np.zeros(n_in)
        tau = slice(nv + self.nf, n)
        self.A[self.n_unactuated:nv, tau] = -np.eye(na)  # - S^T tau (S selects the actuated rows)
        self.H[tau, tau] = 2.0 * self.tau_weight * np.eye(na)
        if self.box:
            self.l_box, self.u_box = np.full(n, -INFINITY), np.full(n, INFINITY)
            self.l_box[tau], self.u_box[tau] = -self.effort_limit, self.effort_limit
        else:
            self.C[n_friction:, tau] = np.eye(na)
            self.lower[n_friction:], self.upper[n_friction:] = -self.effort_limit, self.effort_limit
        self.qp = _new_qp(n, n_eq, n_in, self.box)
        self.initialised = False

    def assemble(self, p: Problem) -> None:
        nv = self.nv
        key = tuple(c.n_forces for c in p.contacts) + tuple(len(c.friction_lower) for c in p.contacts)
        if key != self.key:
            self._allocate(p.contacts)
            self.key = key
        H, g, A, b, C, lower, upper = self.H, self.g, self.A, self.b, self.C, self.lower, self.upper
        H_aa = H[:nv, :nv]
        H_aa.fill(0.0)
        g[:nv] = 0.0
        for task in p.tasks:  # the same task terms as InverseDynamicsQP.assemble
            weighted = task.matrix * task.weight[:, None]
            H_aa += 2.0 * (task.matrix.T @ weighted)
            g[:nv] -= 2.0 * (weighted.T @ task.vector)
        H_aa[np.diag_indices(nv)] += 2.0 * self.acceleration_weight
        A[:nv, :nv] = p.mass_matrix  # M a - J^T T f - S^T tau = -h
        b[:nv] = -p.bias_forces
        row_eq, row_in, col = nv, 0, nv
        for contact in p.contacts:
            k, m = contact.n_forces, len(contact.friction_lower)
            forces = slice(col, col + k)
            A[:nv, forces] = -(contact.jacobian.T @ contact.force_generator)
            A[row_eq:row_eq + 6, :nv] = contact.jacobian
            b[row_eq:row_eq + 6] = contact.motion_rhs
            C[row_in:row_in + m, forces] = contact.friction_matrix
            lower[row_in:row_in + m] = np.maximum(contact.friction_lower, -INFINITY)
            upper[row_in:row_in + m] = np.minimum(contact.friction_upper, INFINITY)
            H[forces, forces][np.diag_indices(k)] = 2.0 * contact.force_weight
            row_eq, row_in, col = row_eq + 6, row_in + m, col + k

    def solve(self) -> None:
        args = (self.H, self.g, self.A, self.b, self.C, self.lower, self.upper)
        if self.box:
            args += (self.l_box, self.u_box)
        if self.initialised:  # the library's ProxQP settings: preconditioner kept from the first solve
            self.qp.update(*args, update_preconditioner=False)
        else:
            self.qp.init(*args)
            self.initialised = True
        self.qp.solve()

    def recover(self, p: Problem) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        x = self.qp.results.x.copy()
        return x[:self.nv], x[self.nv:self.nv + self.nf], x[self.nv + self.nf:]

    def result(self) -> tuple[str, int]:
        info = self.qp.results.info
        return info.status.name, int(info.iter)


# -- 3. replay and checks -----------------------------------------------------------------------
def replay(problems: list[Problem], variants: list) -> dict[str, dict]:
    """Solve every problem with every variant, interleaved; times in ns, answers per tick."""
    runs = {v.name: {"assembly": [], "solve": [], "recover": [], "iterations": [], "failures": 0,
                     "a": [], "f": [], "tau": []} for v in variants}
    for v in variants:  # cold init outside the timing (ProxQP init is ~1 ms)
        v.assemble(problems[0])
        v.solve()
    clock = time.perf_counter_ns
    for k, p in enumerate(problems):
        shift = k % len(variants)
        for v in variants[shift:] + variants[:shift]:
            t0 = clock()
            v.assemble(p)
            t1 = clock()
            v.solve()
            t2 = clock()
            a, f, tau = v.recover(p)
            t3 = clock()
            run = runs[v.name]
            run["assembly"].append(t1 - t0)
            run["solve"].append(t2 - t1)
            run["recover"].append(t3 - t2)
            status, iterations = v.result()
            run["iterations"].append(iterations)
            if status != "PROXQP_SOLVED" or not (np.isfinite(a).all() and np.isfinite(tau).all()):
                run["failures"] += 1
            run["a"].append(a)
            run["f"].append(f)
            run["tau"].append(tau)
    return runs


def percentile(values: list[float], q: float) -> float:
    return float(np.percentile(np.asarray(values, dtype=float), q))


def summarise(runs: dict[str, dict], variants: list, reference: str) -> list[dict]:
    ref = runs[reference]
    rows = []
    for v in variants:
        run = runs[v.name]
        total = [a + s + r for a, s, r in zip(run["assembly"], run["solve"], run["recover"], strict=True)]
        delta = {key: max_delta(run, ref, key) for key in ("a", "f", "tau")}
        n, n_eq, n_in = v.sizes()
        rows.append({
            "variant": v.name, "n": n, "n_eq": n_eq, "n_in": n_in,
            "box": n if getattr(v, "box", False) else 0,
            "assembly_median_us": statistics.median(run["assembly"]) / 1e3,
            "solve_median_us": statistics.median(run["solve"]) / 1e3,
            "recover_median_us": statistics.median(run["recover"]) / 1e3,
            "total_median_us": statistics.median(total) / 1e3,
            "total_p90_us": percentile(total, 90) / 1e3,
            "total_p99_us": percentile(total, 99) / 1e3,
            "solve_p99_us": percentile(run["solve"], 99) / 1e3,
            "iterations_median": statistics.median(run["iterations"]),
            "iterations_max": max(run["iterations"]),
            "max_abs_delta_a": delta["a"], "max_abs_delta_tau": delta["tau"], "max_abs_delta_f": delta["f"],
            "failures": run["failures"],
        })
    return rows


def exact_reference(problems: list[Problem], nv: int, n_unactuated: int, effort_limit: np.ndarray,
                    acceleration_weight: float) -> dict[str, list[np.ndarray]] | None:
    """daqp's exact solution of every problem (eliminated form, assembled by the library)."""
    try:
        import daqp
    except ImportError:
        return None
    lib = InverseDynamicsQP(nv, n_unactuated, effort_limit, acceleration_weight=acceleration_weight)
    exact = {"a": [], "f": [], "tau": [], "failures": 0}
    for p in problems:
        ws = lib.assemble(p.mass_matrix, p.bias_forces, p.tasks, p.contacts)
        A = np.vstack([ws.A, ws.C])
        upper = np.concatenate([ws.b, ws.upper])
        lower = np.concatenate([ws.b, ws.lower])
        sense = np.concatenate([np.full(len(ws.b), 5), np.zeros(len(ws.upper))]).astype(np.int32)
        x, _, exitflag, _ = daqp.solve(ws.H, ws.g, A, upper, lower, sense)
        exact["failures"] += int(exitflag != 1)
        exact["a"].append(x[:nv])
        exact["f"].append(x[nv:])
        exact["tau"].append(ws.torque_rows @ x + p.bias_forces[n_unactuated:])
    return exact


def max_delta(run: dict, ref: dict, key: str) -> float:
    return max(float(np.abs(x - y).max()) for x, y in zip(run[key], ref[key], strict=True))


# -- 4. report ----------------------------------------------------------------------------------
def machine() -> dict[str, str]:
    cpu = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import os

    import pinocchio
    return {"cpu": cpu, "cpus": str(os.cpu_count()), "python": platform.python_version(),
            "proxsuite": proxsuite.__version__, "numpy": np.__version__, "pinocchio": pinocchio.__version__,
            "platform": platform.platform()}


def table(rows: list[dict]) -> str:
    lines = ["| variant | n / n_eq / n_in | assembly median µs | solve median µs | total median µs | total p99 µs "
             "| iterations median (max) | max abs Δa | max abs Δtau | max abs Δf | failures |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        sizes = f"{r['n']} / {r['n_eq']} / {r['n_in']}" + (f" + {r['box']} box" if r["box"] else "")
        deltas = ("—", "—", "—") if r["variant"].startswith("eliminated") else \
            tuple(f"{r[k]:.1e}" for k in ("max_abs_delta_a", "max_abs_delta_tau", "max_abs_delta_f"))
        lines.append(f"| {r['variant']} | {sizes} | {r['assembly_median_us']:.1f} | {r['solve_median_us']:.1f} "
                     f"| {r['total_median_us']:.1f} | {r['total_p99_us']:.1f} "
                     f"| {r['iterations_median']:g} ({r['iterations_max']}) | {deltas[0]} | {deltas[1]} | {deltas[2]} "
                     f"| {r['failures']} |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=int, default=2000, help="problems recorded and replayed")
    parser.add_argument("--warmup", type=int, default=200, help="closed-loop ticks before recording")
    parser.add_argument("--tau-weight", type=float, default=1e-12, help="regularisation of tau (explicit variants)")
    parser.add_argument("--json", type=Path, help="write the numbers to this file")
    args = parser.parse_args()

    cal = calibrate()
    start = time.perf_counter()
    problems, info = record(args.ticks, args.warmup)
    record_s = time.perf_counter() - start
    nv, n_unactuated = info["nv"], info["n_unactuated"]
    contact_sets = sorted({tuple(c.name for c in p.contacts) for p in problems})
    limits, weight = info["effort_limit"], info["acceleration_weight"]
    variants = [Eliminated(nv, n_unactuated, limits, weight),
                Explicit(nv, n_unactuated, limits, weight, args.tau_weight, box=False),
                Explicit(nv, n_unactuated, limits, weight, args.tau_weight, box=True)]
    start = time.perf_counter()
    runs = replay(problems, variants)
    replay_s = time.perf_counter() - start
    reference = variants[0].name
    rows = summarise(runs, variants, reference)
    closed_loop_delta = max(float(np.abs(tau - p.closed_loop_tau).max())
                            for tau, p in zip(runs[reference]["tau"], problems, strict=True))
    closed_loop_failures = sum(p.closed_loop_status != 0 for p in problems)
    exact = exact_reference(problems, nv, n_unactuated, info["effort_limit"], info["acceleration_weight"])
    if exact is not None:
        for row, v in zip(rows, variants, strict=True):
            for key in ("a", "tau", "f"):
                row[f"exact_max_abs_delta_{key}"] = max_delta(runs[v.name], exact, key)
    tau_max = max(float(np.abs(tau).max()) for tau in runs[reference]["tau"])
    at_limit = sum(bool((np.abs(tau) >= info["effort_limit"] - 1e-6).any()) for tau in runs[reference]["tau"])

    env = machine()
    command = shlex.join([sys.executable if not sys.executable.startswith(str(ROOT)) else
                          str(Path(sys.executable).relative_to(ROOT)), *sys.argv])
    print(f"## Inverse-dynamics QP formulations, TALOS sway, {len(problems)} recorded ticks "
          f"(after {args.warmup} warm-up)\n")
    print(table(rows))
    print()
    print(f"- ProxQP dense, one object per variant, warm start from the previous result, preconditioner kept "
          f"from the first solve, the library's eps_abs {EPS_ABS:g} and rho {PROXIMAL_RHO:g}, "
          f"eps_rel 0, max_iter {MAX_ITERATIONS}; cold init outside the timing; variants interleaved per tick.")
    print(f"- cost: same task terms, acceleration_weight {info['acceleration_weight']:g}, same force weights; "
          f"explicit variants add tau_weight {args.tau_weight:g} * ||tau||^2.")
    print("- assembly = filling H, g, A, b, C, l, u; solve = qp.update + qp.solve; total = assembly + solve + "
          "recovering a and tau (eliminated: C_j x + h_j, median "
          f"{rows[0]['recover_median_us']:.1f} µs; explicit: slices).")
    print("- Δ = explicit minus eliminated, max over ticks and components (a in rad/s², tau in N m, f in N).")
    print(f"- contact sets seen: {contact_sets}; closed loop: {closed_loop_failures} solver failures, "
          f"fallen {info['fallen']}; replayed eliminated vs closed-loop tau: max abs Δ {closed_loop_delta:.1e} N m "
          f"(warm-start history differs); max abs tau {tau_max:.1f} N m, ticks with a torque at its limit: "
          f"{at_limit}.")
    if exact is not None:
        print(f"\nDistance to the exact solution (daqp, eliminated form, {exact['failures']} failures):\n")
        print("| variant | max abs Δa | max abs Δtau | max abs Δf |\n|---|---|---|---|")
        for r in rows:
            print(f"| {r['variant']} | {r['exact_max_abs_delta_a']:.1e} | {r['exact_max_abs_delta_tau']:.1e} "
                  f"| {r['exact_max_abs_delta_f']:.1e} |")
        print()
    print(f"- time: recording {record_s:.1f} s, replay {replay_s:.1f} s.")
    print(f"- machine: {env['cpu']} ({env['cpus']} CPUs), Python {env['python']}, proxsuite {env['proxsuite']}, "
          f"numpy {env['numpy']}, pinocchio {env['pinocchio']}")
    print(f"- {calibration_line(cal)}")
    print(f"- command: `{command}`")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({
            "ticks": len(problems), "warmup": args.warmup, "tau_weight": args.tau_weight, "eps_abs": EPS_ABS,
            "eps_rel": 0.0, "max_iter": MAX_ITERATIONS, "rows": rows, "contact_sets": contact_sets,
            "closed_loop_failures": closed_loop_failures,
            "exact_reference": None if exact is None else {"solver": "daqp", "failures": exact["failures"]},
            "closed_loop_max_abs_delta_tau": closed_loop_delta,
            "fallen": info["fallen"], "ticks_with_torque_at_limit": at_limit, "record_s": record_s,
            "replay_s": replay_s, "machine": env, "calibration": cal, "command": command}, indent=2))
        print(f"- wrote {args.json}")


if __name__ == "__main__":
    main()
