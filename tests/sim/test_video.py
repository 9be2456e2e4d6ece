"""Videos of the MuJoCo device: .mp4 (H.264, PyAV) written and logged to the graph's Rerun
recording, the writer on its own, and the errors (extension, path, size, no OpenGL)."""

from __future__ import annotations

import os
import subprocess
import sys
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.recording import Recorder
from dgraph_sim.device import MujocoDevice
from dgraph_sim.video import VideoError, VideoWriter, check_video

av = pytest.importorskip("av")


def decode(path: Path) -> tuple[list[np.ndarray], object]:
    """Every frame of the video at ``path`` (RGB arrays) and its video stream's codec name."""
    with av.open(str(path)) as container:
        codec = container.streams.video[0].codec_context.name
        return [frame.to_ndarray(format="rgb24") for frame in container.decode(video=0)], codec


def video_chunks(rrd: Path, entity: str) -> dict[str, list]:
    """The columns logged under ``entity`` in an .rrd file, by column name (rows of every chunk)."""
    import rerun.chunk as chunk

    columns: dict[str, list] = {}
    for ch in chunk.RrdReader(str(rrd)).stream():
        if str(ch.entity_path) != entity:
            continue
        batch = ch.to_record_batch()
        for name in batch.schema.names:
            columns.setdefault(name, []).extend(batch.column(name).to_pylist())
    return columns


def run_device(tmp_path: Path, video: str, ticks: int, recorder_first: bool = False, rerun: str = "save",
               **params: object) -> MujocoDevice:
    """A TALOS device falling under zero torque for ``ticks`` ticks, with a recorder of its time."""
    with dg.Graph(dt=0.001, name="video_test") as g:
        recorder = Recorder("rec", signals=["sim.sim_time"], rerun=rerun, rrd_path=str(tmp_path / "run.rrd"))
        device = MujocoDevice("sim", video_path=str(tmp_path / video), **params)
        g.add(*((recorder, device) if recorder_first else (device, recorder)))
        device.control.set(np.zeros(32))
        g.run(ticks=ticks)
    return device


@pytest.mark.parametrize("recorder_first", [False, True])  # the device closes before or after the recorder
def test_an_mp4_decodes_back_and_is_in_the_rerun_recording(tmp_path, recorder_first):
    device = run_device(tmp_path, "out/run.mp4", 45, recorder_first, video_fps=100.0, video_size=[64, 48])
    frames, codec = decode(tmp_path / "out/run.mp4")  # the directory was made
    assert codec == "h264"
    assert len(frames) == 5 and all(f.shape == (48, 64, 3) for f in frames)  # after ticks 1, 11, 21, 31, 41
    assert min(f.std() for f in frames) > 10.0  # robot, floor and sky, not a blank image
    assert device.write_video() == str(tmp_path / "out/run.mp4")  # written once; a second call changes nothing

    logged = video_chunks(tmp_path / "run.rrd", "/video/sim")
    assert [bytes(blob[0]) for blob in logged["AssetVideo:blob"]] == [(tmp_path / "out/run.mp4").read_bytes()]
    assert logged["AssetVideo:media_type"] == [["video/mp4"]]
    assert logged["tick"] == [1, 11, 21, 31, 41]
    # the frame at tick t is the video's frame at (t - 1) ms: 100 frames per second of simulation
    assert [ts[0] for ts in logged["VideoFrameReference:timestamp"]] == [k * 10_000_000 for k in range(5)]
    assert [d.total_seconds() for d in logged["time"]] == pytest.approx([0.001, 0.011, 0.021, 0.031, 0.041])


def test_frames_start_at_video_start(tmp_path):
    run_device(tmp_path, "run.mp4", 45, video_fps=100.0, video_size=[32, 24], video_start=0.0195)
    assert len(decode(tmp_path / "run.mp4")[0]) == 3
    logged = video_chunks(tmp_path / "run.rrd", "/video/sim")
    assert logged["tick"] == [20, 30, 40]  # the first tick at or after 19.5 ms, then every 10 ticks
    assert [ts[0] for ts in logged["VideoFrameReference:timestamp"]] == [0, 10_000_000, 20_000_000]


def test_without_a_rerun_recording_the_mp4_is_still_written(tmp_path):
    run_device(tmp_path, "run.mp4", 25, rerun="off", video_fps=100.0, video_size=[32, 24])
    frames, _ = decode(tmp_path / "run.mp4")
    assert len(frames) == 3 and frames[0].shape == (24, 32, 3)
    assert not (tmp_path / "run.rrd").exists()


