"""ContactDetector: made / lost contact from a measured force, with thresholds and dwell times."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

import dgraph as dg

APPROACHING, IN_CONTACT, LOST = 0, 1, 2


@dg.register
class ContactDetector(dg.Entity):
    """A contact's phase from the normal force ``f_n = n . F`` (the supervisor that, in the
    thesis's pushing scenario, removes the force task once the contact is lost, §5.4.1):

    - ``0`` approaching: until ``f_n >= on_force`` for ``on_time`` s, then
    - ``1`` in contact: until ``f_n <= off_force`` for ``off_time`` s, then
    - ``2`` lost, which is final (the task stays removed; a new contact needs a new plan).

    Parameters: ``normal`` (3, world), ``on_force``, ``off_force`` (N, ``off < on``: hysteresis),
    ``on_time``, ``off_time`` (s), ``dt``.
    Inputs: ``force`` (3, N, world, the force on the robot).
    States: ``phase`` (int), ``in_contact`` (bool, phase 1), ``timer`` (s the current condition has held).
    """

    has_state = True
    normal = dg.Param([0.0, 0.0, 1.0], kind="vector", doc="contact normal, world")
    on_force = dg.Param(5.0, kind="float", minimum=0.0, doc="normal force that makes a contact (N)")
    off_force = dg.Param(2.0, kind="float", minimum=0.0, doc="normal force under which it is lost (N)")
    on_time = dg.Param(0.01, kind="float", minimum=0.0, doc="dwell before a contact is made (s)")
    off_time = dg.Param(0.05, kind="float", minimum=0.0, doc="dwell before a contact is lost (s)")
    dt = dg.Param(None, kind="float", minimum=1e-6, doc="tick period in s (default: the graph's dt)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, normal: ArrayLike = (0.0, 0.0, 1.0), on_force: float = 5.0, off_force: float = 2.0,
            on_time: float = 0.01, off_time: float = 0.05, dt: float | None = None,
        ) -> None: ...

    force = dg.Input(shape=(3,), doc="measured force on the robot (N, world)")
    phase = dg.State(shape=(), dtype="int", initial=APPROACHING, doc="0 approaching, 1 in contact, 2 lost")
    in_contact = dg.State(shape=(), dtype="bool", initial=False, doc="phase == 1")
    timer = dg.State(shape=(), initial=0.0, doc="time the switching condition has held (s)")

    def configure(self) -> None:
        """Unit normal; hysteresis check."""
        normal = np.asarray(self.normal, dtype=float)
        if normal.shape != (3,) or not np.linalg.norm(normal) > 1e-9:
            raise dg.ParamError(f"{self.name}: normal must be a non-zero 3-vector", entity=self.name)
        if self.off_force >= self.on_force:
            raise dg.ParamError(f"{self.name}: off_force must be below on_force", entity=self.name)
        self._normal = normal / np.linalg.norm(normal)

    def prepare_state(self, t: int) -> None:
        """Advance the phase when its switching condition has held long enough."""
        phase = int(self.phase(t))
        normal_force = float(self._normal @ self.force(t))
        switching = (phase == APPROACHING and normal_force >= self.on_force) or \
                    (phase == IN_CONTACT and normal_force <= self.off_force)
        timer = float(self.timer(t)) + self.dt if switching else 0.0
        # a millionth of a tick of slack: n ticks of dt may add up to just under n dt (10 x 0.01 s)
        if switching and timer >= (self.on_time if phase == APPROACHING else self.off_time) - 1e-6 * self.dt:
            phase, timer = phase + 1, 0.0
        self.phase.stage(phase)
        self.in_contact.stage(phase == IN_CONTACT)
        self.timer.stage(timer)

    def commit_state(self, t_next: int) -> None:
        """Publish the phase."""
        self.phase.commit(t_next)
        self.in_contact.commit(t_next)
        self.timer.commit(t_next)
