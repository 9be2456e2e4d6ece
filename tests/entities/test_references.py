"""MinimumJerk and TrajectoryFile: boundary values, derivatives, knots, file errors."""

from __future__ import annotations

import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.references import MinimumJerk, Sinusoid, TrajectoryFile
from dgraph.entities.references.trajectory_file import natural_spline_second_derivatives
from tests.conftest import Ticker

DT = 0.001


def mj_graph(**params) -> tuple[dg.Graph, MinimumJerk]:
    g = dg.Graph(dt=DT)
    g.add(Ticker("dev", x0=5.0))
    mj = g.add(MinimumJerk("mj", **params))
    return g, mj


def test_min_jerk_boundary_conditions_and_midpoint():
    g, mj = mj_graph(target=[1.0, -2.0], initial=[0.0, 4.0], duration=2.0, start=0.5)
    p0, pf = np.array([0.0, 4.0]), np.array([1.0, -2.0])
    g.run(ticks=3000)
    start, end, mid = 500, 2500, 1500
    assert np.allclose(mj.position(0), p0) and np.allclose(mj.velocity(0), 0) and np.allclose(mj.acceleration(0), 0)
    assert np.allclose(mj.position(start), p0) and np.allclose(mj.velocity(start), 0)
    assert np.allclose(mj.acceleration(start), 0)
    assert np.allclose(mj.position(mid), (p0 + pf) / 2)  # s = 1/2: 10/8 - 15/16 + 6/32 = 1/2
    assert np.allclose(mj.velocity(mid), (pf - p0) / 2.0 * 1.875)  # peak velocity 15/8 d/T
    assert np.allclose(mj.acceleration(mid), 0, atol=1e-12)
    assert np.allclose(mj.position(end), pf) and np.allclose(mj.velocity(end), 0, atol=1e-12)
    assert np.allclose(mj.acceleration(end), 0, atol=1e-12)
    assert np.allclose(mj.position(2999), pf) and np.allclose(mj.velocity(2999), 0)
    # at s = 1/4: p = d (10/64 - 15/256 + 6/1024), a = d/T^2 * 60 (1/4)(3/4)(1/2)
    q = 1000
    assert np.allclose(mj.position(q), p0 + (pf - p0) * (10 / 64 - 15 / 256 + 6 / 1024))
    assert np.allclose(mj.acceleration(q), (pf - p0) / 4.0 * 60 * 0.25 * 0.75 * 0.5)


def test_min_jerk_velocity_and_acceleration_are_derivatives():
    _, mj = mj_graph(target=3.0, initial=1.0, duration=0.8, start=0.1)
    ticks = np.arange(0, 1200)
    p = np.array([mj.position(int(t)) for t in ticks])
    v = np.array([mj.velocity(int(t)) for t in ticks])
    a = np.array([mj.acceleration(int(t)) for t in ticks])
    assert isinstance(p[0], float)
    assert np.max(np.abs(np.gradient(p, DT) - v)) < 1e-3 * np.max(np.abs(v))
    assert np.max(np.abs(np.gradient(v, DT) - a)) < 2e-2 * np.max(np.abs(a))
    assert np.max(np.abs(v)) == pytest.approx(1.875 * 2.0 / 0.8, rel=1e-5)


def test_min_jerk_samples_its_input_at_the_start_tick():
    g, mj = mj_graph(target=10.0, duration=0.01, start=0.005)
    g.plug("dev.x", "mj.current")  # x(t) = 5 + t
    g.run(ticks=3)
    assert mj.position(3) == 8.0 and mj.velocity(3) == 0.0  # before the start: follows the input
    g.run(ticks=30)
    assert mj.origin.value == 10.0 and mj.origin.time == 6  # sampled at tick 5: x(5) = 10
    assert mj.position(33) == 10.0 and mj.velocity(33) == 0.0

    g2, back = mj_graph(target=0.0, duration=0.01, start=0.005)
    g2.plug("dev.x", "mj.current")
    g2.run(ticks=10)
    assert back.origin.value == 10.0
    assert back.position(10) == pytest.approx(5.0)  # s = 1/2: half way from 10 to 0
    assert back.velocity(10) == pytest.approx(-10.0 / 0.01 * 1.875)
    g2.run(ticks=10)
    assert back.position(20) == 0.0 and back.acceleration(20) == 0.0  # holds the target


