"""Signals: the time-stamped, lazily cached ports of entities.

Three kinds of signals, all read with ``sig(t)``:

* :class:`Output` -- computed by a method of its entity, cached, recomputed at most once per
  tick and only when something it depends on changed (push-invalidate, pull-evaluate).
* :class:`State` -- an output set by its entity during the tick transition (device state,
  delay memory). It breaks cycles: nothing computed at tick ``t`` flows through it.
* :class:`Input` -- plugged to an output, or holding a constant, or falling back on a default.

A port declared at class level (``u = Input(shape=(3,))``) is a *template*; each entity
instance binds its own copy (see :mod:`dgraph.entity`). The contract is written out in
``docs/design.md``.
"""

from __future__ import annotations

import itertools
import math
import time as _time
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from dgraph.errors import ComputeError, DGraphError, NonFiniteError, PlugError, SpecError, UnpluggedInputError
from dgraph.signals.clock import Clock
from dgraph.signals.spec import DType, ShapeDecl, Spec, exact_float_copy, non_finite, resolve_shape

if TYPE_CHECKING:
    import numpy as np

    from dgraph.entity import Entity

_UNSET = object()
_PLANS = itertools.count(1)
"""Numbers of evaluation plans: a plan marks the outputs it visits with its own number."""
DENSE_FRACTION = 8
"""A read walks its cached order when at least 1 in ``DENSE_FRACTION`` of the outputs in it was
stale at its last read (a walk costs ~0.05 µs per output in the order, a search ~0.5 µs per
stale output found)."""
_STRUCTURE = [0]
"""How many times a plug or an unplug changed the graphs' structure: a cached evaluation order
(:meth:`Output._cached_order`) is valid while this number is the one it was made at."""


def structure_changed() -> None:
    """Forget every cached evaluation order (a plug, an unplug, an entity changing clocks)."""
    _STRUCTURE[0] += 1


class Signal:
    """Common part of inputs and outputs: owner, name, spec and documentation."""

    __slots__ = ("_dtype", "_finite", "_labels", "_minimum", "_shape_decl", "doc", "entity", "name", "spec")

    def __init__(self, shape: ShapeDecl = None, dtype: DType = "float",
                 labels: Sequence[str] | None = None, doc: str = "", finite: bool | None = True,
                 minimum: float | None = None):
        self.entity: Entity | None = None
        self.name = ""
        self._shape_decl = shape
        self._dtype = dtype
        self._labels = labels
        self._finite = finite
        self._minimum = minimum
        self.spec = Spec(shape if isinstance(shape, tuple) and all(
            d is None or isinstance(d, int) for d in shape) else None, dtype, labels, finite, minimum)
        self.doc = doc

    @property
    def full_name(self) -> str:
        """``entity.signal``, the name used by graph files, plots and errors."""
        owner = self.entity.name if self.entity is not None else "<unbound>"
        return f"{owner}.{self.name}"

    def _bind_common(self, other: Signal, entity: Entity, name: str) -> None:
        other.entity = entity
        other.name = name
        other._shape_decl = self._shape_decl
        other._dtype = self._dtype
        other._labels = self._labels
        other._finite = self._finite
        other._minimum = self._minimum
        other.doc = self.doc
        where = f"{entity.name}.{name}"
        try:
            other.spec = Spec(resolve_shape(self._shape_decl, entity), self._dtype, self._labels, self._finite,
                              self._minimum)
        except SpecError as exc:
            raise SpecError(f"{where}: {exc}", entity=entity.name, signal=name) from None

    def _unbound(self) -> DGraphError:
        return DGraphError(f"signal {self.name or '?'} is a class-level declaration; "
                           "read it from an entity instance")

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.full_name} {self.spec!r} t={self.time} value={_short(self.value)}>"

    @property
    def value(self) -> Any:  # overridden
        """The last value, without computing anything."""
        return None

    @property
    def time(self) -> int | None:  # overridden
        """The tick of the last value (``None`` if never computed or set)."""
        return None


