"""Add: a weighted sum of n inputs."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from numpy.typing import ArrayLike

import dgraph as dg
from dgraph.entities.operators.shape import vector_shape
from dgraph.params import MAX_PORTS, MAX_SIZE


@dg.register
class Add(dg.Entity):
    """Weighted sum ``output = sum_i coefficients[i] * in_i``.

    Parameters: ``n_inputs`` (default 2), ``coefficients`` (default all 1; ``[1, -1]`` is a
    difference), ``size`` (None for scalars).
    Inputs: ``in0 .. in{n-1}``. Outputs: ``output``.
    """

    n_inputs = dg.Param(2, kind="int", minimum=1, maximum=MAX_PORTS, doc="number of summed inputs")
    coefficients = dg.Param(None, kind="vector", doc="weight of each input (default: all 1)")
    size = dg.Param(None, kind="int", minimum=1, maximum=MAX_SIZE, doc="vector size (None: scalar)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, n_inputs: int = 2, coefficients: ArrayLike | None = None, size: int | None = None,
        ) -> None: ...

    def configure(self) -> None:
        """Declare the inputs ``in0 .. in{n-1}`` and check the coefficients."""
        coeffs = [1.0] * self.n_inputs if self.coefficients is None else list(self.coefficients.ravel())
        if len(coeffs) != self.n_inputs:
            raise dg.ParamError(f"{self.name}: {len(coeffs)} coefficients for {self.n_inputs} inputs",
                             entity=self.name)
        self._coeffs = [float(c) for c in coeffs]
        for i in range(self.n_inputs):
            self.declare(f"in{i}", dg.Input(shape=vector_shape, doc=f"term {i}"))

    def setup(self) -> None:
        """Pair each input with its coefficient."""
        self._terms = [(c, getattr(self, f"in{i}")) for i, c in enumerate(self._coeffs)]

    @dg.output(shape=vector_shape)
    def output(self, t: int) -> Any:
        """The weighted sum."""
        total: Any = 0.0
        for c, term in self._terms:
            value = term(t)
            total = total + (value if c == 1.0 else c * value)
        return total
