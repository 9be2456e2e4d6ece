"""Video files from rendered frames: frames in, a file out, and the file logged to a Rerun recording.

:class:`VideoWriter` takes RGB frames (``height x width x 3``, uint8), each with the graph tick
it shows, and writes one file whose format follows the path's extension (:data:`FORMATS`):

- ``.mp4``: H.264 (``libx264``, yuv420p, no B-frames) through PyAV (the ``av`` package, whose
  wheels bring their own FFmpeg), encoded as the frames come (nothing is kept in memory); the
  frame rate is that of the frames' ticks, so the video plays at the simulation's speed;
- ``.gif``, ``.webp`` (animated) and ``.png`` (APNG) through Pillow, written at :meth:`close`
  (the frames are kept until then).

:func:`log_video` logs an .mp4 written here to a Rerun recording: the file once, as a static
``AssetVideo``, then one ``VideoFrameReference`` per frame, at the frame's tick on the ``tick``
and ``time`` timelines of the recording, so the video scrubs with the plots.

Errors are :class:`VideoError` (a ``ValueError``) with a message that says what is wrong with
the path; the device that owns the writer prefixes its name and parameter.
"""

from __future__ import annotations

import os
import tempfile
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

FORMATS = {".mp4": "H.264 video (PyAV)", ".gif": "animated GIF (Pillow)", ".webp": "animated WebP (Pillow)",
           ".png": "animated PNG (Pillow)"}
"""Extensions a video can be written to, with what writes them."""

X264_OPTIONS = {"crf": "23", "preset": "medium", "bf": "0"}
"""libx264 settings: constant quality 23 (x264's default), no B-frames (every frame is
decoded in the order it is stored, which any player and Rerun's viewer handle)."""


class VideoError(ValueError):
    """A video that cannot be written: the path, the frames or the encoder."""


def check_video(path: str | os.PathLike[str], size: tuple[int, int] | list[int]) -> Path:
    """``path`` as a ``Path`` if a video of ``size`` (width, height) can be written there, else a
    :class:`VideoError`: a known extension, an even size for an .mp4 (H.264 in yuv420p halves
    the colour planes), PyAV installed for an .mp4, and a place this process can create the file
    in (its directory, or the nearest existing ancestor if the directory is still to be made),
    tested by creating and removing a temporary file there, so nothing is left behind."""
    path = Path(path)
    kind = path.suffix.lower()
    if kind not in FORMATS:
        known = ", ".join(f"{ext} ({what})" for ext, what in FORMATS.items())
        raise VideoError(f"{str(path)!r} has an unknown video extension {path.suffix or '(none)'!r}; known: {known}")
    if kind == ".mp4":
        if size[0] % 2 or size[1] % 2:
            raise VideoError(f"{str(path)!r}: an .mp4 (H.264, yuv420p) needs an even width and height, got "
                             f"{size[0]}x{size[1]}")
        try:
            import av  # noqa: F401
        except ImportError:
            raise VideoError(f"{str(path)!r}: writing an .mp4 needs PyAV (pip install 'dgraph[video]'); "
                             ".gif, .webp and .png need only Pillow") from None
    if path.is_dir():
        raise VideoError(f"{str(path)!r} is a directory")
    parent = path.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir():
        raise VideoError(f"{str(path)!r} cannot be created: {str(parent)!r} is not a directory")
    try:
        fd, probe = tempfile.mkstemp(dir=parent, prefix=".video-probe-")
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise VideoError(f"{str(path)!r} cannot be written: {exc.strerror or exc} in {str(parent)!r}") from None
    return path


