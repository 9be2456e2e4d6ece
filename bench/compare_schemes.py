"""The three control schemes of the thesis (Ch. 4.4) on the same TALOS task, side by side.

    .venv/bin/python bench/compare_schemes.py [--scenarios sway transfer] [--schemes IK ...]

Runs ``graphs/talos_ik_position.yaml`` (IK), ``graphs/talos_tsid_position.yaml`` (TSID
position) and ``graphs/talos_sway.yaml`` (TSID torque) in MuJoCo, adds to each the same probes
(a ZMP estimator on the controller's measured state where the graph has none, a recorder, a
timer of the control graph's evaluation), evaluates the recordings with :mod:`dgraph.evaluation`
against the simulator's ground truth, and writes each scenario's table and plots between its
markers in the document (PNG files beside it). Scenarios: ``sway`` (the graphs' own ±5 cm, 0.5 Hz
lateral sway, 20 s) and ``transfer`` (the CoM moved over the left sole, then the right one, then
back, by minimum-jerk moves, 11 s).
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

import numpy as np
from line_plot import line_plot  # bench/, the script's folder

import dgraph as dg
from dgraph.entities.operators import Add, Constant
from dgraph.entities.recording import Recorder
from dgraph.entities.references import MinimumJerk
from dgraph.entities.robot import load_model
from dgraph.entities.stabilizers import ZmpEstimator, lipm_zmp, natural_frequency
from dgraph.evaluation import (
    cost_of_transport,
    mechanical_energy,
    passivity_gait_measure,
    path_length,
    tick_statistics,
    tracking_error,
)
from dgraph.files import declared_entities, parse, read_text
from dgraph_sim.truth import true_com_and_frames

ROOT = Path(__file__).resolve().parents[1]

SCHEMES = {"IK": "talos_ik_position", "TSID position": "talos_tsid_position", "TSID torque": "talos_sway"}
SOLES = ("left_sole_link", "right_sole_link")
ANKLES = [4, 5, 10, 11]  # leg_{left,right}_{5,6}: ankle pitch and roll (both feet stand)
RECORDED = ["device.q", "device.v", "device.joint_torque", "device.fallen", "zmp.zmp"]
HALF_SITTING_COM = np.array([-0.0031639, 0.0012374, 0.8766814])
# CoM transfer: over the left sole (y = 0.085), then the right one, then back; (start s, duration s, y)
TRANSFER = ((1.0, 2.0, 0.075), (4.0, 3.0, -0.075), (8.0, 2.0, HALF_SITTING_COM[1]))
SCENARIOS = {"sway": 20.0, "transfer": 11.0}
SETTLING = 1.0  # s: the robot settles on its contacts from the initial state; left out of the ZMP statistics


def timed(graph: dg.Graph, durations: list[float]) -> None:
    """Time the control graph: a last before hook pulls every plugged input of the device (the
    simulator then reads them from the cache)."""
    device = graph["device"]
    plugged = [inp for inp in device.inputs.values() if inp.source is not None]

    def pull(t: int) -> None:
        start = time.perf_counter()
        for inp in plugged:
            inp(t)
        durations.append(time.perf_counter() - start)

    device.before.add(pull)


def transfer_reference(graph: dg.Graph) -> tuple[str, str]:
    """Replace the sway by the CoM transfer: the half-sitting CoM plus one minimum-jerk move per
    leg of ``TRANSFER`` (positions, velocities and accelerations summed); the names of the new
    reference position and acceleration."""
    consumers = {kind: graph["com_reference"].signal(kind).plugged_inputs
                 for kind in ("output", "velocity", "acceleration")}
    graph.remove("com_reference")
    y = HALF_SITTING_COM[1]
    sums = {kind: graph.add(Add(f"transfer_{kind}", n_inputs=len(TRANSFER) + (kind == "output"), size=3))
            for kind in consumers}
    for i, (start, duration, target) in enumerate(TRANSFER):
        move = graph.add(MinimumJerk(f"transfer_{i}", target=[0.0, target - y, 0.0], duration=duration, start=start,
                                     initial=[0.0, 0.0, 0.0]))
        y = target
        for kind, source in (("output", "position"), ("velocity", "velocity"), ("acceleration", "acceleration")):
            graph.plug(move.signal(source), sums[kind].signal(f"in{i}"))
    graph.add(Constant("transfer_origin", value=HALF_SITTING_COM))
    graph.plug("transfer_origin.output", f"transfer_output.in{len(TRANSFER)}")
    for kind, inputs in consumers.items():
        for inp in inputs:
            graph.plug(sums[kind].output, inp)
    return "transfer_output.output", "transfer_acceleration.output"


def run(name: str, scenario: str, out: Path) -> tuple[dict[str, np.ndarray], list[float], float]:
    """Run one graph on ``scenario`` with the probes; its recording (the reference as
    ``reference`` and ``reference_acceleration``), control tick durations and wall time."""
    path = ROOT / "graphs" / f"{name}.yaml"
    entities = declared_entities(parse(read_text(path), str(path)))  # with the files it extends
    overrides = {f"{e}.rerun": "off" for e in ("recorder", "view") if e in entities or e == "recorder"}
    graph = dg.load(str(path), overrides)
    if scenario == "transfer":
        reference = transfer_reference(graph)
        for recorder in ("recorder", "view"):  # the graph's own recorder records the removed sway
            if recorder in graph.entities:
                graph.remove(recorder)
    else:
        reference = ("com_reference.output", "com_reference.acceleration")
    if "zmp" not in entities:  # TSID torque: the ZMP on the state its controller sees
        graph.add(ZmpEstimator("zmp"))
        graph.plug("robot.state", "zmp.robot")
        for side in ("left", "right"):
            graph.plug(f"device.ft_{side}_ankle", f"zmp.ft_{side}_ankle")
    graph.add(Recorder("evaluation", signals=[*RECORDED, *reference], rerun="off",
                       npz_path=str(out / f"{name}_{scenario}.npz")))
    durations: list[float] = []
    timed(graph, durations)
    start = time.perf_counter()
    with graph:
        graph.run(duration=SCENARIOS[scenario], progress=False)
    data = graph["evaluation"].data()
    data["reference"], data["reference_acceleration"] = data.pop(reference[0]), data.pop(reference[1])
    return data, durations, time.perf_counter() - start


def ground_truth(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """True CoM and sole positions (ticks x 3, ticks x 2 x 3) from the simulator's configurations."""
    return true_com_and_frames(q, SOLES)