def test_a_gif_is_not_logged_to_rerun(tmp_path):  # Rerun's AssetVideo reads MP4 only
    run_device(tmp_path, "run.gif", 15, video_fps=100.0, video_size=[32, 24])
    assert (tmp_path / "run.gif").is_file()
    assert video_chunks(tmp_path / "run.rrd", "/video/sim") == {}


def test_the_writer_encodes_at_the_frame_rate_it_is_given(tmp_path):
    writer = VideoWriter(tmp_path / "v.mp4", Fraction(1000, 33), (16, 16))  # one frame every 33 ticks of 1 ms
    ramp = np.linspace(0, 255, 16 * 16 * 3).astype(np.uint8).reshape(16, 16, 3)
    for k in range(4):
        writer.add(np.roll(ramp, 4 * k, axis=1), 33 * k)
    assert writer.close() == tmp_path / "v.mp4"
    assert writer.ticks == [0, 33, 66, 99]
    with av.open(str(tmp_path / "v.mp4")) as container:
        stream = container.streams.video[0]
        times = [float(frame.pts * stream.time_base) for frame in container.decode(stream)]
    assert times == pytest.approx([0.0, 0.033, 0.066, 0.099], abs=1e-4)


def test_a_writer_without_frames_writes_nothing(tmp_path):
    writer = VideoWriter(tmp_path / "sub/v.mp4", 25, (16, 16))
    assert writer.close() is None
    assert not (tmp_path / "sub").exists()


def test_a_frame_of_another_size_is_refused(tmp_path):
    writer = VideoWriter(tmp_path / "v.mp4", 25, (16, 16))
    with pytest.raises(VideoError, match=r"frame of shape \(8, 16, 3\) uint8, expected \(16, 16, 3\) uint8"):
        writer.add(np.zeros((8, 16, 3), np.uint8), 0)


@pytest.mark.parametrize(("video", "size", "message"), [
    ("run.avi", [32, 24], r"unknown video extension '\.avi'; known: \.mp4 \(H\.264 video \(PyAV\)\), \.gif"),
    ("run", [32, 24], r"unknown video extension '\(none\)'"),
    ("run.mp4", [33, 24], r"an \.mp4 \(H\.264, yuv420p\) needs an even width and height, got 33x24"),
    ("a_file/run.mp4", [32, 24], r"cannot be created: '.*a_file' is not a directory"),
    ("a_dir", [32, 24], r"unknown video extension"),
    ("a_dir.mp4", [32, 24], r"is a directory"),
])
def test_a_video_that_cannot_be_written_is_refused_at_construction(tmp_path, video, size, message):
    (tmp_path / "a_file").write_text("")
    (tmp_path / "a_dir").mkdir()
    (tmp_path / "a_dir.mp4").mkdir()
    with pytest.raises(dg.ParamError, match=rf"^device: video_path: '.*{message}"):
        MujocoDevice("device", video_path=str(tmp_path / video), video_size=size)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a_dir", "a_dir.mp4", "a_file"]  # nothing left behind


def test_a_directory_the_process_cannot_write_is_refused(tmp_path):
    if os.geteuid() == 0:
        pytest.skip("root writes into read-only directories")
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    try:
        with pytest.raises(VideoError, match=r"cannot be written: Permission denied"):
            check_video(locked / "sub" / "run.mp4", (32, 24))
    finally:
        locked.chmod(0o700)


@pytest.mark.skipif(not Path("/sys/kernel").is_dir(), reason="needs Linux's sysfs")
def test_a_file_system_where_no_file_can_be_created_is_refused():  # sysfs: even root cannot create a file there
    with pytest.raises(dg.ParamError, match=r"^device: video_path: '/sys/run.mp4' cannot be written: .* in '/sys'$"):
        MujocoDevice("device", video_path="/sys/run.mp4")


def test_without_opengl_a_video_is_refused_naming_the_parameter(tmp_path):
    """MUJOCO_GL=disable: MuJoCo without any OpenGL back-end (read when mujoco is imported, so in
    another process)."""
    path = str(tmp_path / "run.mp4")
    code = ("import dgraph as dg\nfrom dgraph_sim.device import MujocoDevice\n"
            f"try:\n    MujocoDevice('sim', video_path={path!r})\nexcept dg.ParamError as exc:\n    print(exc)\n")
    result = subprocess.run([sys.executable, "-c", code], env={**os.environ, "MUJOCO_GL": "disable"},
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("sim: video_path: offscreen rendering is not available (MUJOCO_GL=disable: ")
    assert "set MUJOCO_GL=egl" in result.stdout
    assert not (tmp_path / "run.mp4").exists()
