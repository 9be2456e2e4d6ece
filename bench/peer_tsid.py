"""The TSID 1.10 peer of the TALOS whole-body benchmark, run in .venv-tsid (bench/setup_tsid.sh).

    bash bench/setup_tsid.sh
    .venv-tsid/bin/python bench/peer_tsid.py [--ticks 5000] [--solver HQuadProgFast|HQuadProg]
                                             [--config path.json]   -> one JSON object on stdout

It does not import dgraph (other venv). The model is ``example_robot_data.load("talos").model``
(armature 0.1 from the SRDF, 0 on the grippers), given to ``tsid.RobotWrapper(model, FLOATING_BASE_SYSTEM, False)``,
so TSID and dgraph use the same model. The start state is ``half_sitting`` with v = 0.

Each tick k (t = k * dt, k = 0 at the first warm-up tick):
  1. reference: CoM sample = com0 + offset + A sin(2 pi f t), with its 1st and 2nd derivative;
  2. ``HQPData = formulation.computeProblemData(t, q, v)``          -> problem_data_us
  3. ``sol = solver.solve(HQPData)``                                -> solve_us
  4. ``tau = formulation.getActuatorForces(sol)``, ``dv = formulation.getAccelerations(sol)``
  5. the next state: with a ``simulator`` in the config, the MuJoCo closed loop dgraph's tick is
     measured in (``ctrl = tau``, ``mj_step``, ``q, v`` read back from ``qpos, qvel``); without,
     semi-implicit Euler: ``v += dv dt; q = pin.integrate(model, q, v dt)``.
``tick_us`` = (2) + (3); ``loop_us`` = (1) to (5). Only the ``ticks`` ticks after ``warmup`` count.
Timing is ``time.perf_counter_ns``. A tick fails when ``sol.status != 0``; the loop then keeps
the previous dv and tau.

Config (JSON, ``--config``): deep-merged over DEFAULT_CONFIG below, so give only what differs.
A task whose entry is ``null`` or has ``"enabled": false`` is left out (``contacts`` cannot be).
Units: SI (m, N, s, rad); gains in 1/s^2 (kp) and 1/s (kd); ``kd: null`` means 2 sqrt(kp).

  dt, warmup, ticks                 s, ticks, ticks (--ticks overrides ``ticks``)
  solver                            "HQuadProgFast" | "HQuadProg" (--solver overrides)
  armature                          null: keep the model's (0.1, grippers 0); a number: set all joints
  reference_posture                 key of model.referenceConfigurations ("half_sitting")
  contacts.frames                   Contact6d frames, one contact each (ankle joint frames)
  contacts.lxp, lxn, lyp, lyn, lz   sole box in the frame: corners (+lxp|-lxn, +lyp|-lyn, -lz)
  contacts.normal                   contact normal in the frame
  contacts.mu, fMin, fMax           friction coefficient, min/max normal force per foot (N)
  contacts.kp, kd                   scalar gains of the 6d contact motion constraint
  contacts.w_force_reg              weight of the force regularisation (f -> 0) cost
  contacts.motion_weight            weight of the contact motion task, used if not hard
  contacts.hard                     true: contact motion is a level-0 equality (TSID default)
  com.weight, kp, kd                TaskComEquality, level 1 (kp, kd scalar or 3-vector)
  com.offset                        added to the initial CoM (m, 3)
  com.sway_amplitude                A (m, 3); com.sway_frequency f (Hz)
  posture.weight                    TaskJointPosture, level 1, reference = reference_posture
  posture.kp                        scalar, list of na (32), or {"legs": 6, "torso": 2,
                                    "arms": 8 (7 + gripper), "head": 2} per-group lists;
                                    legs/arms apply to left then right
  posture.kd                        same forms as kp, or null (2 sqrt(kp))
  waist.frame, weight, kp, kd       TaskSE3Equality, level 1, reference = its initial pose
  waist.mask                        6 values (linear xyz, angular xyz); default orientation only
  waist.local_frame                 TSID's useLocalFrame (true is TSID's default)
  momentum.weight, kp, kd           TaskAMEquality (centroidal angular momentum), level 1,
                                    reference L = 0, dL = 0; disabled by default
  frames                            list of extra TaskSE3Equality tasks, level 1, each
                                    {name, frame, mask, weight, kp, kd, local_frame}, reference =
                                    the frame's initial pose (default: none)
  simulator                         null (semi-implicit Euler) or {model: path of a MuJoCo binary
                                    model (mj_saveModel; needs the same mujoco version), q0: start
                                    configuration (Pinocchio order), qpos_index, qvel_index,
                                    ctrl_index, free_qpos, free_dof: the maps of dgraph's
                                    dgraph_sim.conventions.JointMap}

Output keys: versions{tsid,libtsid,pinocchio,eigenpy,numpy,python}, solver, threads_env (the
OMP/OpenBLAS/MKL thread variables it ran with), model{nq,nv,na,
mass_kg,armature}, nVar, nEq, nIn, tasks (names), ticks, warmup, dt,
problem_data_us/solve_us/tick_us/loop_us as {median,p90,p99,mean,min,max}, failures,
com_error_final_m, com_error_max_m, com_error_rms_m (|com - ref| over the counted ticks),
mean_sum_fz_N, m_g_N, fz_ratio, tau_max_abs_Nm, base_height_min_m, loop ("mujoco" or
"euler"), config (the effective one).
"""

