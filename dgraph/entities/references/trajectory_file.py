"""TrajectoryFile: a trajectory read from a CSV or .npz file, interpolated in time."""

from __future__ import annotations

import csv
import math
from pathlib import Path
from typing import TYPE_CHECKING, Literal

import numpy as np

import dgraph as dg

LAYOUTS = {"p": 1, "pv": 2, "pva": 3}
"""Column layouts: positions only, then velocities, then accelerations (blocks of n columns)."""

MAX_FILE_BYTES = 512 * 1024 * 1024
"""Larger trajectory files are refused (a file must not exhaust the machine)."""


class TrajectoryData:
    """Knot times ``(N,)`` and position / velocity / acceleration ``(N, n)`` (the last two optional)."""

    def __init__(self, time: np.ndarray, position: np.ndarray, velocity: np.ndarray | None = None,
                 acceleration: np.ndarray | None = None):
        self.time = time
        self.position = position
        self.velocity = velocity
        self.acceleration = acceleration


def _fail(path: Path, line: int | None, message: str) -> dg.ParamError:
    where = f"{path}:{line}" if line is not None else str(path)
    return dg.ParamError(f"{where}: {message}")


def _check_times(path: Path, time: np.ndarray, lines: list[int] | None, what: str = "row") -> None:
    if len(time) < 2:
        raise _fail(path, None, f"a trajectory needs at least 2 samples, got {len(time)}")
    bad = np.flatnonzero(np.diff(time) <= 0)
    if len(bad):
        k = int(bad[0]) + 1
        line = lines[k] if lines is not None else None
        where = "" if lines is not None else f"{what} {k}: "
        raise _fail(path, line, f"{where}time {float(time[k])!r} is not greater than the previous time "
                    f"{float(time[k - 1])!r}")


def read_csv(path: Path, layout: str) -> TrajectoryData:
    """Read ``time, values...`` rows; ``#`` lines are comments, a first line whose first cell is
    ``t``, ``time`` or starts with ``time_`` / ``t_`` (``time_s``) is a header; a UTF-8 byte-order
    mark is ignored. Every cell must be a finite number (nothing is evaluated)."""
    blocks = LAYOUTS[layout]
    rows: list[list[float]] = []
    lines: list[int] = []
    width: int | None = None
    with path.open(newline="", encoding="utf-8-sig") as f:
        for lineno, cells in enumerate(csv.reader(f), start=1):
            cells = [c.strip() for c in cells]
            if not cells or all(not c for c in cells) or cells[0].startswith("#"):
                continue
            first = cells[0].lower()
            if width is None and not rows and (first in ("t", "time") or first.startswith(("t_", "time_"))):
                width = len(cells)  # the header fixes the column count
                header_line = lineno
                continue
            if width is None:
                width, header_line = len(cells), lineno
            if len(cells) != width:
                raise _fail(path, lineno, f"{len(cells)} columns, expected {width} (as line {header_line})")
            row = []
            for col, cell in enumerate(cells, start=1):
                try:
                    value = float(cell)
                except ValueError:
                    value = math.nan
                if not math.isfinite(value):
                    raise _fail(path, lineno, f"column {col}: {cell[:40]!r} is not a finite number")
                row.append(value)
            rows.append(row)
            lines.append(lineno)
    if width is None:
        raise _fail(path, None, "no data rows")
    values = width - 1
    if values < blocks or values % blocks:
        raise _fail(path, header_line, f"{width} columns do not fit layout {layout!r}: expected 1 time "
                    f"column + {blocks} x n value columns")
    data = np.array(rows, dtype=float).reshape(len(rows), width)
    _check_times(path, data[:, 0], lines)
    n = values // blocks
    parts = [data[:, 1 + k * n: 1 + (k + 1) * n] for k in range(blocks)]
    return TrajectoryData(data[:, 0], *parts)


def read_npz(path: Path) -> TrajectoryData:
    """Read the arrays ``time`` (N,), ``position`` (N,) or (N, n), optional ``velocity`` and
    ``acceleration`` (shape of position); pickled objects are refused."""
    try:
        archive = np.load(path, allow_pickle=False)
    except (ValueError, OSError) as exc:
        raise _fail(path, None, f"not a readable .npz file: {exc}") from None
    if not isinstance(archive, np.lib.npyio.NpzFile):
        raise _fail(path, None, "not an .npz archive (a single .npy array?): save arrays named time, position, "
                    "... with numpy.savez")
    with archive:
        for key in ("time", "position"):
            if key not in archive.files:
                raise _fail(path, None, f"missing array {key!r} (has: {', '.join(archive.files) or 'none'})")
        try:
            raw = {k: archive[k] for k in ("time", "position", "velocity", "acceleration") if k in archive.files}
        except (ValueError, TypeError) as exc:
            raise _fail(path, None, f"arrays must hold numbers: {exc}") from None
        for key, value in raw.items():
            if value.dtype.kind not in "iuf":
                raise _fail(path, None, f"array {key!r} must hold real numbers, got dtype {value.dtype}")
        arrays = {k: np.asarray(v, dtype=float) for k, v in raw.items()}
    time = arrays["time"]
    if time.ndim != 1:
        raise _fail(path, None, f"time must be 1-D, got shape {time.shape}")
    for key, value in arrays.items():
        if key != "time":
            if value.ndim == 1:
                arrays[key] = value = value[:, None]
            if value.ndim != 2 or value.shape[0] != len(time) or value.shape[1] == 0:
                raise _fail(path, None, f"{key} has shape {value.shape}: expected ({len(time)}, n), n >= 1")
            if value.shape[1] != arrays["position"].shape[1]:
                raise _fail(path, None, f"{key} has {value.shape[1]} columns, position {arrays['position'].shape[1]}")
        bad = np.flatnonzero(~np.isfinite(value).all(axis=tuple(range(1, value.ndim))))
        if len(bad):
            raise _fail(path, None, f"{key}, row {int(bad[0])}: not a finite number")
    _check_times(path, time, None)
    return TrajectoryData(time, arrays["position"], arrays.get("velocity"), arrays.get("acceleration"))