def test_min_jerk_parameters_are_checked():
    with pytest.raises(dg.ParamError, match="duration must be > 0"):
        MinimumJerk("m", target=1.0, duration=0.0)
    with pytest.raises(dg.ParamError, match="initial has shape"):
        MinimumJerk("m", target=[1.0, 2.0], initial=[1.0], duration=1.0)
    g = dg.Graph()
    g.add(Ticker("dev"))
    g.add(MinimumJerk("m", target=1.0, duration=1.0))
    with pytest.raises(dg.GraphError, match=r"m\.current is not plugged"):
        g.validate()


# -- TrajectoryFile ----------------------------------------------------------------------------
def write(tmp_path, text, name="traj.csv"):
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def traj_graph(**params) -> tuple[dg.Graph, TrajectoryFile]:
    g = dg.Graph(dt=DT)
    g.add(Ticker("dev"))
    return g, g.add(TrajectoryFile("traj", **params))


KNOTS = np.array([0.0, 0.1, 0.25, 0.3, 0.5])
VALUES = np.stack([np.sin(3 * KNOTS), KNOTS**2], axis=1)


@pytest.mark.parametrize("interpolation", ["linear", "cubic"])
def test_file_trajectories_interpolate_the_knots_exactly(tmp_path, interpolation):
    rows = "\n".join(",".join(repr(float(x)) for x in (t, *v)) for t, v in zip(KNOTS, VALUES, strict=True))
    path = write(tmp_path, "# a comment\ntime,a,b\n" + rows + "\n")
    _, tr = traj_graph(path=path, interpolation=interpolation, start=0.2)
    for t, v in zip(KNOTS, VALUES, strict=True):
        tick = round((t + 0.2) / DT)
        assert np.allclose(tr.position(tick), v, atol=1e-12), (interpolation, t)
    assert np.allclose(tr.position(0), VALUES[0]) and np.allclose(tr.velocity(0), 0)
    assert np.allclose(tr.position(10_000), VALUES[-1]) and np.allclose(tr.acceleration(10_000), 0)
    # linear: the midpoint of a segment is the mean of its knots
    if interpolation == "linear":
        assert np.allclose(tr.position(200 + 175), (VALUES[1] + VALUES[2]) / 2, atol=1e-12)


def test_cubic_velocity_and_acceleration_are_the_spline_derivatives(tmp_path):
    np.savez(tmp_path / "t.npz", time=KNOTS, position=VALUES)
    _, tr = traj_graph(path=str(tmp_path / "t.npz"), interpolation="cubic")
    ticks = np.arange(0, 501)
    p = np.array([tr.position(int(t)) for t in ticks])
    v = np.array([tr.velocity(int(t)) for t in ticks])
    a = np.array([tr.acceleration(int(t)) for t in ticks])
    inner = slice(2, -2)
    assert np.max(np.abs(np.gradient(p, DT, axis=0) - v)[inner]) < 1e-4
    assert np.max(np.abs(np.gradient(v, DT, axis=0) - a)[inner]) < 1e-1
    m = natural_spline_second_derivatives(KNOTS, VALUES)
    assert np.allclose(m[0], 0) and np.allclose(m[-1], 0)
    assert np.allclose(a[0], 0, atol=1e-9) and np.allclose(a[500], 0, atol=1e-9)  # natural ends
    # continuity of the velocity at an inner knot (tick 100 = 0.1 s)
    assert np.allclose(tr.velocity(100), (tr.position(101) - tr.position(99)) / (2 * DT), atol=1e-4)