from __future__ import annotations

import warnings

warnings.simplefilter("ignore", RuntimeWarning)  # "to-Python converter ... already registered"

import argparse  # noqa: E402
import copy  # noqa: E402
import importlib.metadata as md  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import os  # noqa: E402
import platform  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import example_robot_data as erd  # noqa: E402
import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402
import tsid  # noqa: E402

DEFAULT_CONFIG: dict = {
    "dt": 1e-3,
    "warmup": 100,
    "ticks": 5000,
    "solver": "HQuadProgFast",
    "armature": None,
    "reference_posture": "half_sitting",
    "contacts": {
        "frames": ["leg_left_6_joint", "leg_right_6_joint"],
        "lxp": 0.10, "lxn": 0.11, "lyp": 0.069, "lyn": 0.069, "lz": 0.107,
        "normal": [0.0, 0.0, 1.0],
        "mu": 0.3, "fMin": 5.0, "fMax": 1000.0,
        "kp": 30.0, "kd": None,
        "w_force_reg": 1e-5,
        "motion_weight": 1.0,
        "hard": True,
    },
    "com": {
        "enabled": True, "weight": 1e3, "kp": 20.0, "kd": 3.0,
        "offset": [0.0, 0.0, 0.0],
        "sway_amplitude": [0.0, 0.05, 0.0], "sway_frequency": 0.5,
    },
    "posture": {
        "enabled": True, "weight": 0.1,
        "kp": {"legs": [10, 5, 5, 1, 10, 10], "torso": [100, 100],
               "arms": [50, 10, 10, 10, 50, 10, 10, 10], "head": [100, 100]},
        "kd": None,
    },
    "waist": {
        "enabled": True, "frame": "base_link", "weight": 1.0, "kp": 100.0, "kd": 20.0,
        "mask": [0, 0, 0, 1, 1, 1], "local_frame": True,
    },
    "momentum": {"enabled": False, "weight": 0.02, "kp": 10.0, "kd": 0.0},
    "frames": [],
    "simulator": None,
}

SOLVERS = {"HQuadProgFast": tsid.SolverHQuadProgFast, "HQuadProg": tsid.SolverHQuadProg}


def merge(base: dict, over: dict) -> dict:
    out = copy.deepcopy(base)
    for key, value in over.items():
        if key not in out:
            raise SystemExit(f"peer_tsid: unknown config key {key!r}")
        if isinstance(out[key], dict) and isinstance(value, dict):
            out[key] = merge(out[key], value)
        else:
            out[key] = value
    return out


def enabled(section) -> bool:
    return section is not None and section.get("enabled", True)


def vector(gain, n: int) -> np.ndarray:
    g = np.asarray(gain, dtype=float)
    return np.full(n, float(g)) if g.ndim == 0 else g.reshape(n).copy()


def kd_of(kp: np.ndarray, kd) -> np.ndarray:
    return 2.0 * np.sqrt(kp) if kd is None else vector(kd, kp.size)