def natural_spline_second_derivatives(time: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Second derivatives ``M`` at the knots of the natural cubic spline (``M_0 = M_N = 0``)
    through ``values`` (N, n): the tridiagonal system solved by the Thomas algorithm."""
    n_knots = len(time)
    m = np.zeros_like(values)
    if n_knots < 3:
        return m
    h = np.diff(time)
    slopes = np.diff(values, axis=0) / h[:, None]
    rhs = 6.0 * (slopes[1:] - slopes[:-1])  # rows 1 .. N-2
    diag = 2.0 * (h[:-1] + h[1:])
    sub = h[:-1]  # coefficient of M_{i-1} in row i
    sup = h[1:]  # coefficient of M_{i+1} in row i
    k = len(diag)
    c = np.empty(k)
    d = np.empty_like(rhs)
    c[0] = sup[0] / diag[0]
    d[0] = rhs[0] / diag[0]
    for i in range(1, k):
        denom = diag[i] - sub[i] * c[i - 1]
        c[i] = sup[i] / denom
        d[i] = (rhs[i] - sub[i] * d[i - 1]) / denom
    m[k] = d[k - 1]
    for i in range(k - 2, -1, -1):
        m[i + 1] = d[i] - c[i] * m[i + 2]
    return m


@dg.register
class TrajectoryFile(dg.Entity):
    """A trajectory from a file, played from ``start`` seconds and interpolated in time.

    The file holds knots ``(t_k, p_k)`` (and optionally ``v_k``, ``a_k``): a CSV (``time,
    values...`` per row, blocks of n columns as given by ``layout``: ``p``, ``pv`` or ``pva``;
    ``#`` comment lines; an optional header line starting with ``t`` or ``time``) or an .npz
    (arrays ``time``, ``position``, optional ``velocity`` and ``acceleration``). Times must
    increase strictly; every cell must be a finite number. Nothing in the file is executed
    (CSV cells go through ``float``; .npz is read with ``allow_pickle=False``). Errors name the
    file and the line (CSV) or the array and the row (.npz).

    With ``tau = t * dt - start`` the file time, inside ``[t_0, t_N]`` and ``h = t_{k+1} - t_k``,
    ``u = (tau - t_k) / h``:

    * ``linear``: ``p = (1 - u) p_k + u p_{k+1}``. Without velocity columns, knot velocities are
      finite differences (``numpy.gradient``, second order) of the positions, and knot
      accelerations finite differences of those; velocity and acceleration are interpolated
      linearly in the same way.
    * ``cubic``: without velocities, the natural cubic spline through the positions (second
      derivatives ``M_k``, ``M_0 = M_N = 0``):
      ``p = (1-u) p_k + u p_{k+1} + h^2/6 [((1-u)^3 - (1-u)) M_k + (u^3 - u) M_{k+1}]``, and
      velocity and acceleration are its exact derivatives. With velocities, the cubic Hermite
      interpolant of ``(p_k, v_k)``, with velocity and acceleration its derivatives.
    * Given acceleration columns are interpolated linearly and used as the acceleration.

    Before ``t_0`` and after ``t_N`` the position holds the end value, velocity and
    acceleration are zero. Positions interpolate the knots exactly in every mode.

    Parameters: ``path`` (.csv or .npz), ``layout`` (CSV columns), ``interpolation``
    (``linear`` | ``cubic``), ``start`` (s), ``dt`` (default: the graph's).
    Outputs: ``position``, ``velocity``, ``acceleration`` (n,), depending on time.
    """

    path = dg.Param(kind="path", doc="trajectory file (.csv or .npz; in a graph file, relative to its folder)")
    layout = dg.Param("p", kind="str", choices=tuple(LAYOUTS), doc="CSV columns after time: p, pv or pva blocks")
    interpolation = dg.Param("cubic", kind="str", choices=("linear", "cubic"), doc="interpolation in time")
    start = dg.Param(0.0, kind="float", minimum=-1e9, maximum=1e9, doc="graph time (s) at which file time 0 is played")
    dt = dg.Param(None, kind="float", minimum=1e-6, doc="tick period in s (default: the graph's dt)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, path: str, layout: Literal["p", "pv", "pva"] = "p",
            interpolation: Literal["linear", "cubic"] = "cubic", start: float = 0.0, dt: float | None = None,
        ) -> None: ...

    def configure(self) -> None:
        """Read and check the file; precompute what the interpolation needs."""
        path = Path(self.path)
        try:
            size = path.stat().st_size
        except OSError as exc:
            raise dg.ParamError(f"{self.name}: cannot read trajectory file {path}: {exc.strerror or exc}",
                                entity=self.name) from None
        if size > MAX_FILE_BYTES:
            raise dg.ParamError(f"{path}: {size} bytes, more than the {MAX_FILE_BYTES} allowed", entity=self.name)
        try:
            data = read_npz(path) if path.suffix.lower() == ".npz" else read_csv(path, self.layout)
        except dg.ParamError as exc:
            raise dg.ParamError(f"{self.name}: {exc}", entity=self.name) from None
        except (OSError, UnicodeDecodeError, csv.Error) as exc:
            raise dg.ParamError(f"{self.name}: cannot read trajectory file {path}: {exc}", entity=self.name) from None
        self.data = data
        self.size = data.position.shape[1]
        self.value_shape = (self.size,)
        time, p = data.time, data.position
        self._given_v = data.velocity is not None
        if self.interpolation == "cubic" and not self._given_v:
            self._m = natural_spline_second_derivatives(time, p)
        self._v = data.velocity if self._given_v else np.gradient(p, time, axis=0)
        if data.acceleration is not None:
            self._a = data.acceleration
        else:
            self._a = np.gradient(self._v, time, axis=0)

    @property
    def knots(self) -> np.ndarray:
        """The knot times of the file (s, file time)."""
        return self.data.time

    def _segment(self, t: int) -> tuple[int, float, float] | None:
        """``(k, u, h)`` for the file time at tick ``t``, or None outside ``[t_0, t_N]``."""
        time = self.data.time
        tau = t * self.dt - self.start
        if tau < time[0] or tau > time[-1]:
            return None
        k = min(int(np.searchsorted(time, tau, side="right")) - 1, len(time) - 2)
        h = time[k + 1] - time[k]
        return k, (tau - time[k]) / h, h

    def _outside(self, t: int) -> np.ndarray:
        tau = t * self.dt - self.start
        return self.data.position[0 if tau < self.data.time[0] else -1].copy()

    @dg.output(shape=lambda self: self.value_shape, depends=("t",))
    def position(self, t: int) -> np.ndarray:
        """Interpolated position (held at the ends)."""
        seg = self._segment(t)
        if seg is None:
            return self._outside(t)
        k, u, h = seg
        p = self.data.position
        if self.interpolation == "linear":
            return (1 - u) * p[k] + u * p[k + 1]
        if self._given_v:
            v = self._v
            h00, h10, h01, h11 = 2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u, -2 * u**3 + 3 * u**2, u**3 - u**2
            return h00 * p[k] + h10 * h * v[k] + h01 * p[k + 1] + h11 * h * v[k + 1]
        m = self._m
        w = 1 - u
        return w * p[k] + u * p[k + 1] + h * h / 6.0 * ((w**3 - w) * m[k] + (u**3 - u) * m[k + 1])

    @dg.output(shape=lambda self: self.value_shape, depends=("t",))
    def velocity(self, t: int) -> np.ndarray:
        """Interpolated velocity (zero outside the file's time range)."""
        seg = self._segment(t)
        if seg is None:
            return np.zeros(self.size)
        k, u, h = seg
        p, v = self.data.position, self._v
        if self.interpolation == "linear":
            return (1 - u) * v[k] + u * v[k + 1]
        if self._given_v:
            d00, d10, d01, d11 = 6 * u**2 - 6 * u, 3 * u**2 - 4 * u + 1, -6 * u**2 + 6 * u, 3 * u**2 - 2 * u
            return (d00 * p[k] + d01 * p[k + 1]) / h + d10 * v[k] + d11 * v[k + 1]
        m = self._m
        w = 1 - u
        return (p[k + 1] - p[k]) / h + h / 6.0 * ((1 - 3 * w**2) * m[k] + (3 * u**2 - 1) * m[k + 1])

    @dg.output(shape=lambda self: self.value_shape, depends=("t",))
    def acceleration(self, t: int) -> np.ndarray:
        """Interpolated acceleration (zero outside the file's time range)."""
        seg = self._segment(t)
        if seg is None:
            return np.zeros(self.size)
        k, u, h = seg
        if self.interpolation == "linear" or self.data.acceleration is not None:
            return (1 - u) * self._a[k] + u * self._a[k + 1]
        p = self.data.position
        if self._given_v:
            v = self._v
            e00, e10, e01, e11 = 12 * u - 6, 6 * u - 4, -12 * u + 6, 6 * u - 2
            return (e00 * p[k] + e01 * p[k + 1]) / h**2 + (e10 * v[k] + e11 * v[k + 1]) / h
        return (1 - u) * self._m[k] + u * self._m[k + 1]
