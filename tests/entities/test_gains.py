"""Gains: scalar-or-vector gain inputs as checked vectors and Python floats, converted once per value."""

from __future__ import annotations

import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.tasks.gains import Gains


class Holder(dg.Entity):
    kp = dg.Input(default=0.0)


class Schedule(dg.Entity):
    """A gain written into the same buffer at every tick (the value changes on odd ticks)."""

    def configure(self):
        self.buffer = np.zeros(3)

    @dg.output(shape=(3,), depends=("t",))
    def kp(self, t):
        self.buffer[:] = [1.0 + t // 2, 2.0, 3.0]
        return self.buffer


def test_floats_follow_the_vector_and_are_converted_once_per_value():
    g = dg.Graph()
    holder = g.add(Holder("holder"))
    gains = Gains(holder)
    holder.kp.set(2.0)
    first = gains.floats("kp", 3, 0)
    assert first == [2.0, 2.0, 2.0] and gains.floats("kp", 3, 1) is first
    holder.kp.set([1.0, 2.0, 3.0])
    assert gains.floats("kp", 3, 2) == [1.0, 2.0, 3.0]
    g.add(Schedule("schedule"))
    g.plug("schedule.kp", "holder.kp")
    seen = [gains.floats("kp", 3, t) for t in range(3, 7)]
    assert [row[0] for row in seen] == [2.0, 3.0, 3.0, 4.0]  # the producer's buffer, read by value
    assert seen[1] is seen[2] and seen[0] is not seen[1]
    holder.kp.set(-1.0)
    with pytest.raises(dg.SpecError, match="holder.kp must be >= 0"):
        gains.floats("kp", 3, 7)