def posture_gain(gain, model: pin.Model, na: int) -> np.ndarray:
    """Scalar, na-list, or per-group dict (legs, torso, arms, head) in model joint order."""
    if not isinstance(gain, dict):
        return vector(gain, na)
    out = np.full(na, np.nan)
    for j in range(2, model.njoints):  # skip universe and the free flyer
        name, idx = model.names[j], model.joints[j].idx_v - 6
        if name.startswith("leg_"):
            group, k = "legs", int(name.split("_")[2]) - 1
        elif name.startswith("torso_"):
            group, k = "torso", int(name.split("_")[1]) - 1
        elif name.startswith("arm_"):
            group, k = "arms", int(name.split("_")[2]) - 1
        elif name.startswith("gripper_"):
            group, k = "arms", 7
        elif name.startswith("head_"):
            group, k = "head", int(name.split("_")[1]) - 1
        else:
            raise SystemExit(f"peer_tsid: joint {name} is in no posture gain group")
        out[idx] = gain[group][k]
    assert not np.isnan(out).any()
    return out


def add_motion_task(formulation: tsid.InverseDynamicsFormulationAccForce, task: object, cfg: dict,
                    size: int) -> object:
    """``task`` with the config's gains (``kd`` null: ``2 sqrt(kp)``), added at level 1 with its weight."""
    kp = vector(cfg["kp"], size)
    task.setKp(kp)
    task.setKd(kd_of(kp, cfg["kd"]))
    formulation.addMotionTask(task, float(cfg["weight"]), 1, 0.0)
    return task


def add_se3_task(formulation: tsid.InverseDynamicsFormulationAccForce, robot: tsid.RobotWrapper,
                 data: pin.Data, cfg: dict) -> tsid.TaskSE3Equality:
    """A TaskSE3Equality on ``cfg["frame"]`` (level 1), held at the frame's initial pose."""
    model = robot.model()
    task = tsid.TaskSE3Equality(cfg["name"], robot, cfg["frame"])
    task.setMask(np.asarray(cfg["mask"], dtype=float))
    task.useLocalFrame(bool(cfg["local_frame"]))
    add_motion_task(formulation, task, cfg, 6)
    h0 = robot.framePosition(data, model.getFrameId(cfg["frame"]))
    task.setReference(tsid.TrajectorySE3Constant(f"traj-{cfg['name']}", h0).computeNext())
    return task


def stats(values_ns: list[int]) -> dict[str, float]:
    us = np.asarray(values_ns, dtype=float) * 1e-3
    return {"median": float(np.median(us)), "p90": float(np.percentile(us, 90)),
            "p99": float(np.percentile(us, 99)), "mean": float(us.mean()),
            "min": float(us.min()), "max": float(us.max())}


