"""The linear model-predictive pattern generator on the cart-table (LIPM) model, solved by ProxQP.

This is the linear MPC of Wieber (2006), as jrl-walkgen runs it, on the model of thesis Eq. 2.22
(its walking pattern generator, thesis §2.4 L1514-1580, is the nonlinear descendant of it).
Per horizontal axis the state is ``x = [c, c_dot, c_ddot]``, the input the CoM jerk ``u``, held
constant over each sample of ``T`` seconds::

    x+ = A x + B u,   A = [[1, T, T^2/2], [0, 1, T], [0, 0, 1]],   B = [T^3/6, T^2/2, T]
    z  = c - (h/g) c_ddot                                           (the ZMP, Eq. 2.22)
    xi = c + c_dot / omega,   omega = sqrt(g/h)                     (the DCM, Eq. 2.27)

Over a horizon of ``N`` samples, with ``U = [u_0 .. u_{N-1}]``, every predicted quantity is
affine in ``(x0, U)`` (the condensed form): ``Z = P_zs x0 + P_zu U``, ``V = P_vs x0 + P_vu U``
(the velocities ``c_dot_k``), ``xi_N = p_xs x0 + p_xu U``, for ``k = 1..N``. Both axes are in
one problem over ``[U_x, U_y]`` (2N variables), because a support polygon's edges couple x and
y as soon as a foot yaws::

    min  1/2 sum_k [ beta ||z_k - z_ref_k||^2 + alpha ||c_dot_k - c_dot_ref_k||^2 + gamma ||u_(k-1)||^2 ]
    s.t. E_k z_k <= e_k        k = 1..N      (the ZMP in the support polygon of sample k)
         E_N xi_N <= e_N                     (the DCM at the horizon's end in the last polygon)

The polygons are the footstep plan's, already shrunk by a safety margin (0.02 m by default in
the pattern generator; placo uses 0.025 m). The terminal constraint makes the end of the
horizon capturable: the capture point of a LIPM whose DCM is inside the support polygon can be
brought to rest over it (the terminal capture-point constraint of the HRC walking pattern
generator, thesis §4.5.3.b L5137-5177). Default weights and horizon are jrl-walkgen's
(``nmpc_generator.cpp``): ``T = 0.1 s``, ``N = 16`` (1.6 s), ``alpha = 5`` (CoM velocity),
``beta = 1e3`` (ZMP), ``gamma = 5e-4`` (jerk).

The cost's Hessian, the condensed matrices and the ProxQP problem are built once (a new CoM
height means a new :class:`LipmMpc`); each solve writes the gradient, the constraint rows and
their bounds into the same problem and warm-starts from the previous solution (shifted by the
whole samples elapsed since it was made: none when it re-plans every 5 ms, some after failed
re-plans). Every polygon is padded to ``max_edges`` rows (a zero row with an
infinite bound is inactive), so the problem's size never changes. The ZMP is constrained at the
samples only: between two of them it follows the cubic CoM and may leave a polygon whose phase
is shorter than ``T`` (a 0.115 s double support moving the ZMP 0.6 m does, by up to 62 mm on the
60 cm walk's plan, docs/walking.md; the 20 cm walk's stays 2 cm inside its soles). A failed solve raises
nothing: its :class:`MpcResult` has the status and no trajectory, and the caller keeps the
previous one.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from dgraph.control.proxqp import INFINITY, WarmStartedQP
from dgraph.control.status import NOT_FINITE, SOLVED, Status
from dgraph.entities.stabilizers.lipm import GRAVITY, natural_frequency

MAX_EDGES = 8
"""Rows per polygon: the convex hull of two rectangular soles has at most 8 edges."""
EPS_ABS = 1e-6
"""ProxQP's absolute tolerance (m for the ZMP rows)."""
MAX_ITERATIONS = 1000
"""ProxQP's iteration limit per solve."""
PROXIMAL_RHO = 1e-8
"""ProxQP's proximal parameter (the inverse dynamics' choice)."""


def lipm_transition(sampling: float) -> tuple[np.ndarray, np.ndarray]:
    """``A`` (3x3) and ``B`` (3,) of the jerk-driven cart-table over one sample of ``sampling`` s."""
    square = sampling * sampling
    transition = np.array([[1.0, sampling, square / 2], [0.0, 1.0, sampling], [0.0, 0.0, 1.0]])
    return transition, np.array([square * sampling / 6, square / 2, sampling])


