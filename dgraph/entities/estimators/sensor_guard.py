"""SensorGuard: the check of raw sensor readings where they enter the controller, and what replaces a bad one.

A robot controller must keep sending a safe command when one sample is bad. An estimator reads
its sensor inputs through a guard, which checks every element of every reading at every tick
and hands over a value the estimator can trust:

- **non-finite** (NaN, inf): refused;
- **out of range**: outside ``[lower, upper]`` (a joint's limits with a margin, a sensor's
  measuring range);
- **jump**: farther than ``max_step`` from the prediction (the last trusted value, plus
  ``dt`` times the trusted rate for a position that has one: a joint encoder's velocity). The
  bound grows with each tick ``n`` an element has been replaced, ``max_step + growth n``, so a
  reading that comes back, or that really moved while it was replaced, is trusted again. A
  reading that stays off by a constant is indistinguishable from a real change once the bound
  has grown past the offset: ``growth`` (``max_step / 100`` by default: an offset of 2
  ``max_step`` is refused for 100 ticks) sets how long that takes;
- **frozen**: bit for bit the same as the last reading ``frozen_ticks`` times in a row (a
  sensor whose driver stopped; a real reading always carries noise, a simulated one always
  moves a little); an exact 0 is not taken for frozen (a joint at rest in a noiseless
  simulation, an unloaded axis);
- **stale**: its source, a state (a device's reading; a computed output is stamped whenever it
  is computed, so it is never taken for stale), last updated more than ``stale_ticks`` ticks ago, as
  seen every ``stale_ticks / 4`` ticks (a
  driver that stopped delivering a sensor; a slower sensor under a faster loop is stale for a
  tick or two, so the bound is a parameter): handled like a frozen reading, one fault per input;
- a **quaternion** (``Channel.quaternion``) is refused as a whole (one bad element makes it no
  rotation), also when its norm is not 1 within 1 %, and is compared with its prediction up to
  its sign (``q`` and ``-q`` are the same rotation: a reading that flips sign is turned back,
  not refused).

A refused element is replaced by its prediction, the tick goes on, and a fault is reported
(:mod:`dgraph.faults`) naming ``entity.input[index]``, the cause and the value. A frozen element
is reported; a frozen position is replaced by its prediction, a frozen reading without a rate is
kept (there is nothing better to use). The trusted values are what the next tick predicts from;
a position whose rate is itself a substitute is predicted with a rate of 0, within its range (a
driver that stopped sends neither: its last velocity is not integrated for ever).
The first reading has no prediction: a bad element there is filled with a value in its range
(the identity for a quaternion), checked for range only until it reads good once.

Cost: the readings are checked together, as one vector (a handful of numpy operations per
tick); only a tick with a bad element looks at the elements one by one.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

import dgraph as dg
from dgraph.signals.signal import State

MAX_NAMED = 4
"""Elements named one by one in the faults of one reading at one tick (the rest are counted)."""


@dataclass(frozen=True)
class Channel:
    """One guarded sensor input: ``name`` (an input of the entity), ``lower``/``upper`` (its
    range, per element or scalar; ``±inf`` for none), ``max_step`` (per tick, ``inf`` for no jump
    test), ``growth`` (of the bound per replaced tick; None: the default of the module
    docstring), ``rate`` (the name of the channel that is this one's time derivative, or None),
    ``frozen`` (test for a frozen reading), ``quaternion`` (a unit quaternion ``[x, y, z, w]``)."""

    name: str
    lower: float | np.ndarray = -np.inf
    upper: float | np.ndarray = np.inf
    max_step: float | np.ndarray = np.inf
    growth: float | None = None
    rate: str | None = None
    frozen: bool = True
    quaternion: bool = False


QUATERNION_NORM_TOLERANCE = 0.01
"""How far from 1 a quaternion's norm may be (1 %)."""


class SensorGuard:
    """The guard of an entity's sensor inputs (see the module docstring).

    ``read(t)`` returns the trusted value of each channel at ``t`` (fresh arrays, in the order of
    ``channels``) and sets ``faulty`` (how many elements it replaced or found frozen);
    ``commit()`` makes them the prediction base of the next tick (call it from the entity's
    ``commit_state``, so a failed tick changes nothing). ``frozen_ticks`` 0 turns the frozen
    test off, ``stale_ticks`` 0 (the default) the stale one.
    """

    def __init__(self, entity: dg.Entity, channels: Sequence[Channel], dt: float, frozen_ticks: int = 50,
                 stale_ticks: int = 0):
        self.entity = entity
        self.stale_ticks = int(stale_ticks)
        self._stale_every = max(1, self.stale_ticks // 4)  # looked at every so often: stale means for long
        self._was_stale = False
        self.channels = list(channels)
        self._inputs = [entity.signal(c.name) for c in self.channels]
        sizes = [int(np.prod(inp.spec.shape)) for inp in self._inputs]
        self._slices, start = [], 0
        for size in sizes:
            self._slices.append(slice(start, start + size))
            start += size
        n = start
        by_name = {c.name: (c, s, size) for c, s, size in zip(self.channels, self._slices, sizes, strict=True)}
        self._lower, self._upper, self._step, self._growth = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
        self._frozen_test = np.zeros(n, dtype=bool)
        self._position_slices: list[tuple[slice, slice]] = []
        self._quaternions = [s for c, s, _ in by_name.values() if c.quaternion]
        self._not_unit: list[slice] = []
        self._has_position = np.zeros(n, dtype=bool)
        for channel, part, size in by_name.values():
            self._lower[part], self._upper[part], self._step[part] = channel.lower, channel.upper, channel.max_step
            step = self._step[part]  # no growth for no jump test (inf * 0 would be NaN)
            default_growth = np.where(np.isfinite(step), step / 100.0, 0.0)
            self._growth[part] = default_growth if channel.growth is None else channel.growth
            self._frozen_test[part] = channel.frozen
            if channel.rate is not None:
                rate_channel = by_name.get(channel.rate)
                if rate_channel is None or rate_channel[2] != size:
                    raise dg.ParamError(f"{entity.name}: the rate {channel.rate!r} of {channel.name!r} is not a "
                                        f"guarded input of the same size", entity=entity.name)
                self._position_slices.append((part, rate_channel[1]))
                self._has_position[part] = True
        self.dt = float(dt)
        self.frozen_ticks = int(frozen_ticks)
        self._names = [c.name for c in self.channels]
        self._flat = all(len(inp.spec.shape) == 1 for inp in self._inputs)
        self._bounded = bool(np.isfinite(self._lower).all() and np.isfinite(self._upper).all())
        self._zero_replaced = np.zeros(n, dtype=np.int64)  # shared "none": compared by identity
        self._zero_same = np.zeros(n, dtype=np.int64)
        self._channel_of = [k for k, part in enumerate(self._slices) for _ in range(part.start, part.stop)]
        self._element_names = [(c.name, i - s.start) for c, s in zip(self.channels, self._slices, strict=True)
                               for i in range(s.start, s.stop)]
        self.faulty = 0
        self.reset()

    def reset(self) -> None:
        """No trusted value yet: the first reading is checked for finiteness and range only."""
        n = len(self._lower)
        self._trusted: np.ndarray | None = None
        self._predicted: np.ndarray | None = None
        self._raw: np.ndarray | None = None            # the last reading, as read (the frozen test)
        self._replaced = self._zero_replaced           # consecutive ticks each element was replaced
        self._same = self._zero_same                   # consecutive ticks each element was bit-identical
        self._tolerance = self._step                   # max_step + growth replaced
        self._unknown: np.ndarray | None = None        # elements never read good (filled at the first tick)
        self._next: tuple[np.ndarray, ...] | None = None  # trusted, raw, replaced, same, unknown, doubtful
        self._deviation, self._within = np.empty(n), np.empty(n, dtype=bool)

    def _predict(self, trusted: np.ndarray, doubtful: np.ndarray | None) -> np.ndarray:
        """``trusted``, each position moved by ``dt`` times its rate; a rate that is itself a
        substitute (``doubtful``: replaced, frozen or stale) counts as 0, and the prediction then
        stays in range (a driver that stopped must not integrate its last velocity for ever)."""
        predicted = trusted.copy()
        for position, rate in self._position_slices:
            speed = trusted[rate] if doubtful is None else np.where(doubtful[rate], 0.0, trusted[rate])
            predicted[position] += self.dt * speed
        if doubtful is not None:
            np.clip(predicted, self._lower, self._upper, out=predicted)
        predicted.flags.writeable = False
        return predicted

    def read(self, t: int) -> list[np.ndarray]:
        """The trusted readings at ``t`` (faults reported for the elements replaced)."""
        raw = np.concatenate([inp(t) for inp in self._inputs], axis=None)
        unit = self._orient_quaternions(raw) if self._quaternions else True
        raw.flags.writeable = False  # handed out, and kept as the next prediction's base
        stale = self._stale(t) if self.stale_ticks and (t % self._stale_every == 0 or self._was_stale) else None
        self._was_stale = bool(stale)
        if (self._trusted is None or not unit or self._replaced is not self._zero_replaced or stale
                or not self._fine(raw)):
            return self._checked(t, raw, stale)
        self._next = (raw, raw, self._zero_replaced, self._zero_same, None, None)
        self.faulty = 0
        return self._split(raw)

    def _fine(self, raw: np.ndarray) -> bool:
        """The common case, in a few numpy operations on preallocated buffers: every element
        within ``max_step`` of its prediction and in range (finite bounds refuse NaN and inf
        too), none that could be frozen the same as at the last tick."""
        deviation, within = self._deviation, self._within
        if not self._bounded and not math.isfinite(np.vdot(raw, raw)):
            return False
        np.subtract(raw, self._predicted, out=deviation)
        np.abs(deviation, out=deviation)
        n = len(raw)  # count_nonzero is the cheapest reduction of a boolean array (4x .all())
        if np.count_nonzero(np.less_equal(deviation, self._step, out=within)) != n:
            return False
        if np.count_nonzero(np.greater_equal(raw, self._lower, out=within)) != n:  # a one-sided range too
            return False
        if np.count_nonzero(np.less_equal(raw, self._upper, out=within)) != n:
            return False
        if not (self.frozen_ticks and np.count_nonzero(np.equal(raw, self._raw, out=within))):
            return True
        return not (within & self._frozen_candidates() & (raw != 0.0)).any()  # a repeated 0 cannot be frozen

    def _stale(self, t: int) -> list[tuple[int, int]]:
        """``(channel, tick of its source's last update)`` of each input whose source last
        changed more than ``stale_ticks`` ticks before ``t`` (looked at every ``stale_ticks / 4``
        ticks, and every tick while one is stale: found within 1.25 ``stale_ticks``)."""
        stale = []
        for channel, inp in enumerate(self._inputs):
            source = inp._source  # a computed output is stamped when computed, a constant has none
            updated = source.time if isinstance(source, State) else None
            if updated is not None and t - updated > self.stale_ticks:
                stale.append((channel, updated))
        return stale

    def _checked(self, t: int, raw: np.ndarray, stale: list[tuple[int, int]] | None = None) -> list[np.ndarray]:
        """Element by element: which are bad, frozen or stale, the repaired reading, the faults."""
        first = self._trusted is None
        predicted = raw if first else self._predicted
        in_range = (raw >= self._lower) & (raw <= self._upper) & np.isfinite(raw)  # NaN compares false
        tolerance = self._tolerance if self._unknown is None else np.where(self._unknown, np.inf, self._tolerance)
        bad = ~in_range if first else ~((np.abs(raw - predicted) <= tolerance) & in_range)
        for part in self._not_unit:
            bad[part] = True
        for part in self._quaternions:  # refused as a whole: a quaternion mixed of two is no rotation
            if bad[part].any():
                bad[part] = True
        same = self._same
        if self.frozen_ticks and self._raw is not None:
            same = (same + 1) * (raw == self._raw)
        frozen = self._frozen(same, raw, bad) if self.frozen_ticks else None
        held = frozen  # a frozen or stale position follows its prediction, another reading is kept
        if stale:
            held = np.zeros(len(raw), dtype=bool) if frozen is None else frozen.copy()
            for channel, _ in stale:
                held[self._slices[channel]] |= ~bad[self._slices[channel]]
            self._report_stale(t, stale)
        self.faulty = int(bad.sum()) + (0 if held is None else int(held.sum()))
        trusted = raw if not self.faulty else self._repair(t, raw, predicted, bad, frozen, held)
        replaced = np.where(bad, self._replaced + 1, 0) if bad.any() else self._zero_replaced
        if not same.any():
            same = self._zero_same
        unknown = bad.copy() if first else None if self._unknown is None else self._unknown & bad
        if unknown is not None:  # a position whose rate is unknown has no prediction either
            for position, rate in self._position_slices:
                unknown[position] |= unknown[rate]
        doubtful = bad if held is None else bad | held
        self._next = (trusted, raw, replaced, same, unknown if unknown is not None and unknown.any() else None,
                      doubtful if doubtful.any() else None)
        return self._split(trusted)

    def _frozen(self, same: np.ndarray, raw: np.ndarray, bad: np.ndarray) -> np.ndarray:
        """The elements read bit-identical ``frozen_ticks`` times that are not at rest: an exact 0
        is never frozen (a joint at rest in a noiseless simulation, an unloaded axis), nor a
        position whose trusted rate moves it by less than ``max_step`` over ``frozen_ticks``
        ticks (a quantized encoder at rest repeats its value)."""
        repeated = (same >= self.frozen_ticks) & ~bad & (raw != 0.0)
        return repeated & self._frozen_candidates() if repeated.any() else repeated

    def _frozen_candidates(self) -> np.ndarray:
        """The elements a repeated reading can be frozen in: those tested, but a position whose
        trusted rate moves it by less than ``max_step`` over ``frozen_ticks`` ticks (at rest)."""
        candidates = self._frozen_test.copy()
        for position, rate in self._position_slices:
            travel = np.abs(self._trusted[rate]) * (self.frozen_ticks * self.dt)
            candidates[position] &= travel > self._step[position]
        return candidates

    def _orient_quaternions(self, raw: np.ndarray) -> bool:
        """Whether every quaternion's norm is 1 within the tolerance (those that are not are
        listed in ``_not_unit``); one that points away from its trusted value
        (``q . q_trusted < 0``) is negated in ``raw`` first (the same rotation)."""
        self._not_unit = []
        for part in self._quaternions:
            x, y, z, w = raw[part].tolist()
            if self._trusted is not None:
                a, b, c, d = self._trusted[part].tolist()
                if a * x + b * y + c * z + d * w < 0.0:
                    raw[part] *= -1.0
            if not abs(math.sqrt(x * x + y * y + z * z + w * w) - 1.0) <= QUATERNION_NORM_TOLERANCE:
                self._not_unit.append(part)
        return not self._not_unit

    def _repair(self, t: int, raw: np.ndarray, predicted: np.ndarray, bad: np.ndarray,
                frozen: np.ndarray | None, held: np.ndarray | None) -> np.ndarray:
        """``raw`` with its bad elements (and its ``held`` positions: frozen or stale) replaced by
        their prediction; the bad and frozen elements reported. A bad element with no prediction
        yet (the first tick) takes 0, or the nearest end of its range if 0 is outside it or the
        value is finite beyond it (a quaternion: the identity)."""
        trusted = raw.copy()
        if held is not None:
            positions = held & self._has_position
            trusted[positions] = predicted[positions]
        if self._trusted is None:  # a finite value out of range: its nearest end; NaN or inf: 0, into the range
            value = np.where(np.isfinite(raw[bad]), raw[bad], 0.0)
            trusted[bad] = np.clip(value, self._lower[bad], self._upper[bad])
            for part in self._quaternions:  # clipped elements are no rotation: the identity
                if bad[part].any():
                    trusted[part] = (0.0, 0.0, 0.0, 1.0)
        else:
            trusted[bad] = predicted[bad]
        self._report(t, raw, predicted, bad, "replaced by its prediction" if self._trusted is not None
                     else "replaced by a value in range (no earlier reading)")
        if frozen is not None and frozen.any():
            self._report_frozen(t, frozen)
        trusted.flags.writeable = False  # handed out, and kept as the next prediction's base
        return trusted

    def _report(self, t: int, raw: np.ndarray, predicted: np.ndarray, bad: np.ndarray, action: str) -> None:
        """One fault per bad element (per quaternion: one for the whole reading, named by its worst
        element: non-finite, else the farthest from its prediction)."""
        faults = []
        elements = self._per_reading(bad)
        for index, channel, whole in elements[:MAX_NAMED]:  # the rest counted (a dead sensor: every tick)
            if whole:
                part = self._slices[channel]
                with np.errstate(invalid="ignore"):  # inf - inf at the first tick: NaN, taken as the worst
                    error = np.abs(raw[part] - predicted[part])
                index = part.start + int(np.argmax(np.where(np.isfinite(error), error, np.inf)))
            cause, detail = self._cause(index, raw[index], predicted)
            where = self._source(channel)
            faults.append((self._element_name(index, whole), cause, action,
                           f"{where}: {detail}" if where and detail else where or detail))
        self._emit(t, faults, len(elements), "more bad elements", action)

    def _per_reading(self, mask: np.ndarray) -> list[tuple[int, int, bool]]:
        """``(index, channel, whole)`` of each element of ``mask``; a quaternion's once (whole)."""
        elements, seen = [], set()
        for index in np.flatnonzero(mask).tolist():
            channel = self._channel_of[index]
            whole = self.channels[channel].quaternion
            if not (whole and channel in seen):
                seen.add(channel)
                elements.append((index, channel, whole))
        return elements

    def _element_name(self, index: int, whole: bool) -> str:
        name, element = self._element_names[index]
        return name if whole else f"{name}[{element}]"

    def _emit(self, t: int, faults: list[tuple[str, str, str, str]], total: int, more: str, action: str) -> None:
        """Report ``faults`` (signal, cause, action, detail), and one fault counting the
        ``total - len(faults)`` left undescribed (past :data:`MAX_NAMED`)."""
        for signal, cause, fault_action, detail in faults:
            self.entity.report_fault(t, signal, cause, fault_action, detail)
        if total > len(faults):
            self.entity.report_fault(t, "sensors", more, action, f"{total - len(faults)} more")

    def _source(self, channel: int) -> str:
        """``from <the plugged output>`` (where the bad reading came from), or nothing."""
        source = getattr(self._inputs[channel], "source", None)
        return f"from {source.full_name}" if source is not None else ""

    def _cause(self, index: int, value: float, predicted: np.ndarray) -> tuple[str, str]:
        """What is wrong with the element ``index`` of the reading, and the numbers."""
        if math.isnan(value):
            return "NaN", ""
        if math.isinf(value):
            return "inf", f"{value}"
        if any(part.start <= index < part.stop for part in self._not_unit):
            return "not a unit quaternion", f"element {value:.6g}"
        lower, upper = self._lower[index], self._upper[index]
        if not lower <= value <= upper:
            return "out of range", f"{value:.6g} not in [{lower:.6g}, {upper:.6g}]"
        return "jump", f"{value:.6g}, predicted {predicted[index]:.6g} (tolerance {self._tolerance[index]:.3g})"

    def _report_stale(self, t: int, stale: list[tuple[int, int]]) -> None:
        """One fault per stale input."""
        for channel, updated in stale:
            moving = self.channels[channel].rate is not None
            action = "replaced by its prediction" if moving else "kept (nothing better)"
            self.entity.report_fault(t, self.channels[channel].name, "stale", action,
                                     f"{self._source(channel)}: last updated at tick {updated}")

    def _report_frozen(self, t: int, frozen: np.ndarray) -> None:
        """One fault per frozen element (per quaternion: one)."""
        elements = self._per_reading(frozen)
        faults = [(self._element_name(index, whole), "frozen",
                   "replaced by its prediction" if self._has_position[index] else "kept (nothing better)",
                   f"the same for {self._same[index] + 1} ticks") for index, _, whole in elements[:MAX_NAMED]]
        self._emit(t, faults, len(elements), "more frozen elements", "as above")

    def _split(self, values: np.ndarray) -> list[np.ndarray]:
        """One read-only view of ``values`` per channel, in its input's shape."""
        if self._flat:
            return [values[part] for part in self._slices]
        return [values[part].reshape(inp.spec.shape) for part, inp in zip(self._slices, self._inputs, strict=True)]

    def commit(self) -> None:
        """The tick committed: its trusted readings become the base of the next prediction."""
        if self._next is not None:
            self._trusted, self._raw, replaced, self._same, self._unknown, doubtful = self._next
            self._predicted = self._predict(self._trusted, doubtful)
            if replaced is not self._replaced:
                self._replaced = replaced
                self._tolerance = self._step if replaced is self._zero_replaced else \
                    self._step + self._growth * replaced
            self._next = None


__all__ = ["Channel", "SensorGuard"]