class Output(Signal):
    """A computed output: ``out(t)`` returns the value at tick ``t``, recomputing lazily.

    Recomputes when read at ``t`` only if it was never computed or something it depends on
    changed since; never more than once per tick. With ``period=N`` it recomputes at most once
    per window ``[kN, (k+1)N)``, sampled by the device loop at the window start. Counters:
    ``count`` (computations), ``total_duration`` (seconds, exclusive, when profiling).

    Time stamps never move backwards. A read at a tick earlier than the latest tick of its
    clock (by hand: the loop only moves forward) serves a fresh output from its cache, as any
    read; a stale one whose stamp is later than the tick read raises
    :class:`~dgraph.errors.DGraphError` naming it, the tick read and its stamp (something it
    depends on changed since: the graph keeps no history to compute its past value from), and
    nothing is computed. The exception is an output declaring ``"t"`` (time-varying): it is a
    function of the tick, evaluated at the tick read without being cached, so its stamp stays (a
    reference is sampled anywhere on its horizon, as ``MinimumJerk`` is written to answer). The
    check costs one integer comparison on the stale
    path (:meth:`_evaluate`); cached reads are untouched.
    """

    __slots__ = (
        "_clock",
        "_computing",
        "_dense",
        "_down",
        "_fn",
        "_held",
        "_mark",
        "_order",
        "_order_version",
        "_plugged",
        "_stale",
        "_time",
        "_unguarded",
        "_upstream",
        "_value",
        "count",
        "depends",
        "deps",
        "on_demand",
        "period",
        "time_varying",
        "total_duration",
    )

    def __init__(self, fn: Callable[..., Any] | None = None, *, shape: ShapeDecl = None,
                 dtype: DType = "float", depends: Sequence[str] | None = None, period: int = 1,
                 labels: Sequence[str] | None = None, doc: str = "",
                 on_demand: Sequence[str] | bool = (), finite: bool | None = True):
        super().__init__(shape, dtype, labels, doc or (fn.__doc__ or "" if fn else "").strip(), finite)
        if not isinstance(period, int) or period < 1:
            raise SpecError(f"period must be an int >= 1, got {period!r}")
        self._fn = fn
        self.period = period
        self.depends = None if depends is None else tuple(depends)
        self.on_demand: tuple[str, ...] | bool = on_demand if isinstance(on_demand, bool) else tuple(on_demand)
        self.time_varying = self.depends is not None and "t" in self.depends
        self._value: Any = None
        self._time: int | None = None
        self._stale = True
        self._down: list[Output] = []
        self._plugged: list[Input] = []
        self._clock: Clock | None = None
        self._computing = False
        self.deps: list[Signal] = []
        self.count = 0
        self.total_duration = 0.0
        self._held = False
        self._unguarded: Callable[..., Any] | None = None
        self._upstream: list[Output] | None = None
        self._mark = 0
        self._order: list[Output] | None = None
        self._order_version = -1
        self._dense = True  # most of the order was stale at the last read

    def bind(self, entity: Entity, name: str) -> Output:
        """Return this template's copy for ``entity`` (called by :class:`~dgraph.Entity`)."""
        out = type(self).__new__(type(self))
        Output.__init__(out, None, depends=self.depends, period=self.period, on_demand=self.on_demand)
        self._bind_common(out, entity, name)
        if self._fn is not None:
            out._fn = self._fn.__get__(entity)
        out._clock = entity._clock
        return out

    # -- reading ----------------------------------------------------------------------------
    def __call__(self, t: int) -> Any:
        """The value at tick ``t``, recomputed only if stale."""
        clock = self._clock
        if t != clock.t:
            clock.advance(t)
        if self._stale:
            return self._evaluate(t)
        return self._value

    def _evaluate(self, t: int, force: bool = False) -> Any:
        """Bring this stale output up to date at ``t``: first every stale output it needs, in
        dependency order, so that its method finds its inputs fresh and the Python stack stays
        flat whatever the graph's depth; then itself. When most of its upstream is stale (a
        control graph at each tick), it walks the order cached from the graph's structure
        (:meth:`_cached_order`); when few of them are (a large graph of constants), or the
        upstream has periodic outputs or outputs on another clock, it searches for the stale ones
        (:meth:`_stale_upstream`, whose cost is the number found). A periodic output already
        sampled in this window holds, unless ``force``. A read at a tick earlier than the
        clock's latest is checked by :meth:`_evaluate_past`."""
        if self.period > 1 and not force and self._holds(t):
            return self._hold()
        clock = self._clock
        if t < clock.latest:  # a past read, by hand: the only one that could move a stamp back
            return self._evaluate_past(t)
        if clock.cache_enabled:  # with the cache off every read recomputes: nothing to prepare
            order = self._order if self._order_version == _STRUCTURE[0] else self._cached_order()
            if order is not None and self._dense:
                computed = 0
                for node in order:
                    if node._stale:  # fresh: so is everything it reads
                        node._compute(t)
                        computed += 1
                self._dense = computed * DENSE_FRACTION >= len(order)
            else:
                upstream = self._upstream if self._upstream is not None else self._upstream_outputs()
                for up in upstream:
                    if up._stale:  # something to prepare (the common case, fresh inputs, skips the search)
                        found = self._stale_upstream(t)
                        for node in found:
                            if node._stale:  # an on-demand read in an earlier method may have computed it
                                node._compute(t)
                        self._dense = order is not None and len(found) * DENSE_FRACTION >= len(order)
                        break
        return self._compute(t)

    def _evaluate_past(self, t: int) -> Any:
        """A read at a tick earlier than the clock's latest: the stale outputs it needs (searched,
        :meth:`_stale_upstream`) and itself are computed at ``t`` unless one of them that is not
        time-varying is stamped later than ``t``: then it raises, naming that one, before
        computing anything. A time-varying output stamped later is evaluated at ``t`` when it
        is read and handed out without being cached (:meth:`_compute_uncached`): its stamp
        stays. Outputs read on demand or on another clock check themselves. With the cache off
        every read recomputes (a debugging aid): nothing tells what changed, so nothing is
        checked."""
        if not self._clock.cache_enabled:
            return self._compute(t)
        needed = self._stale_upstream(t)
        for node in (*needed, self):
            if _stamped_after(node, t) and not node.time_varying:
                raise _past_tick_error(node, t, node._time)
        for node in needed:  # stamped at or before t (or never): computing at t moves no stamp back
            if node._stale and not _stamped_after(node, t):  # an earlier on-demand read may have computed it
                node._compute(t)
        return self._compute_uncached(t) if _stamped_after(self, t) else self._compute(t)

    def _compute_uncached(self, t: int) -> Any:
        """The value at ``t`` of a time-varying output stamped later: computed and returned, with
        the cached value and its stamp left as they were (and the output stale, as the clock's
        move back to ``t`` made it)."""
        value, stamp = self._value, self._time
        try:
            return self._compute(t)
        finally:
            self._value, self._time, self._stale = value, stamp, True

    def _cached_order(self) -> list[Output] | None:
        """Every output this one reads ahead of its method, directly or not, each after what it
        reads (:meth:`_post_order` over all of them), kept until a plug or an unplug; None if
        one of them is periodic or on another clock (their holds and clocks decide at each read
        what is needed). Computing the stale ones in this order computes what the search of
        :meth:`_stale_upstream` finds: a fresh output's upstream is fresh (invalidation reaches
        everything downstream), so a stale output in the order is needed."""
        clock = self._clock
        order: list[Output] | None = self._post_order(lambda up: True)
        if any(node.period > 1 or node._clock is not clock for node in order):
            order = None
        self._order, self._order_version = order, _STRUCTURE[0]
        return order

    def _holds(self, t: int) -> bool:
        """A periodic output whose value was sampled in the window of ``t`` (it serves its hold)."""
        return self._time is not None and t - t % self.period <= self._time <= t

    def _stale_upstream(self, t: int) -> list[Output]:
        """The stale outputs this one reads, directly or not, in dependency order (each after
        everything it reads): :meth:`_post_order` stopping at fresh outputs, at States, at
        periodic outputs that hold, and at on-demand dependencies. Its cost is the number of
        stale outputs found, not the size of the graph. An output on another clock (an entity
        outside this graph, plugged by hand) is left to its reader: read through the input, it
        moves its own clock to ``t`` first."""
        clock = self._clock
        return self._post_order(lambda up: up._stale and up._clock is clock and not (up.period > 1 and up._holds(t)))

    def _post_order(self, follow: Callable[[Output], bool]) -> list[Output]:
        """The outputs upstream of this one (through :meth:`_upstream_outputs`) that ``follow``
        admits, each after those it reads: an iterative depth-first search (no recursion, any
        depth), each output visited once; this output itself is not in the list."""
        mark = self._mark = next(_PLANS)
        order: list[Output] = []
        stack = [(self, iter(self._upstream_outputs()))]
        while stack:
            node, pending = stack[-1]
            for up in pending:
                if up._mark != mark and follow(up):
                    up._mark = mark
                    stack.append((up, iter(up._upstream_outputs())))
                    break
            else:
                stack.pop()
                order.append(node)
        order.pop()  # this output itself, computed by the caller
        return order

    def _upstream_outputs(self) -> list[Output]:
        """The computed outputs this one reads ahead of its method: the sources of its declared
        inputs and its entity's declared outputs, without States and on-demand dependencies.
        Rebuilt after a plug or an unplug of one of its inputs."""
        upstream = self._upstream
        if upstream is None:
            on_demand = self.on_demand
            upstream = []
            if on_demand is not True:
                for dep in self.deps:
                    source = dep._source if isinstance(dep, Input) else dep
                    if source is not None and not isinstance(source, State) and dep.name not in on_demand:
                        upstream.append(source)
            self._upstream = upstream
        return upstream

    def _compute(self, t: int) -> Any:
        """Run the method at ``t`` and cache its value (its inputs are normally fresh by now)."""
        if self._computing:
            raise ComputeError(f"{self.full_name} was read during its own computation at tick {t} "
                               "(an undeclared algebraic loop)", entity=self.entity.name, signal=self.name)
        clock = self._clock
        self._computing = True
        profiling = clock.profiling
        if profiling:  # exclusive time: what upstream computations took is not counted here
            outer_inner, clock.inner = clock.inner, 0.0
            start = _time.perf_counter()
        try:
            value = self._fn(t)
        except DGraphError:
            raise
        except Exception as exc:
            raise ComputeError(f"{self.full_name} failed at tick {t}: {type(exc).__name__}: {exc}",
                               entity=self.entity.name, signal=self.name) from exc
        finally:
            self._computing = False
            if profiling:
                elapsed = _time.perf_counter() - start
                self.total_duration += elapsed - clock.inner
                clock.inner = outer_inner + elapsed
        if clock.check_values:
            problem = self.spec.problem(value)
            if problem is not None:
                raise SpecError(f"{self.full_name} at tick {t}: {problem}", entity=self.entity.name,
                                signal=self.name)
        self._value = value
        self._time = t
        self._stale = not clock.cache_enabled
        self.count += 1
        return value

    def _hold(self) -> Any:
        """Serve the cached value of a periodic output until its period has elapsed."""
        if not self._held:
            self._held = True
            self._clock.held.append(self)
        return self._value

    def release_hold(self) -> None:
        """End of a periodic hold: everything that read the held value becomes stale."""
        self._held = False
        self._stale = True
        _invalidate_all(self._down)

    def next_sample(self) -> int:
        """First tick of the period window after the last sample (periodic outputs)."""
        return (self._time // self.period + 1) * self.period if self._time is not None else 0

    def sample(self, t: int) -> None:
        """Loop-driven sampling of a periodic output at the start of a window (``t % period == 0``).

        The loop's sample is authoritative: a stale output recomputes now, even if something
        computed it earlier in this tick (a hook, a failed tick being retried) and a later
        change was held; readers of the held value are invalidated. A value still valid is
        stamped ``t`` by the clock. So the window's value never depends on who read it first.
        """
        clock = self._clock
        if t != clock.t:
            clock.advance(t)
        if not self._stale:
            return
        held = self._held
        if held:
            self._held = False
            clock.held = [o for o in clock.held if o is not self]
        self._evaluate(t, force=True)
        if held:
            _invalidate_all(self._down)

    # -- staleness --------------------------------------------------------------------------
    def invalidate(self) -> None:
        """Mark this output and everything downstream of it stale (stops at stale nodes)."""
        if not self._stale:
            _invalidate_all([self])

    def _defer(self) -> bool:
        """A periodic output invalidated within its period holds its value: the change reaches
        downstream only when the period has elapsed (:meth:`release_hold`). True if deferred."""
        if self._time is None:
            return False
        clock = self._clock
        if clock.t is not None and clock.t >= self.next_sample():
            return False
        if not self._held:
            self._held = True
            clock.held.append(self)
        return True

    @property
    def stale(self) -> bool:
        """True if the next read will recompute (or serve a periodic hold)."""
        return self._stale

    @property
    def value(self) -> Any:
        """The last computed value (``None`` if never computed); computes nothing."""
        return self._value

    @property
    def time(self) -> int | None:
        """The tick of the last computation."""
        return self._time

    @property
    def plugged_inputs(self) -> list[Input]:
        """The inputs this output feeds."""
        return list(self._plugged)


def _stamped_after(output: Output, t: int) -> bool:
    """True if ``output`` holds a value stamped later than tick ``t``."""
    return output._time is not None and output._time > t


def _past_tick_error(output: Output, t: int, stamp: int) -> DGraphError:
    """The error of a stale ``output`` stamped ``stamp`` read at the earlier tick ``t``."""
    return DGraphError(f"{output.full_name} was read at tick {t}, but it is stamped {stamp} and something "
                       f"it depends on changed since: time stamps never move backwards (the graph keeps no "
                       f"history to compute tick {t} from)", entity=output.entity.name if output.entity else None,
                       signal=output.name)


def _invalidate_all(nodes: list[Output]) -> None:
    """Mark ``nodes`` and their downstream stale, depth first without recursion (long chains
    are fine), stopping at nodes already stale and at periodic outputs that hold."""
    stack = list(nodes)
    pop, extend = stack.pop, stack.extend
    while stack:
        node = pop()
        if not node._stale:
            node._stale = True
            if node.period > 1 and node._defer():
                continue
            if node._down:
                extend(node._down)


class State(Output):
    """An output whose value the entity sets during the tick transition.

    Device state and delay memory are States. An entity stages the next value in
    ``prepare_state`` (``state.stage(value)``: checked there, so a bad value fails before
    anything is committed) and publishes it in ``commit_state`` (``state.commit(t + 1)``);
    ``state.set(value, t)`` does both at once (initial values). Reading never computes;
    publishing invalidates everything downstream. Nothing computed at a tick flows into a
    State, so a loop closed through a State is legal.
    """

    __slots__ = ("_staged", "initial")

    def __init__(self, *, shape: ShapeDecl = None, dtype: DType = "float", initial: Any = None,
                 labels: Sequence[str] | None = None, doc: str = "", finite: bool | None = True):
        super().__init__(None, shape=shape, dtype=dtype, depends=(), labels=labels, doc=doc, finite=finite)
        self.initial = initial
        self._staged: Any = _UNSET

    def bind(self, entity: Entity, name: str) -> State:
        """Return this template's copy for ``entity``."""
        out = State.__new__(State)
        State.__init__(out, initial=self.initial)
        self._bind_common(out, entity, name)
        out._clock = entity._clock
        out._stale = False
        return out

    def __call__(self, t: int) -> Any:
        """The current state (set by the entity, stamped with the tick it belongs to)."""
        clock = self._clock
        if t != clock.t:
            clock.advance(t)
        if self._time is None:
            raise UnpluggedInputError(f"state {self.full_name} was read before it was initialised",
                                      entity=self.entity.name, signal=self.name)
        return self._value

    def stage(self, value: Any, copy: bool = True, nan_checked: bool = False) -> None:
        """Check and hold ``value`` as the next state (raises :class:`SpecError` here, not at commit).

        ``copy=False`` keeps a float array of the declared shape as it is (still checked for
        NaN and inf): for a caller that hands over an array of its own that it never writes again,
        such as the result of a gather (a device's sensors), it saves a copy per state per tick.
        ``nan_checked``: the caller found no NaN (nor inf) in ``value`` (:func:`stage_views`). A
        state of ``finite=None`` (a raw reading) is staged NaN and all.
        """
        spec = self.spec
        checked = nan_checked or spec.finite is None
        array = exact_float_copy(spec, value, copy, checked, bool(spec.finite))  # the common case first
        if array is None:
            array = _coerce(self, value, copy)
            if spec.finite and spec.dtype == "float" and _infinite(array):
                raise NonFiniteError(f"{self.full_name}: staged value contains inf: {_short(array)}",
                                entity=self.entity.name if self.entity else None, signal=self.name)
        self._staged = array

    def commit(self, t: int) -> None:
        """Publish the staged value as the state at tick ``t``; invalidate everything downstream."""
        _invalidate_all(self.publish(t))

    def publish(self, t: int) -> list[Output]:
        """Make the staged value the state at tick ``t`` and return the outputs to invalidate
        (:func:`commit_all` invalidates the readers of several states in one walk)."""
        if self._staged is _UNSET:
            raise DGraphError(f"{self.full_name}: commit at tick {t} without a staged value",
                              entity=self.entity.name, signal=self.name)
        self._value, self._staged = self._staged, _UNSET
        self._time = t
        return self._down

    def set(self, value: Any, t: int) -> None:
        """Stage and commit at once: the state at tick ``t`` is ``value``."""
        self.stage(value)
        self.commit(t)

    def invalidate(self) -> None:
        """A state never becomes stale: it changes only when its entity sets it."""


def stage_views(groups: Sequence[tuple[np.ndarray, Sequence[tuple[State, slice | None]]]]) -> None:
    """For each ``(block, parts)`` of ``groups``: ``state.stage(block[index], copy=False)`` for
    each ``(state, index)`` of ``parts`` (``index`` None: the whole block), with one NaN check
    per block instead of one per state (a device stages a dozen views of a few gathers at
    every tick). A block with a NaN has its views checked one by one, so the error names the
    first state with a NaN, as :meth:`State.stage` would. The views are kept as they are, like
    ``copy=False``: the blocks must be arrays nobody writes again."""
    for block, parts in groups:
        checked = not non_finite(block)
        for state, index in parts:
            state.stage(block if index is None else block[index], False, checked)


def commit_all(states: Sequence[State], t: int) -> None:
    """Commit every state of ``states`` at tick ``t``, then invalidate all their readers in one
    walk (the same result as committing them one by one; a device commits its sensors so)."""
    for state in states:  # nothing is published unless everything can be
        if state._staged is _UNSET:
            state.publish(t)  # raises, naming it
    readers: list[Output] = []
    for state in states:
        readers += state.publish(t)
    _invalidate_all(readers)


class Input(Signal):
    """An input port: plugged to an output, or holding a constant, or using its default.

    ``inp(t)`` forwards to the plugged output; ``inp.set(v)`` stores a constant (unplugging
    first); ``default`` is used when neither. Reading an input with none of them raises
    :class:`~dgraph.errors.UnpluggedInputError` naming ``entity.signal``. ``minimum`` bounds the
    constants (and the default) from below, element by element (:class:`~dgraph.signals.spec.Spec`):
    a value below it is refused when it is set; what arrives through a plug is its reader's to check.
    The entity's :meth:`~dgraph.Entity.constant_problem` refuses what depends on more than the spec.
    """

    __slots__ = ("_has_value", "_set_time", "_source", "_subs", "_value", "default", "is_set")

    def __init__(self, shape: ShapeDecl = None, dtype: DType = "float", default: Any = _UNSET,
                 labels: Sequence[str] | None = None, doc: str = "", finite: bool | None = True,
                 minimum: float | None = None):
        super().__init__(shape, dtype, labels, doc, finite, minimum)
        self.default = default
        self._source: Output | None = None
        self._value: Any = None
        self._has_value = False
        self._set_time: int | None = None
        self.is_set = False
        self._subs: list[Output] = []

    @property
    def has_default(self) -> bool:
        """True if a default value was declared."""
        return self.default is not _UNSET

    def bind(self, entity: Entity, name: str) -> Input:
        """Return this template's copy for ``entity`` (with its default coerced)."""
        inp = Input.__new__(Input)
        Input.__init__(inp, default=self.default)
        self._bind_common(inp, entity, name)
        if inp.has_default:
            inp._value = _coerce(inp, self.default)
            inp._has_value = True
            inp.default = inp._value
        return inp

    def __call__(self, t: int) -> Any:
        """The value at tick ``t``."""
        source = self._source
        if source is not None:
            if not source._stale and source._clock.t == t and source._time is not None:
                return source._value  # what ``source(t)`` returns when it is up to date, one call less
            return source(t)
        if self._has_value:
            return self._value
        if self.entity is None:
            raise self._unbound()
        raise UnpluggedInputError(f"input {self.full_name} is read at tick {t} but is neither "
                                  "plugged nor set and has no default", entity=self.entity.name,
                                  signal=self.name)

    # -- constants ------------------------------------------------------------------------
    def set(self, value: Any) -> None:
        """Hold the constant ``value`` (unplugs first). Dependents recompute once."""
        if self.entity is None:
            raise self._unbound()
        coerced = _coerce(self, value)
        problem = self.entity.constant_problem(self.name, coerced)
        if problem is not None:
            raise SpecError(f"{self.full_name}: {problem}", entity=self.entity.name, signal=self.name)
        if self._source is not None:
            self.unplug()
        self._value = coerced
        self._has_value = True
        self.is_set = True
        graph = self.entity.graph
        self._set_time = graph.t if graph is not None else self.entity._clock.t
        _invalidate_all(self._subs)

    def reset(self) -> None:
        """Forget a constant set with :meth:`set` and fall back to the default (if any)."""
        if self.is_set:
            self.is_set = False
            self._fall_back()
            _invalidate_all(self._subs)

    def _fall_back(self) -> None:
        """Hold the default, if one was declared, else nothing."""
        self._has_value = self.has_default
        self._value = self.default if self.has_default else None

    # -- plugging ---------------------------------------------------------------------------
    def plug(self, source: Output) -> None:
        """Plug ``source`` into this input (shape/dtype checked; no graph-level checks).

        Prefer :func:`dgraph.plug` or :meth:`Graph.plug`, which also refuse cycles.
        """
        if not isinstance(source, Output):
            raise PlugError(f"cannot plug {source!r} into {self.full_name}: not an output")
        if not self.spec.accepts(source.spec):
            why = "a different type" if self.spec.structured or source.spec.structured else "shape or dtype mismatch"
            raise PlugError(f"cannot plug {source.full_name} {source.spec!r} into {self.full_name} "
                            f"{self.spec!r}: {why}", entity=self.entity.name, signal=self.name)
        if self._source is not None:
            self.unplug()
        self.is_set = False
        self._source = source
        source._plugged.append(self)
        source._down.extend(self._subs)
        self._forget_upstream()
        _invalidate_all(self._subs)

    def unplug(self) -> None:
        """Disconnect from the plugged output; the input keeps no value unless set or default."""
        source = self._source
        if source is None:
            return
        source._plugged.remove(self)
        for sub in self._subs:
            source._down.remove(sub)
        self._source = None
        self._forget_upstream()
        if not self.is_set:
            self._fall_back()
        _invalidate_all(self._subs)

    def _forget_upstream(self) -> None:
        """The outputs reading this input list their upstream again at their next evaluation."""
        for sub in self._subs:
            sub._upstream = None
        structure_changed()

    @property
    def source(self) -> Output | None:
        """The plugged output, or ``None``."""
        return self._source

    @property
    def value(self) -> Any:
        """The constant, or the plugged output's last value; computes nothing."""
        return self._source.value if self._source is not None else self._value

    @property
    def time(self) -> int | None:
        """The stamp of the plugged output's last value, or the tick at which the constant was set."""
        return self._source.time if self._source is not None else self._set_time


def _coerce(sig: Signal, value: Any, copy: bool = True) -> Any:
    """``sig.spec.coerce`` with the error attributed to the signal's entity and name (a float
    array of exactly the declared shape, or a float for a float scalar, takes the fast path,
    without building the name)."""
    spec = sig.spec
    if spec.minimum is None:  # a bound takes the general path, which checks it
        if type(value) is float and spec.dtype == "float" and spec.shape == () and value == value:
            return value
        array = exact_float_copy(spec, value, copy)
        if array is not None:
            return array
    try:
        return sig.spec.coerce(value, sig.full_name)
    except SpecError as exc:
        raise SpecError(str(exc), entity=sig.entity.name if sig.entity else None, signal=sig.name) from None


def _infinite(value: Any) -> bool:
    """True if a coerced float value (a float or a float array) holds an infinity (NaN is
    refused before)."""
    if isinstance(value, float):
        return math.isinf(value)
    return isinstance(value, np.ndarray) and value.dtype.kind == "f" and non_finite(value)


def _short(value: Any) -> str:
    text = repr(value).replace("\n", "")
    return text if len(text) <= 50 else text[:47] + "..."


def output(shape: ShapeDecl = None, dtype: DType = "float", depends: Sequence[str] | None = None,
           period: int = 1, labels: Sequence[str] | None = None, doc: str = "",
           on_demand: Sequence[str] | bool = (), finite: bool | None = True) -> Callable[[Callable[..., Any]], Output]:
    """Decorator declaring a computed output from a method ``def name(self, t)``.

    ``depends`` lists the names of the entity's inputs, states and other outputs that the
    method reads, plus ``"t"`` if the value depends on time itself. Without it, the output
    depends on every input and state of the entity (conservative).

    Before the method runs, every stale output it depends on is brought up to date, in
    dependency order. ``on_demand`` names the dependencies the method reads only on some ticks
    (``True``: all of them), such as the unselected inputs of a switch: they still invalidate
    the output, but are computed only if the method reads them.
    ``finite=False``: the value may hold infinities (value checks refuse only NaN then);
    ``finite=None``: a raw value, never checked (its readers check it).
    """

    def wrap(fn: Callable[..., Any]) -> Output:
        return Output(fn, shape=shape, dtype=dtype, depends=depends, period=period, labels=labels, doc=doc,
                      on_demand=on_demand, finite=finite)

    return wrap
