"""GroundTruthEstimator: the simulator's true state, behind the same ports as a real estimator."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import dgraph as dg


@dg.register
class GroundTruthEstimator(dg.Entity):
    """Pass-through: ``q(t) = q_true(t)``, ``v(t) = v_true(t)``.

    Plug a simulator's ground-truth ``q`` and ``v`` here, and its consumers to ``q`` and ``v``;
    swapping for :class:`FloatingBaseEstimator` is then a matter of plugging, not rewiring.

    Parameters: ``nq``, ``nv`` (default TALOS: 39, 38). Inputs: ``q``, ``v``. Outputs: ``q``, ``v``.
    """

    nq = dg.Param(39, kind="int", minimum=1, maximum=10_000, doc="configuration size")
    nv = dg.Param(38, kind="int", minimum=1, maximum=10_000, doc="velocity size")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(self, name: str, *, nq: int = 39, nv: int = 38) -> None: ...

    q_true = dg.Input(shape=("nq",), doc="true configuration (Pinocchio conventions)")
    v_true = dg.Input(shape=("nv",), doc="true velocity (Pinocchio conventions)")

    @dg.output(shape=("nq",), depends=("q_true",))
    def q(self, t: int) -> Any:
        """Estimated configuration: the true one."""
        return self.q_true(t)

    @dg.output(shape=("nv",), depends=("v_true",))
    def v(self, t: int) -> Any:
        """Estimated velocity: the true one."""
        return self.v_true(t)