def evaluate(data: dict[str, np.ndarray], durations: list[float], wall: float, dt: float) -> dict[str, object]:
    """Every metric of one run."""
    mass = sum(i.mass for i in load_model("talos").inertias)
    reference = data["reference"]
    com, feet = ground_truth(data["device.q"])
    omega = natural_frequency(reference[:, 2])
    zmp_reference = lipm_zmp(reference, data["reference_acceleration"], omega)
    torque, velocity = data["device.joint_torque"], data["device.v"][:, 6:]
    energy, positive = mechanical_energy(torque, velocity, dt)
    distance = path_length(reference[:, :2])
    return {
        "fallen": bool(data["device.fallen"].any()),
        "com": tracking_error(com, reference),
        "feet": tracking_error(feet.reshape(len(feet), -1), np.broadcast_to(feet[0].ravel(), (len(feet), 6))),
        "zmp": tracking_error(data["zmp.zmp"][:, :2], zmp_reference, mask=np.arange(len(com)) * dt >= SETTLING),
        "energy": (energy, positive), "distance": distance,
        "cot": (cost_of_transport(energy, mass, distance), cost_of_transport(positive, mass, distance)),
        "pgm": passivity_gait_measure(torque, ANKLES),
        "tick": tick_statistics(np.array(durations[1:]), dt),
        "real_time_factor": len(durations) * dt / wall,
        "series": {"t": np.arange(len(com)) * dt, "com_error": np.linalg.norm(com - reference, axis=1),
                   "zmp_y": data["zmp.zmp"][:, 1], "zmp_ref_y": zmp_reference[:, 1]},
    }