class VideoWriter:
    """Frames in, one video file out (the format by the path's extension, see :data:`FORMATS`).

    ``fps`` is the rate at which the frames are taken (a ``Fraction`` keeps it exact, e.g.
    1000/33); ``size`` is ``(width, height)``; both are checked by :func:`check_video`. The
    file (and its directory) is created at the first frame: a run that adds no frame writes
    nothing.
    """

    def __init__(self, path: str | os.PathLike[str], fps: float | Fraction, size: tuple[int, int]):
        self.size = (int(size[0]), int(size[1]))
        self.path = check_video(path, self.size)
        self.kind = self.path.suffix.lower()
        self.fps = Fraction(fps).limit_denominator(1_000_000)
        if self.fps <= 0:
            raise VideoError(f"frame rate must be positive, got {fps}")
        self.ticks: list[int] = []  # the tick each frame shows
        self._images: list[Any] = []  # Pillow formats: the frames, kept until close
        self._container: Any = None  # .mp4: the open PyAV output and its stream
        self._stream: Any = None
        self.closed = False
        self.failed = False  # an error was raised: the file is incomplete, close() returns None

    def add(self, frame: np.ndarray, tick: int) -> None:
        """Add a frame (``height x width x 3`` uint8 RGB, of this writer's size) showing ``tick``."""
        if self.closed:
            raise VideoError(f"{str(self.path)!r} is already written")
        frame = np.asarray(frame)
        if frame.shape != (self.size[1], self.size[0], 3) or frame.dtype != np.uint8:
            raise VideoError(f"frame of shape {frame.shape} {frame.dtype}, expected "
                             f"({self.size[1]}, {self.size[0]}, 3) uint8")
        if self.kind == ".mp4":
            self._encode(frame)
        else:
            from PIL import Image

            self._images.append(Image.fromarray(frame))
        self.ticks.append(int(tick))

    def _encode(self, frame: np.ndarray | None) -> None:
        """Encode one frame (``None``: flush the encoder) and mux its packets."""
        import av

        try:
            if self._container is None:
                self.path.parent.mkdir(parents=True, exist_ok=True)
                self._container = av.open(str(self.path), mode="w")
                stream = self._container.add_stream("libx264", rate=self.fps, options=dict(X264_OPTIONS))
                stream.width, stream.height = self.size
                stream.pix_fmt = "yuv420p"
                self._stream = stream
            if frame is None:
                packets = self._stream.encode()
            else:
                video_frame = av.VideoFrame.from_ndarray(frame, format="rgb24")
                video_frame.pts = len(self.ticks)  # in 1 / fps, the stream's codec time base
                packets = self._stream.encode(video_frame)
            self._container.mux(packets)
        except (OSError, av.FFmpegError) as exc:
            self._abandon()
            raise VideoError(f"{str(self.path)!r} cannot be written: {exc}") from None

    def _abandon(self) -> None:
        """After an encoding error: close what is open, mark the writer failed."""
        container, self._container = self._container, None
        self.closed = self.failed = True
        if container is not None:
            try:
                container.close()
            except Exception:  # already failing: the first error is the one reported
                pass

    def close(self) -> Path | None:
        """Finish the file; returns its path, or ``None`` if no frame was added (nothing written).
        Idempotent."""
        if self.closed:
            return self.path if self.ticks and not self.failed else None
        if not self.ticks:
            self.closed = True
            return None
        if self.kind == ".mp4":
            self._encode(None)
            try:
                self._container.close()
            except Exception as exc:  # PyAV's errors (FFmpegError) are not all OSErrors
                self.failed = True
                raise VideoError(f"{str(self.path)!r} cannot be written: {exc}") from None
            finally:
                self._container, self.closed = None, True
            return self.path
        images, self._images, self.closed = self._images, [], True
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            images[0].save(self.path, save_all=True, append_images=images[1:],
                           duration=round(1000.0 / float(self.fps)), loop=0)
        except (OSError, ValueError) as exc:
            self.failed = True
            raise VideoError(f"{str(self.path)!r} cannot be written: {exc}") from None
        return self.path


def log_video(stream: Any, entity_path: str, path: str | os.PathLike[str], ticks: list[int] | np.ndarray) -> int:
    """Log the .mp4 at ``path`` to the Rerun recording ``stream`` (a
    :class:`~dgraph.entities.recording.rerun_stream.RerunStream`) under ``entity_path``: the
    file as a static ``AssetVideo``, and its ``k``-th frame (by presentation time) referenced at
    ``ticks[k]`` on the recording's ``tick`` and ``time`` timelines. Returns the number of frames.

    Raises :class:`VideoError` if the file does not hold one frame per tick."""
    rr = stream._rr
    video = rr.AssetVideo(path=str(path))
    timestamps = np.sort(video.read_frame_timestamps_nanos())
    ticks = np.asarray(ticks, dtype=np.int64)
    if len(timestamps) != len(ticks):
        raise VideoError(f"{str(path)!r} holds {len(timestamps)} frames, expected {len(ticks)} (one per "
                         "recorded tick)")
    stream.rec.log(entity_path, video, static=True)
    stream.rec.send_columns(entity_path, indexes=stream.indexes(ticks),
                            columns=rr.VideoFrameReference.columns_nanos(timestamps))
    return len(ticks)