class Simulator:
    """The MuJoCo closed loop of the config's ``simulator`` entry: the torques go to ``ctrl``, one
    ``mj_step`` per tick, and ``(q, v)`` come back in Pinocchio's conventions (``qpos`` and
    ``qvel`` permuted, the base's linear velocity turned from the world frame to the base frame)."""

    def __init__(self, spec: dict):
        import mujoco

        self.mujoco = mujoco
        self.model = mujoco.MjModel.from_binary_path(spec["model"])
        self.data = mujoco.MjData(self.model)
        self.qpos_index, self.qvel_index, self.ctrl_index = (np.array(spec[key], dtype=np.intp) for key in (
            "qpos_index", "qvel_index", "ctrl_index"))
        self.base_quat = slice(int(spec["free_qpos"]) + 3, int(spec["free_qpos"]) + 7)
        self.data.qpos[self.qpos_index] = spec["q0"]
        mujoco.mj_forward(self.model, self.data)
        self._conjugate, self._linear = np.zeros(4), np.zeros(3)

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        """``(q, v)`` of the simulated robot."""
        d, mujoco = self.data, self.mujoco
        q, v = d.qpos[self.qpos_index], d.qvel[self.qvel_index]
        mujoco.mju_negQuat(self._conjugate, d.qpos[self.base_quat])
        mujoco.mju_rotVecQuat(self._linear, v[:3].copy(), self._conjugate)
        v[:3] = self._linear
        return q, v

    def step(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Apply ``tau`` (actuated order) for one step; the new ``(q, v)``."""
        self.data.ctrl[:] = tau[self.ctrl_index]
        self.mujoco.mj_step(self.model, self.data)
        return self.state()


def run(cfg: dict) -> dict:
    model = erd.load("talos").model
    if cfg["armature"] is not None:
        model.armature[6:] = float(cfg["armature"])
    robot = tsid.RobotWrapper(model, tsid.FLOATING_BASE_SYSTEM, False)
    model = robot.model()
    na, dt = robot.na, float(cfg["dt"])
    simulator = Simulator(cfg["simulator"]) if cfg["simulator"] else None
    if simulator is None:
        q = np.array(model.referenceConfigurations[cfg["reference_posture"]], dtype=float)
        v = np.zeros(robot.nv)
    else:
        q, v = simulator.state()

    formulation = tsid.InverseDynamicsFormulationAccForce("tsid", robot, False)
    formulation.computeProblemData(0.0, q, v)
    data = formulation.data()  # a copy (the binding returns by value): never refreshed later
    com_data = model.createData()
    tasks: list[str] = []

    c = cfg["contacts"]
    points = np.array([[c["lxp"], -c["lxn"], -c["lxn"], c["lxp"]],
                       [-c["lyn"], -c["lyn"], c["lyp"], c["lyp"]],
                       [-c["lz"]] * 4], dtype=float)
    contacts = []
    for frame in c["frames"]:
        name = f"contact_{frame}"
        contact = tsid.Contact6d(name, robot, frame, points, np.asarray(c["normal"], float),
                                 float(c["mu"]), float(c["fMin"]), float(c["fMax"]))
        kp = vector(c["kp"], 6)
        contact.setKp(kp)
        contact.setKd(kd_of(kp, c["kd"]))
        contact.setReference(robot.framePosition(data, model.getFrameId(frame)))
        formulation.addRigidContact(contact, float(c["w_force_reg"]), float(c["motion_weight"]),
                                    not c["hard"])
        contacts.append(contact)
        tasks.append(name)

    com_cfg = cfg["com"]
    com_task = com_sample = None
    if enabled(com_cfg):
        com_task = add_motion_task(formulation, tsid.TaskComEquality("task-com", robot), com_cfg, 3)
        com_sample = tsid.TrajectorySample(3)
        tasks.append("task-com")
    com0 = robot.com(data).copy() + np.asarray(com_cfg["offset"] if com_cfg else [0, 0, 0], float)
    amp = np.asarray(com_cfg["sway_amplitude"] if com_cfg else [0, 0, 0], float)
    omega = 2.0 * math.pi * float(com_cfg["sway_frequency"] if com_cfg else 0.0)

    p_cfg = cfg["posture"]
    if enabled(p_cfg):
        posture = tsid.TaskJointPosture("task-posture", robot)
        kp = posture_gain(p_cfg["kp"], model, na)
        posture.setKp(kp)
        posture.setKd(2.0 * np.sqrt(kp) if p_cfg["kd"] is None
                      else posture_gain(p_cfg["kd"], model, na))
        formulation.addMotionTask(posture, float(p_cfg["weight"]), 1, 0.0)
        posture.setReference(tsid.TrajectoryEuclidianConstant("traj-posture", q[7:]).computeNext())
        tasks.append("task-posture")

    se3_cfgs = ([{"name": "task-waist", **cfg["waist"]}] if enabled(cfg["waist"]) else []) + cfg["frames"]
    # the formulation keeps C++ references only: the Python task objects must outlive the loop
    se3_tasks = [add_se3_task(formulation, robot, data, f_cfg) for f_cfg in se3_cfgs]
    tasks.extend(task.name for task in se3_tasks)

    m_cfg = cfg["momentum"]
    if enabled(m_cfg):
        momentum = add_motion_task(formulation, tsid.TaskAMEquality("task-am", robot), m_cfg, 3)
        momentum.setReference(tsid.TrajectorySample(3))  # L* = 0, dL* = 0
        tasks.append("task-am")

    solver = SOLVERS[cfg["solver"]](f"solver-{cfg['solver']}")
    solver.resize(formulation.nVar, formulation.nEq, formulation.nIn)

    warmup, ticks = int(cfg["warmup"]), int(cfg["ticks"])
    t_data, t_solve, t_loop = [], [], []
    com_err, sum_fz, failures = [], [], 0
    dv = np.zeros(robot.nv)
    tau = np.zeros(na)
    tau_max = 0.0
    base_height_min = math.inf
    clock = time.perf_counter_ns
    integrate = pin.integrate
    for k in range(warmup + ticks):
        t = k * dt
        t0 = clock()
        s, co = math.sin(omega * t), math.cos(omega * t)
        ref = com0 + amp * s
        if com_task is not None:
            com_sample.value(ref)
            com_sample.derivative(amp * (omega * co))
            com_sample.second_derivative(amp * (-omega * omega * s))
            com_task.setReference(com_sample)
        t1 = clock()
        hqp = formulation.computeProblemData(t, q, v)
        t2 = clock()
        sol = solver.solve(hqp)
        t3 = clock()
        if sol.status == 0:
            tau = formulation.getActuatorForces(sol)
            dv = formulation.getAccelerations(sol)
        q_tick = q
        if simulator is None:
            v += dv * dt
            q = integrate(model, q, v * dt)
        else:
            q, v = simulator.step(tau)
        t4 = clock()
        if k < warmup:
            continue
        failures += sol.status != 0
        t_data.append(t2 - t1)
        t_solve.append(t3 - t2)
        t_loop.append(t4 - t0)
        # Outside the timed part: the CoM at the q given to computeProblemData at time t.
        com_err.append(float(np.linalg.norm(pin.centerOfMass(model, com_data, q_tick) - ref)))
        base_height_min = min(base_height_min, float(q_tick[2]))
        if sol.status == 0:
            sum_fz.append(sum(ct.getNormalForce(formulation.getContactForce(ct.name, sol))
                              for ct in contacts))
            tau_max = max(tau_max, float(np.abs(tau).max()))

    mass = float(pin.computeTotalMass(model))
    mg = mass * float(np.linalg.norm(model.gravity.linear))
    err = np.asarray(com_err)
    mean_fz = float(np.mean(sum_fz)) if sum_fz else float("nan")
    return {
        "versions": {"tsid": md.version("tsid"), "libtsid": md.version("libtsid"),
                     "pinocchio": pin.__version__, "eigenpy": md.version("eigenpy"),
                     "numpy": np.__version__, "python": platform.python_version()},
        "solver": cfg["solver"],
        "threads_env": {k: os.environ.get(k) for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")},
        "model": {"nq": robot.nq, "nv": robot.nv, "na": na, "mass_kg": mass,
                  "armature": sorted({float(a) for a in model.armature[6:]})},
        "nVar": formulation.nVar, "nEq": formulation.nEq, "nIn": formulation.nIn,
        "tasks": tasks, "ticks": ticks, "warmup": warmup, "dt": dt,
        "problem_data_us": stats(t_data), "solve_us": stats(t_solve),
        "tick_us": stats([a + b for a, b in zip(t_data, t_solve, strict=True)]),
        "loop_us": stats(t_loop),
        "failures": int(failures),
        "com_error_final_m": float(err[-1]), "com_error_max_m": float(err.max()),
        "com_error_rms_m": float(np.sqrt(np.mean(err**2))),
        "mean_sum_fz_N": mean_fz, "m_g_N": mg, "fz_ratio": mean_fz / mg,
        "tau_max_abs_Nm": tau_max,
        "base_height_min_m": base_height_min,
        "loop": "euler" if simulator is None else "mujoco",
        "config": cfg,
    }


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--ticks", type=int)
    parser.add_argument("--solver", choices=sorted(SOLVERS))
    parser.add_argument("--config", help="JSON file, deep-merged over DEFAULT_CONFIG")
    args = parser.parse_args(argv)
    cfg = DEFAULT_CONFIG
    if args.config:
        with open(args.config) as f:
            cfg = merge(cfg, json.load(f))
    cfg = copy.deepcopy(cfg)
    if args.ticks is not None:
        cfg["ticks"] = args.ticks
    if args.solver is not None:
        cfg["solver"] = args.solver
    if cfg["solver"] not in SOLVERS:
        raise SystemExit(f"peer_tsid: solver must be one of {sorted(SOLVERS)}")
    if not enabled(cfg["contacts"]):
        raise SystemExit("peer_tsid: contacts cannot be disabled")
    json.dump(run(cfg), sys.stdout)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