def table(results: dict[str, dict[str, object]]) -> str:
    """The markdown table, one column per scheme."""
    rows = [
        ("fallen", lambda r: "yes" if r["fallen"] else "no"),
        ("CoM error RMS / max (mm)", lambda r: f"{1e3 * r['com'].rms:.2f} / {1e3 * r['com'].max:.2f}"),
        ("feet drift RMS / max (mm)", lambda r: f"{1e3 * r['feet'].rms:.2f} / {1e3 * r['feet'].max:.2f}"),
        ("ZMP error x, t ≥ 1 s: mean / std / peak (mm)", lambda r: " / ".join(f"{1e3 * v[0]:.1f}" for v in (
            r["zmp"].mean, r["zmp"].std, r["zmp"].peak))),
        ("ZMP error y, t ≥ 1 s: mean / std / peak (mm)", lambda r: " / ".join(f"{1e3 * v[1]:.1f}" for v in (
            r["zmp"].mean, r["zmp"].std, r["zmp"].peak))),
        ("E_m / E_m⁺ (J)", lambda r: f"{r['energy'][0]:.0f} / {r['energy'][1]:.0f}"),
        ("C_et / C_mt (D = planned CoM path)", lambda r: f"{r['cot'][0]:.2f} / {r['cot'][1]:.2f}"),
        ("PGM, double support (ankles / all joints)", lambda r: f"{r['pgm']:.2f}"),
        ("control tick mean / median / p99 / peak (ms)", lambda r: " / ".join(f"{1e3 * v:.2f}" for v in (
            r["tick"].mean, r["tick"].median, r["tick"].p99, r["tick"].peak))),
        ("ticks over 1 ms (%)", lambda r: f"{100 * r['tick'].overruns:.1f}"),
        ("real-time factor of the loop (MuJoCo, recorder)", lambda r: f"{r['real_time_factor']:.2f}"),
    ]
    lines = ["| metric | " + " | ".join(results) + " |", "|---|" + "---|" * len(results)]
    lines += [f"| {label} | " + " | ".join(cell(r) for r in results.values()) + " |" for label, cell in rows]
    return "\n".join(lines)


def plots(results: dict[str, dict[str, object]], folder: Path, scenario: str,
          window: tuple[float, float]) -> list[str]:
    """The CoM error of every scheme over the run, and the lateral ZMP against the plan over
    ``window`` (s); the PNG names."""
    first = next(iter(results.values()))["series"]
    t = first["t"]
    names = [f"control_schemes_{scenario}_com.png", f"control_schemes_{scenario}_zmp.png"]
    errors = [(n, 1e3 * r["series"]["com_error"]) for n, r in results.items()]
    line_plot(str(folder / names[0]), t, errors, "CoM error |c - c_plan|", "time (s)", "mm")
    shown = (t >= window[0]) & (t <= window[1])
    zmp = [(n, r["series"]["zmp_y"][shown]) for n, r in results.items()]
    line_plot(str(folder / names[1]), t[shown], [*zmp, ("plan (LIPM)", first["zmp_ref_y"][shown])],
              "lateral ZMP", "time (s)", "y (m)")
    return names


def write(doc: Path, scenario: str, text: str) -> None:
    """Replace what is between the ``scenario`` markers of ``doc``."""
    begin, end = f"<!-- {scenario}:begin -->", f"<!-- {scenario}:end -->"
    content = doc.read_text()
    if begin not in content or end not in content:
        raise SystemExit(f"{doc} has no {begin} ... {end} markers")
    doc.write_text(re.sub(re.escape(begin) + ".*?" + re.escape(end), lambda _: f"{begin}\n{text}\n{end}", content,
                          flags=re.S))


def main() -> None:
    """Run, evaluate, print and write the results."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenarios", nargs="+", default=list(SCENARIOS), choices=list(SCENARIOS))
    parser.add_argument("--schemes", nargs="+", default=list(SCHEMES), choices=list(SCHEMES))
    parser.add_argument("--doc", type=Path, default=ROOT / "docs" / "control_schemes.md")
    args = parser.parse_args()
    out = ROOT / "out" / "compare_schemes"
    out.mkdir(parents=True, exist_ok=True)
    for scenario in args.scenarios:
        results = {}
        for scheme in args.schemes:
            data, durations, wall = run(SCHEMES[scheme], scenario, out)
            results[scheme] = evaluate(data, durations, wall, 0.001)
            print(f"{scenario}, {scheme}: done ({wall:.0f} s)", flush=True)
        text = table(results)
        print(text)
        duration = SCENARIOS[scenario]
        window = (duration - 4.0, duration) if scenario == "sway" else (0.0, duration)
        images = plots(results, args.doc.parent, scenario, window)
        write(args.doc, scenario, f"`{' '.join(['.venv/bin/python', *sys.argv])}`, {duration:g} s per scheme, "
              f"{time.strftime('%Y-%m-%d')}.\n\n{text}\n\n" + "\n".join(f"![{name}]({name})" for name in images))


if __name__ == "__main__":
    main()
