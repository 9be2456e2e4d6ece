"""Cost of the MuJoCo device per tick, on top of MuJoCo's own step: ``python -m dgraph_sim.bench``.

TALOS stands in position mode (gravity feed-forward). For each tick, interleaved, it times the
device's ``prepare_state`` + ``commit_state`` and, from the same MuJoCo state, the bare
``mj_step2`` + ``mj_step1`` (what ``prepare_state`` calls; together one ``mj_step``). It also times
staging and committing its states alone (dgraph's ``State.stage``/``commit``: shape, dtype and
NaN checks), to tell the device's own work from the signal layer's. Medians, in microseconds.
Then MuJoCo's own timers over the same steps (``mjData.timer``: means per call of the step and
its stages: position, of which collision and its broad and narrow phases, constraint solver).
"""

from __future__ import annotations

import argparse
import time

import mujoco
import numpy as np

import dgraph as dg
from dgraph_sim.device import MujocoDevice

_STATE = mujoco.mjtState.mjSTATE_INTEGRATION


def measure(ticks: int = 3000) -> dict[str, float]:
    """Median times (µs) per tick: ``tick`` (prepare + commit), ``mujoco`` (step2 + step1),
    ``overhead`` (their difference), ``stage_commit`` (every state's stage + commit alone), ``states``."""
    import pinocchio as pin

    g = dg.Graph(dt=0.001, name="bench")
    dev = g.add(MujocoDevice("sim", control_mode="position"))
    model = dev.sim.pin_model
    q0 = dev.q.value.copy()
    dev.control.set(q0[7:])
    dev.feedforward_torque.set(pin.rnea(model, model.createData(), q0, np.zeros(model.nv), np.zeros(model.nv))[6:])
    g.run(ticks=200)
    m, d = dev.mj_model, dev.data
    saved = np.zeros(mujoco.mj_stateSize(m, _STATE))
    states = [s for s in dev.outputs.values() if isinstance(s, dg.State)]
    clock = time.perf_counter
    tick, bare, signals = [], [], []
    for _ in range(ticks):
        t = g.t
        mujoco.mj_getState(m, d, saved, _STATE)
        start = clock()
        mujoco.mj_step2(m, d)
        mujoco.mj_step1(m, d)
        bare.append(clock() - start)
        mujoco.mj_setState(m, d, saved, _STATE)
        mujoco.mj_step1(m, d)
        start = clock()
        dev.prepare_state(t)
        dev.commit_state(t + 1)
        tick.append(clock() - start)
        g.t = t + 1
        values = [s.value for s in states]
        start = clock()
        for state, value in zip(states, values, strict=True):
            state.stage(value)
        for state in states:
            state.commit(t + 1)
        signals.append(clock() - start)
    med = {name: float(np.median(v)) * 1e6 for name, v in (("tick", tick), ("mujoco", bare),
                                                           ("stage_commit", signals))}
    med["overhead"] = med["tick"] - med["mujoco"]
    med["states"] = len(states)
    med["own"] = med["overhead"] - med["stage_commit"]
    med.update(mujoco_timers(d))
    return med


TIMERS = {"step": "STEP", "position": "POSITION", "collision": "POS_COLLISION", "broad phase": "COL_BROAD",
          "narrow phase": "COL_NARROW", "constraint": "CONSTRAINT", "velocity": "VELOCITY"}


def mujoco_timers(d: mujoco.MjData) -> dict[str, float]:
    """MuJoCo's own timers: the mean duration per call (µs) of the step and its stages."""
    means = {}
    for name, timer in TIMERS.items():
        stat = d.timer[getattr(mujoco.mjtTimer, f"mjTIMER_{timer}")]
        means[f"mujoco {name}"] = 1e6 * stat.duration / max(stat.number, 1)
    return means


def main() -> None:
    """Print the measurement."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=int, default=3000)
    args = parser.parse_args()
    med = measure(args.ticks)
    print(f"prepare+commit {med['tick']:.1f} us | mj_step2+mj_step1 {med['mujoco']:.1f} us | "
          f"overhead {med['overhead']:.1f} us, of which {med['states']:.0f} x State.stage+commit "
          f"{med['stage_commit']:.1f} us "
          f"and the device's own work {med['own']:.1f} us (medians over {args.ticks} ticks)")
    print("MuJoCo's timers (mean per call): " + ", ".join(f"{name} {med[f'mujoco {name}']:.1f} us" for name in TIMERS))


if __name__ == "__main__":
    main()