def pad_polygon(edges: np.ndarray, offsets: np.ndarray, max_edges: int = MAX_EDGES) -> tuple[np.ndarray, np.ndarray]:
    """The half-planes ``edges z <= offsets`` as ``max_edges`` rows: the extra rows are zero with an
    infinite offset (never active). ``ValueError`` if there are more than ``max_edges``."""
    edges, offsets = np.asarray(edges, dtype=float), np.asarray(offsets, dtype=float)
    count = len(offsets)
    if count > max_edges or edges.shape != (count, 2):
        raise ValueError(f"a polygon of {count} edges (normals {edges.shape}) does not fit {max_edges} rows of 2")
    padded_edges, padded_offsets = np.zeros((max_edges, 2)), np.full(max_edges, INFINITY)
    padded_edges[:count], padded_offsets[:count] = edges, offsets
    return padded_edges, padded_offsets


def padded_polygons(polygons: Sequence[tuple[np.ndarray, np.ndarray]],
                    max_edges: int = MAX_EDGES) -> tuple[np.ndarray, np.ndarray]:
    """``(edges (N, M, 2), offsets (N, M))`` of a sequence of ``(A, b)`` half-plane sets."""
    padded = [pad_polygon(edges, offsets, max_edges) for edges, offsets in polygons]
    return np.stack([p[0] for p in padded]), np.stack([p[1] for p in padded])


@dataclass(frozen=True, eq=False)
class LipmTrajectory:
    """A CoM trajectory of piecewise-constant jerk, on both horizontal axes (the last axis: x, y).

    ``states[k]`` is ``[c, c_dot, c_ddot]`` at ``k T`` (``k = 0..N``), ``jerks[k]`` the jerk over
    ``[k T, (k+1) T)``; after ``N T`` the jerk is zero (the model with no input: the horizon's
    end, extrapolated). ``omega = sqrt(g/h)``.
    """

    sampling: float
    omega: float
    states: np.ndarray
    jerks: np.ndarray
    pieces: np.ndarray = field(init=False, repr=False)
    """``[c, c_dot, c_ddot, u]`` (N+1, 4, 2) at the start of every sample and of the tail."""

    def __post_init__(self) -> None:
        tail = np.concatenate([self.states[-1:], np.zeros((1, 1, 2))], axis=1)
        pieces = np.concatenate([np.concatenate([self.states[:-1], self.jerks[:, None, :]], axis=1), tail])
        object.__setattr__(self, "pieces", pieces)

    @classmethod
    def from_jerks(cls, initial_state: np.ndarray, jerks: np.ndarray, sampling: float,
                   omega: float) -> LipmTrajectory:
        """Integrate ``x+ = A x + B u`` from ``initial_state`` (3, 2) under ``jerks`` (N, 2)."""
        transition, jerk_input = lipm_transition(sampling)
        states = np.empty((len(jerks) + 1, 3, 2))
        states[0] = initial_state
        for k, jerk in enumerate(jerks):
            states[k + 1] = transition @ states[k] + np.outer(jerk_input, jerk)
        return cls(sampling, omega, states, np.asarray(jerks, dtype=float))

    def sample(self, elapsed: float) -> np.ndarray:
        """``[c, c_dot, c_ddot, u]`` (4, 2) at ``elapsed`` s after the start: the exact cubic of the
        sample holding it, ``c = c_k + s c_dot_k + s^2/2 c_ddot_k + s^3/6 u_k``, ``s = elapsed - k T``."""
        index = min(max(int(elapsed / self.sampling), 0), len(self.jerks))
        s = elapsed - index * self.sampling
        half_square = s * s / 2
        powers = np.array([[1.0, s, half_square, half_square * s / 3], [0.0, 1.0, s, half_square],
                           [0.0, 0.0, 1.0, s], [0.0, 0.0, 0.0, 1.0]])
        return powers @ self.pieces[index]

    def zmp(self) -> np.ndarray:
        """``z_k = c_k - c_ddot_k / omega^2`` at the samples (N+1, 2) (Eq. 2.22)."""
        return self.states[:, 0] - self.states[:, 2] / self.omega**2

    def dcm(self) -> np.ndarray:
        """``xi_k = c_k + c_dot_k / omega`` at the samples (N+1, 2) (Eq. 2.27)."""
        return self.states[:, 0] + self.states[:, 1] / self.omega


