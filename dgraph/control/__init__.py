"""The maths of the whole-body solvers, with no entity in it: what tasks, contacts, tanks and
solvers hand each other, and the solver algorithms more than one entity family calls.

Vocabulary (each class a structured value type, :mod:`dgraph.signals.value_types`):

- :mod:`~dgraph.control.rows` -- :class:`RowBlock`, equalities and inequalities over a solver's
  variables (a priority level is made of them);
- :mod:`~dgraph.control.feature` -- :class:`FeatureValue`, a task-space quantity at one tick;
- :mod:`~dgraph.control.equation` -- :class:`TaskEquation`, a weighted row block over the
  accelerations;
- :mod:`~dgraph.control.contact` -- :class:`ContactConstraint`, a contact's rows and force variables;
- :mod:`~dgraph.control.passivity` -- :class:`Passivity`, what an energy tank hands a passive solve;
- :mod:`~dgraph.control.solutions` -- :class:`QPSolution`, :class:`CascadeSolution`;
- :mod:`~dgraph.control.status` -- :class:`Status`, how a solve ended.

Algorithms:

- :mod:`~dgraph.control.proxqp` -- ProxQP's settings and status, a problem warm-started tick after tick;
- :mod:`~dgraph.control.inverse_dynamics` -- the rows of whole-body inverse dynamics and the
  weighted QP of thesis Eq. 4.14;
- :mod:`~dgraph.control.cascade` -- the lexicographic cascade of Eq. 4.4 / 2.59.

The layer imports numpy, scipy, proxsuite and :mod:`dgraph.signals.value_types` only; entity
families import it, the core never does (``tests/control/test_layering.py``).
"""

from dgraph.control.contact import ContactConstraint
from dgraph.control.equation import TaskEquation
from dgraph.control.feature import FeatureValue
from dgraph.control.passivity import Passivity
from dgraph.control.rows import RowBlock
from dgraph.control.solutions import CascadeSolution, QPSolution
from dgraph.control.status import (
    DUAL_INFEASIBLE,
    MAX_ITERATIONS,
    NOT_FINITE,
    NOT_SOLVED,
    PRIMAL_INFEASIBLE,
    SOLVED,
    Status,
)

__all__ = ["DUAL_INFEASIBLE", "MAX_ITERATIONS", "NOT_FINITE", "NOT_SOLVED", "PRIMAL_INFEASIBLE", "SOLVED",
           "CascadeSolution", "ContactConstraint", "FeatureValue", "Passivity", "QPSolution", "RowBlock", "Status",
           "TaskEquation"]