def test_hermite_with_given_velocities_and_accelerations(tmp_path):
    velocities = np.stack([3 * np.cos(3 * KNOTS), 2 * KNOTS], axis=1)
    accelerations = np.stack([-9 * np.sin(3 * KNOTS), 2 + 0 * KNOTS], axis=1)
    rows = "\n".join(",".join(map(str, (t, *p, *v, *a)))
                     for t, p, v, a in zip(KNOTS, VALUES, velocities, accelerations, strict=True))
    _, tr = traj_graph(path=write(tmp_path, rows), layout="pva", interpolation="cubic")
    for k, t in enumerate(KNOTS):
        tick = round(t / DT)
        assert np.allclose(tr.position(tick), VALUES[k]) and np.allclose(tr.velocity(tick), velocities[k])
        assert np.allclose(tr.acceleration(tick), accelerations[k])
    ticks = np.arange(0, 501)
    p = np.array([tr.position(int(t)) for t in ticks])
    v = np.array([tr.velocity(int(t)) for t in ticks])
    assert np.max(np.abs(np.gradient(p, DT, axis=0) - v)[2:-2]) < 1e-4
    # the b column is t^2, reproduced exactly by a cubic Hermite with exact velocities
    assert np.allclose(p[:, 1], (ticks * DT) ** 2, atol=1e-12)


def test_linear_without_velocities_uses_finite_differences(tmp_path):
    t = np.linspace(0.0, 1.0, 11)
    np.savez(tmp_path / "q.npz", time=t, position=2.0 * t + 1.0)
    g, tr = traj_graph(path=str(tmp_path / "q.npz"), interpolation="linear")
    assert tr.position(550).shape == (1,) and tr.position(550)[0] == pytest.approx(2.1)
    assert tr.velocity(550)[0] == pytest.approx(2.0) and tr.acceleration(550)[0] == pytest.approx(0.0)
    g.run(ticks=5)
    assert tr.position(5)[0] == pytest.approx(1.010)  # in a running graph, at the current tick


@pytest.mark.parametrize(("text", "layout", "message"), [
    ("0,1\n0.1,abc\n", "p", r"traj\.csv:2: column 2: 'abc' is not a finite number"),
    ("0,1\n0.1,nan\n", "p", r"traj\.csv:2: column 2: 'nan' is not a finite number"),
    ("# c\n0,1,2\n0.1,1\n", "p", r"traj\.csv:3: 2 columns, expected 3 \(as line 2\)"),
    ("time,a\n0,1\n0.2,1\n0.2,3\n", "p", r"traj\.csv:4: time 0.2 is not greater than the previous time 0.2"),
    ("0,1,2\n0.1,1,2\n", "pva", r"traj\.csv:1: 3 columns do not fit layout 'pva'"),
    ("0,1\n", "p", r"traj\.csv: a trajectory needs at least 2 samples, got 1"),
    ("# nothing\n", "p", r"traj\.csv: no data rows"),
    ("0,1\n0.1,__import__('os')\n", "p", r"traj\.csv:2: column 2: \"__import__\('os'\)\" is not a finite number"),
])
def test_malformed_csv_files_are_reported_with_file_and_line(tmp_path, text, layout, message):
    with pytest.raises(dg.ParamError, match=message) as info:
        TrajectoryFile("traj", path=write(tmp_path, text), layout=layout)
    assert str(tmp_path) in str(info.value) and info.value.entity == "traj"