@dataclass(frozen=True, eq=False)
class MpcResult:
    """One solve: its :class:`~dgraph.control.status.Status`, ProxQP iterations, wall time (s) of
    the assembly and the solve, and the trajectory (None unless solved)."""

    status: Status
    iterations: int
    solve_time: float
    trajectory: LipmTrajectory | None


class CondensedLipm:
    """The condensed predictions over ``N`` samples of ``T`` s, for a CoM height ``h``:
    ``state_maps[k]`` (3x3) and ``jerk_maps[k]`` (3xN) give ``x_k = state_maps[k] x0 +
    jerk_maps[k] U`` (``k = 0..N``); from them ``P_zs, P_zu`` (ZMP), ``P_vs, P_vu`` (velocity) over
    ``k = 1..N`` and the rows ``p_xs, p_xu`` of the DCM at ``k = N``."""

    def __init__(self, sampling: float, horizon: int, com_height: float, gravity: float = GRAVITY):
        transition, jerk_input = lipm_transition(sampling)
        self.omega = float(natural_frequency(com_height, gravity))
        self.state_maps = np.empty((horizon + 1, 3, 3))
        self.jerk_maps = np.zeros((horizon + 1, 3, horizon))
        self.state_maps[0] = np.eye(3)
        for k in range(horizon):
            self.state_maps[k + 1] = transition @ self.state_maps[k]
            self.jerk_maps[k + 1] = transition @ self.jerk_maps[k]
            self.jerk_maps[k + 1, :, k] = jerk_input
        zmp_row = np.array([1.0, 0.0, -com_height / gravity])
        dcm_row = np.array([1.0, 1.0 / self.omega, 0.0])
        self.zmp_state, self.zmp_jerk = zmp_row @ self.state_maps[1:], zmp_row @ self.jerk_maps[1:]
        self.velocity_state, self.velocity_jerk = self.state_maps[1:, 1], self.jerk_maps[1:, 1]
        self.dcm_state, self.dcm_jerk = dcm_row @ self.state_maps[-1], dcm_row @ self.jerk_maps[-1]


