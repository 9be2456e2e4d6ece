"""The device: the entity whose state closes the control loop, and its periodic hooks.

A device pulls its control input at tick ``t``, integrates, and stamps its state at ``t + 1``
(:meth:`Device.increment`). ``before`` hooks run before the control is pulled, ``after``
hooks once the new state is committed; both run in the order they were added.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from dgraph.entity import Entity
from dgraph.errors import HookError
from dgraph.signals.signal import Signal

Hook = Signal | Callable[[int], Any]


class Hooks:
    """An ordered list of hooks: signals to pull or callables ``f(t)``.

    ``hooks.add(h)`` appends, ``hooks.add(h, index=0)`` inserts, ``hooks.remove(h)`` removes.
    A failing hook raises :class:`HookError` naming the hook, its entity and the device.
    """

    def __init__(self, device: Device, phase: str):
        self.device = device
        self.phase = phase
        self._hooks: list[Hook] = []

    def add(self, hook: Hook, index: int | None = None) -> None:
        """Add a hook (at the end, or at ``index``)."""
        if not (isinstance(hook, Signal) or callable(hook)):
            raise HookError(f"{self.device.name}.{self.phase}: a hook must be a signal or a "
                            f"callable f(t), got {hook!r}", entity=self.device.name)
        if index is None:
            self._hooks.append(hook)
        else:
            self._hooks.insert(index, hook)

    def remove(self, hook: Hook) -> None:
        """Remove a hook."""
        self._hooks.remove(hook)

    def __iter__(self) -> Any:
        return iter(list(self._hooks))

    def __len__(self) -> int:
        return len(self._hooks)

    def run(self, t: int) -> None:
        """Call every hook at tick ``t``."""
        for hook in self._hooks:
            try:
                hook(t)
            except Exception as exc:
                name, owner = describe_hook(hook)
                raise HookError(f"{self.phase} hook {name} of device {self.device.name} failed at "
                                f"tick {t}: {type(exc).__name__}: {exc}", entity=owner,
                                signal=hook.name if isinstance(hook, Signal) else None) from exc


def describe_hook(hook: Hook) -> tuple[str, str | None]:
    """A readable name for a hook and the name of the entity it belongs to (if any)."""
    if isinstance(hook, Signal):
        return hook.full_name, hook.entity.name if hook.entity else None
    owner = getattr(hook, "__self__", None)
    name = getattr(hook, "__qualname__", repr(hook))
    if isinstance(owner, Entity):
        return f"{owner.name}.{getattr(hook, '__name__', name)}", owner.name
    return name, None


class Device(Entity):
    """Base class of devices (simulators, hardware interfaces, integrators).

    Subclasses declare their state as :class:`~dgraph.State` outputs and a control input,
    and implement :meth:`prepare_state` (read ``control(t)``, compute and ``state.stage`` the
    next state) and :meth:`commit_state` (``state.commit(t + 1)``, which cannot fail).
    Splitting the two keeps every state consistent when anything fails mid-tick.
    """

    has_state = True

    def __init__(self, name: str, **params: Any):
        self.before = Hooks(self, "before")
        self.after = Hooks(self, "after")
        self._standalone_t = 0
        super().__init__(name, **params)

    @property
    def t(self) -> int:
        """The tick of the device state."""
        return self.graph.t if self.graph is not None else self._standalone_t

    def increment(self) -> None:
        """One tick: before hooks -> control(t) -> integrate -> state at t+1 -> after hooks.

        In a graph this is :meth:`Graph.step` (every stateful entity advances together).
        """
        if self.graph is not None:
            self.graph.step()
            return
        from dgraph.loop import run_after_hooks, transition
        roles = {"devices": [self], "stateful": [self], "observers": [], "commit": [self], "periodic": [],
                 "faults": self.fault_log}
        transition(roles, self._standalone_t)
        self._standalone_t += 1
        run_after_hooks([self], self._standalone_t)