def test_malformed_npz_files_are_reported(tmp_path):
    np.savez(tmp_path / "a.npz", time=[0.0, 0.2, 0.1], position=[1.0, 2.0, 3.0])
    with pytest.raises(dg.ParamError, match=r"a\.npz: row 2: time 0.1 is not greater than the previous time 0.2"):
        TrajectoryFile("traj", path=str(tmp_path / "a.npz"))
    np.savez(tmp_path / "b.npz", time=[0.0, 0.1], values=[1.0, 2.0])
    with pytest.raises(dg.ParamError, match=r"b\.npz: missing array 'position' \(has: time, values\)"):
        TrajectoryFile("traj", path=str(tmp_path / "b.npz"))
    np.savez(tmp_path / "c.npz", time=[0.0, 0.1], position=np.array([{"x": 1}, None], dtype=object))
    with pytest.raises(dg.ParamError, match=r"c\.npz"):
        TrajectoryFile("traj", path=str(tmp_path / "c.npz"))  # pickled objects are never loaded
    np.savez(tmp_path / "d.npz", time=[0.0, 0.1], position=[[1.0, 2.0], [1.0, 2.0]], velocity=[1.0, 2.0])
    with pytest.raises(dg.ParamError, match=r"d\.npz: velocity has 1 columns, position 2"):
        TrajectoryFile("traj", path=str(tmp_path / "d.npz"))
    with pytest.raises(dg.ParamError, match="cannot read trajectory file"):
        TrajectoryFile("traj", path=str(tmp_path / "missing.csv"))


def test_trajectory_files_with_a_bom_a_unit_header_or_the_wrong_arrays(tmp_path):
    bom = tmp_path / "bom.csv"
    bom.write_text("\ufefftime_s,x\n0,0\n1,2\n", encoding="utf-8")
    g = dg.Graph(dt=DT)
    traj = g.add(TrajectoryFile("traj", path=str(bom)))
    assert traj.position(500) == pytest.approx([1.0])
    npy = tmp_path / "single.npz"
    with npy.open("wb") as f:
        np.save(f, np.zeros(3))
    with pytest.raises(dg.ParamError, match=r"single\.npz.*not an \.npz archive"):
        TrajectoryFile("t", path=str(npy))
    complex_file = tmp_path / "c.npz"
    np.savez(complex_file, time=np.arange(3.0), position=np.arange(3.0) + 1j)
    with pytest.raises(dg.ParamError, match="'position' must hold real numbers"):
        TrajectoryFile("t", path=str(complex_file))
    empty = tmp_path / "e.npz"
    np.savez(empty, time=np.arange(3.0), position=np.zeros((3, 0)))
    with pytest.raises(dg.ParamError, match=r"position has shape \(3, 0\)"):
        TrajectoryFile("t", path=str(empty))


def test_a_sinusoid_3_vector_is_its_components_and_its_derivatives():
    g = dg.Graph(dt=DT)
    params = {"frequency": 0.5, "phase": 0.3, "ramp": 1.0}
    point = g.add(Sinusoid("point", amplitude=[0.0, 0.05, -0.02], offset=[0.1, 0.2, 0.9], **params))
    parts = [g.add(Sinusoid(f"part{k}", amplitude=a, offset=o, **params))
             for k, (a, o) in enumerate(zip([0.0, 0.05, -0.02], [0.1, 0.2, 0.9], strict=True))]
    for t in (0, 1, 400, 999, 1000, 1500):  # in the fade-in, at its end, after it
        for name in ("output", "velocity", "acceleration"):
            value = point.signal(name)(t)
            assert isinstance(value, np.ndarray) and value.shape == (3,)
            np.testing.assert_allclose(value, [part.signal(name)(t) for part in parts], rtol=1e-15, atol=1e-15)
    for t in (500, 1500):  # central differences of the position and of the velocity
        for low, high in (("output", "velocity"), ("velocity", "acceleration")):
            slope = (point.signal(low)(t + 1) - point.signal(low)(t - 1)) / (2 * DT)
            np.testing.assert_allclose(slope, point.signal(high)(t), atol=1e-5)


@pytest.mark.parametrize("name", ["frequency", "phase", "offset"])
def test_a_sinusoid_parameter_that_does_not_fit_the_amplitude_is_named(name):
    params = {"amplitude": [0.0, 0.05, 0.0], "frequency": 0.5, name: [1.0, 2.0]}
    with pytest.raises(dg.ParamError, match=rf"^s: {name} has shape \(2,\) but amplitude \(3,\): give a scalar or one "
                                            "value per component$"):
        Sinusoid("s", **params)