class LipmMpc:
    """The MPC of the module docstring for one CoM height ``com_height`` (m above the ground).

    Parameters: ``sampling`` (T, s), ``horizon`` (N), ``alpha``, ``beta``, ``gamma`` (weights of
    the CoM velocity, ZMP and jerk terms), ``max_edges`` (rows per polygon), ``gravity``,
    ``eps_abs`` and ``max_iterations`` (ProxQP's).
    """

    def __init__(self, com_height: float, *, sampling: float = 0.1, horizon: int = 16, alpha: float = 5.0,
                 beta: float = 1e3, gamma: float = 5e-4, max_edges: int = MAX_EDGES, gravity: float = GRAVITY,
                 eps_abs: float = EPS_ABS, max_iterations: int = MAX_ITERATIONS):
        if not (com_height > 0 and sampling > 0 and horizon >= 1):
            raise ValueError(f"need com_height > 0, sampling > 0, horizon >= 1; got {com_height}, {sampling}, "
                             f"{horizon}")
        self.com_height, self.sampling, self.horizon, self.max_edges = com_height, sampling, horizon, max_edges
        self.alpha, self.beta = alpha, beta
        self.model = model = CondensedLipm(sampling, horizon, com_height, gravity)
        self.omega = model.omega
        hessian = (beta * model.zmp_jerk.T @ model.zmp_jerk + alpha * model.velocity_jerk.T @ model.velocity_jerk
                   + gamma * np.eye(horizon))
        self.hessian = np.kron(np.eye(2), hessian)  # the same block for x and y
        # the rows the polygons act on: the ZMP at k = 1..N, then the DCM at N (with the last polygon)
        self.constrained_jerk = np.vstack([model.zmp_jerk, model.dcm_jerk])
        self.constrained_state = np.vstack([model.zmp_state, model.dcm_state])
        n_rows = (horizon + 1) * max_edges
        self.qp = WarmStartedQP(2 * horizon, 0, n_rows, eps_abs=eps_abs, max_iterations=max_iterations,
                                rho=PROXIMAL_RHO)
        self.no_equality = (np.zeros((0, 2 * horizon)), np.zeros(0))
        self.lower = np.full(n_rows, -INFINITY)

    def gradient(self, initial_state: np.ndarray, zmp_reference: np.ndarray,
                 velocity_reference: np.ndarray) -> np.ndarray:
        """``g = [g_x, g_y]``, ``g_a = beta P_zu^T (P_zs x0_a - z_ref_a) + alpha P_vu^T (P_vs x0_a - v_ref_a)``."""
        model = self.model
        zmp_error = model.zmp_state @ initial_state - zmp_reference
        velocity_error = model.velocity_state @ initial_state - velocity_reference
        per_axis = self.beta * model.zmp_jerk.T @ zmp_error + self.alpha * model.velocity_jerk.T @ velocity_error
        return per_axis.T.ravel()

    def constraints(self, initial_state: np.ndarray, edges: np.ndarray,
                    offsets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``C U <= upper``: for each sample's padded polygon ``(E_k, e_k)`` (``edges`` (N, M, 2),
        ``offsets`` (N, M)), ``E_k z_k <= e_k``, then the last polygon on the DCM at ``N``."""
        edges = np.concatenate([edges, edges[-1:]])
        offsets = np.concatenate([offsets, offsets[-1:]])
        jerk_rows = self.constrained_jerk[:, None, :]
        matrix = np.concatenate([edges[..., 0, None] * jerk_rows, edges[..., 1, None] * jerk_rows], axis=2)
        free_motion = self.constrained_state @ initial_state  # (N+1, 2): the rows with U = 0
        upper = offsets - np.einsum("kmi,ki->km", edges, free_motion)
        return matrix.reshape(-1, 2 * self.horizon), upper.ravel()

    def solve(self, initial_state: np.ndarray, zmp_reference: np.ndarray, velocity_reference: np.ndarray,
              polygons: tuple[np.ndarray, np.ndarray], tick: int | None = None, shift: int = 0) -> MpcResult:
        """Plan from ``initial_state`` (3, 2) toward ``zmp_reference`` and ``velocity_reference``
        (N, 2, at the samples ``k = 1..N``) inside ``polygons`` = ``(edges (N, M, 2), offsets (N, M))``
        (padded by :func:`pad_polygon`). The warm start is the previous solution, its jerks moved
        ``shift`` samples earlier (the time elapsed since it, in whole samples); ``tick``: see
        :class:`~dgraph.control.proxqp.WarmStartedQP`. Never raises on a failed solve."""
        started = time.perf_counter()
        initial_state = np.asarray(initial_state, dtype=float)
        if not np.isfinite(initial_state).all():
            return MpcResult(NOT_FINITE, 0, time.perf_counter() - started, None)
        gradient = self.gradient(initial_state, zmp_reference, velocity_reference)
        matrix, upper = self.constraints(initial_state, *polygons)
        problem = (self.hessian, gradient, *self.no_equality, matrix, self.lower, upper)
        status, iterations = self.qp.solve(problem, tick, self._shifted_guess(shift))
        trajectory = None
        if status == SOLVED:
            jerks = self.qp.latest[0].reshape(2, self.horizon).T.copy()
            trajectory = self.trajectory(initial_state, jerks)
        return MpcResult(status, iterations, time.perf_counter() - started, trajectory)

    def trajectory(self, initial_state: np.ndarray, jerks: np.ndarray) -> LipmTrajectory:
        """The trajectory of ``jerks`` (N, 2) from ``initial_state`` (3, 2), from the condensed maps."""
        model = self.model
        states = model.state_maps @ initial_state + model.jerk_maps @ jerks
        return LipmTrajectory(self.sampling, self.omega, states, jerks)

    def _shifted_guess(self, shift: int) -> tuple[np.ndarray, ...] | None:
        """The previous solution with its jerks and its sample rows moved ``shift`` samples
        earlier (zeros after), or None (the default warm start) for no shift or no solution."""
        if shift <= 0 or not self.qp.has_solution:
            return None
        x, y, z = self.qp.latest
        n, rows = self.horizon, self.max_edges
        jerks = np.zeros((2, n))
        if shift < n:
            jerks[:, :n - shift] = x.reshape(2, n)[:, shift:]
        multipliers = np.zeros_like(z)
        kept = max(n - shift, 0) * rows
        multipliers[:kept] = z[shift * rows:shift * rows + kept]
        return jerks.ravel(), y, multipliers
