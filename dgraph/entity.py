"""Entities: named nodes of a control graph owning input, output and state signals.

An entity class declares its ports and parameters as class attributes::

    @dg.register
    class Gain(dg.Entity):
        size = dg.Param(3, kind="int")
        u = dg.Input(shape=("size",))
        k = dg.Input(shape=(), default=1.0)

        @dg.output(shape=("size",), depends=("u", "k"))
        def y(self, t):
            return self.k(t) * self.u(t)

and is created as ``Gain("name", size=3)`` (the name first, as in dynamic-graph). Each
instance binds its own copies of the declared ports; shapes may refer to parameters.
"""

from __future__ import annotations

import inspect
import re
from collections.abc import Callable
from typing import Any, ClassVar, TypeVar

from dgraph.errors import DGraphError, ParamError
from dgraph.faults import FaultLog
from dgraph.params import REQUIRED, Param
from dgraph.signals.clock import Clock
from dgraph.signals.signal import Input, Output, Signal, State, structure_changed

F = TypeVar("F", bound=Callable[..., Any])
NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_\-]*$")


def command(fn: F) -> F:
    """Mark an entity method as a command: a runtime operation listed with its docstring."""
    fn._dg_command = True  # type: ignore[attr-defined]
    return fn


_ANNOTATIONS: dict[str, Any] = {
    "float": float, "int": int, "bool": bool, "str": str, "path": str, "name_or_path": str | Any,
    "vector": "Sequence[float]", "str_list": list[str], "path_list": list[str], "int_list": list[int], "object": Any,
}
"""The type shown in an entity's signature for each parameter kind."""


def _generic_init(cls: type) -> bool:
    """True if ``cls`` is built by ``Entity.__init__(name, **params)`` (no constructor of its own
    with other arguments)."""
    init = cls.__init__
    parameters = list(inspect.signature(init).parameters.values())[1:]  # without self
    return [(p.name, p.kind) for p in parameters] == [("name", inspect.Parameter.POSITIONAL_OR_KEYWORD),
                                                      ("params", inspect.Parameter.VAR_KEYWORD)]


def _signature(params: dict[str, Param]) -> inspect.Signature:
    """``(name, *, param=default, ...)``: the name, then every parameter as a keyword argument
    with its type and default (a required one has none)."""
    parameters = [inspect.Parameter("name", inspect.Parameter.POSITIONAL_OR_KEYWORD, annotation=str)]
    for pname, decl in params.items():
        default = inspect.Parameter.empty if decl.default is REQUIRED else decl.default
        parameters.append(inspect.Parameter(pname, inspect.Parameter.KEYWORD_ONLY, default=default,
                                            annotation=_ANNOTATIONS.get(decl.kind, Any)))
    return inspect.Signature(parameters)


class Entity:
    """Base class of all entities.

    Subclasses declare :class:`~dgraph.Input`, :func:`~dgraph.output`, :class:`~dgraph.State`
    and :class:`~dgraph.Param` class attributes, and may override:

    * :meth:`configure` -- derive attributes from parameters before ports are built (sizes),
      and add per-instance ports with :meth:`declare`;
    * :meth:`setup` -- one-time work once the ports exist;
    * :meth:`reset` -- put states to their initial values (called at construction);
    * :meth:`prepare_state` / :meth:`commit_state` -- for entities with ``has_state = True``,
      the two phases of the tick transition driven by the device loop;
    * :meth:`observe` -- for entities with ``observes = True`` (recorders), called every tick
      after the control is computed and before states are committed; what it reads is kept
      in :meth:`commit_state`, so a failed tick leaves nothing behind;
    * :meth:`check` -- extra problems reported by :meth:`Graph.validate`;
    * :meth:`constant_problem` -- what is wrong with a constant about to be set on an input,
      beyond its spec (a length that depends on what is plugged), refused where it is set.
    """

    type_name: ClassVar[str] = "Entity"
    has_state: ClassVar[bool] = False
    observes: ClassVar[bool] = False
    _port_templates: ClassVar[dict[str, Signal]] = {}
    _param_decls: ClassVar[dict[str, Param]] = {}
    _command_names: ClassVar[tuple[str, ...]] = ()

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        cls.type_name = cls.__name__
        ports: dict[str, Signal] = {}
        params: dict[str, Param] = {}
        commands: list[str] = []
        for klass in reversed(cls.__mro__):
            for attr, value in vars(klass).items():
                if isinstance(value, Signal):
                    ports[attr] = value
                elif isinstance(value, Param):
                    value.name = attr
                    params[attr] = value
                elif callable(value) and getattr(value, "_dg_command", False) and attr not in commands:
                    commands.append(attr)
        for attr in [*ports, *params]:
            if attr in _RESERVED:
                raise DGraphError(f"{cls.__name__}: {attr!r} is an Entity attribute and cannot name a "
                                  "port or parameter")
        for pname in params:
            # a parameter may share its name with a base-class property (``dt``): the property
            # reads the parameter, so the declaration must not shadow it on the class
            if pname in vars(cls) and any(isinstance(vars(b).get(pname), property) for b in cls.__mro__[1:]):
                delattr(cls, pname)
        cls._port_templates = ports
        cls._param_decls = params
        cls._command_names = tuple(commands)
        # what inspect.signature, help() and notebooks show: the parameters (None: a constructor of
        # its own, whose signature inspect reads; not one inherited from a base class)
        cls.__signature__ = _signature(params) if _generic_init(cls) else None

    def __init__(self, name: str, **params: Any):
        if not isinstance(name, str) or not NAME_RE.match(name):
            raise ParamError(f"invalid entity name {name!r}: use letters, digits, '_' or '-', "
                             "starting with a letter", entity=str(name))
        self.name = name
        self.graph: Any = None
        self._clock = Clock()
        self._set_params(params)
        self._extra_templates: dict[str, Signal] = {}
        self.configure()
        self._signals: dict[str, Signal] = {}
        for port_name, template in {**self._port_templates, **self._extra_templates}.items():
            signal = template.bind(self, port_name)
            self._signals[port_name] = signal
            setattr(self, port_name, signal)
        self._wire_dependencies()
        self.setup()
        self.reset()

    # -- construction -----------------------------------------------------------------------
    def _set_params(self, given: dict[str, Any]) -> None:
        unknown = set(given) - set(self._param_decls)
        if unknown:
            known = ", ".join(self._param_decls) or "none"
            raise ParamError(f"{self.name} ({self.type_name}): unknown parameter(s) "
                             f"{', '.join(sorted(unknown))}; known: {known}", entity=self.name)
        self.params: dict[str, Any] = {}
        self.given_params: dict[str, Any] = {}
        for pname, decl in self._param_decls.items():
            if pname in given:
                value = decl.convert(given[pname], self.name)
                self.given_params[pname] = value
            elif decl.required:
                raise ParamError(f"{self.name} ({self.type_name}): missing required parameter "
                                 f"{pname!r}", entity=self.name)
            else:
                value = decl.default if decl.default is not REQUIRED else None
                if value is not None:
                    value = decl.convert(value, self.name)
            self.params[pname] = value
            if not isinstance(getattr(type(self), pname, None), property):
                setattr(self, pname, value)

    def configure(self) -> None:
        """Derive attributes from parameters before the ports are built (override)."""

    def setup(self) -> None:
        """Called once the ports exist, before :meth:`reset` (override)."""

    def declare(self, name: str, template: Signal) -> None:
        """Add a per-instance port (call from :meth:`configure`), e.g. variadic inputs."""
        if name in self._port_templates or name in self._extra_templates or hasattr(type(self), name):
            raise DGraphError(f"{self.name}: port {name!r} already exists", entity=self.name)
        self._extra_templates[name] = template

    def _wire_dependencies(self) -> None:
        inputs = [s for s in self._signals.values() if isinstance(s, Input)]
        states = [s for s in self._signals.values() if isinstance(s, State)]
        for out in self._signals.values():
            if not isinstance(out, Output) or isinstance(out, State):
                continue
            if out.depends is None:
                deps: list[Signal] = [*inputs, *states]
            else:
                deps = []
                for dep in out.depends:
                    if dep == "t":
                        continue
                    if dep not in self._signals or dep == out.name:
                        raise DGraphError(f"{self.name}.{out.name} declares a dependency on "
                                          f"{dep!r}, which is not a signal of {self.type_name}",
                                          entity=self.name, signal=out.name)
                    deps.append(self._signals[dep])
            if out.on_demand is not True:
                for name in out.on_demand:
                    if name not in self._signals or (out.depends is not None and name not in out.depends):
                        raise DGraphError(f"{self.name}.{out.name} declares {name!r} on demand, which is not one of "
                                          f"its dependencies", entity=self.name, signal=out.name)
            out.deps = deps
            for dep in deps:
                (dep._subs if isinstance(dep, Input) else dep._down).append(out)
            self._clock.register(out)

    def reset(self) -> None:
        """Set the states to their initial values (override; called at construction)."""
        for sig in self._signals.values():
            if isinstance(sig, State) and sig.initial is not None:
                sig.set(sig.initial, 0)

    def _attach_clock(self, clock: Clock) -> None:
        """Move to ``clock`` (joining or leaving a graph): a new time base, so every computed
        output is recomputed on its next read; a periodic hold moves with its output."""
        for sig in self._signals.values():
            if isinstance(sig, Output):
                sig._clock = clock
                if not isinstance(sig, State):
                    sig._stale = True
                clock.register(sig)
        self._clock = clock
        structure_changed()  # the cached evaluation orders through it are out of date

    # -- tick transition (stateful entities) --------------------------------------------------
    def prepare_state(self, t: int) -> None:
        """Compute the next state from the values at tick ``t``; publish nothing yet."""

    def commit_state(self, t_next: int) -> None:
        """Publish the prepared state, stamped ``t_next``."""

    def observe(self, t: int) -> None:
        """Called every tick for entities with ``observes = True``."""

    def constant_problem(self, name: str, value: Any) -> str | None:
        """What is wrong with ``value`` (coerced to its spec) as the constant of input ``name``,
        or None (override). ``inp.set`` refuses it with a :class:`SpecError` naming the input."""
        return None

    def check(self) -> list[str]:
        """Problems :meth:`Graph.validate` should report for this entity (override)."""
        return []

    # -- faults -------------------------------------------------------------------------------
    @property
    def fault_log(self) -> FaultLog:
        """Where this entity's faults go: its graph's log (an entity outside a graph has its own)."""
        if self.graph is not None:
            return self.graph.fault_log
        own = self.__dict__.get("_own_fault_log")
        if own is None:
            own = self.__dict__["_own_fault_log"] = FaultLog()
        return own

    def report_fault(self, t: int, signal: str, cause: str, action: str, detail: str = "") -> None:
        """Report that tick ``t`` is degraded: ``signal`` (a name of this entity's, or a full
        ``entity.signal`` name) had ``cause``, and ``action`` was taken instead of failing
        (see :mod:`dgraph.faults`)."""
        name = signal if "." in signal.split("[")[0] else f"{self.name}.{signal}"
        self.fault_log.report(t, name, cause, action, detail)

    # -- introspection ------------------------------------------------------------------------
    @property
    def dt(self) -> float:
        """The control period in seconds: the entity's ``dt`` parameter, else its graph's."""
        own = self.params.get("dt")
        if own is not None:
            return own
        if self.graph is not None:
            return self.graph.dt
        raise DGraphError(f"{self.name}: no dt (give the parameter dt or add it to a graph)",
                          entity=self.name)

    @property
    def ports(self) -> dict[str, Signal]:
        """All signals (inputs, outputs, states) by name."""
        return dict(self._signals)

    @property
    def inputs(self) -> dict[str, Input]:
        """Input ports by name."""
        return {n: s for n, s in self._signals.items() if isinstance(s, Input)}

    @property
    def outputs(self) -> dict[str, Output]:
        """Output ports (computed and states) by name."""
        return {n: s for n, s in self._signals.items() if isinstance(s, Output)}

    @property
    def commands(self) -> dict[str, str]:
        """Command names and their docstrings."""
        return {n: (getattr(type(self), n).__doc__ or "").strip() for n in self._command_names}

    def signal(self, name: str) -> Signal:
        """The port called ``name`` (raises naming the entity and the known ports)."""
        try:
            return self._signals[name]
        except KeyError:
            raise DGraphError(f"{self.name} ({self.type_name}) has no signal {name!r}; it has: "
                              f"{', '.join(self._signals)}", entity=self.name, signal=name) from None

    @classmethod
    def describe(cls) -> str:
        """Docstring, parameters, ports and commands of this type, for ``dgraph entities``."""
        lines = [f"{cls.type_name}: {(cls.__doc__ or '').strip().splitlines()[0] if cls.__doc__ else ''}"]
        for param in cls._param_decls.values():
            lines.append(f"  param   {param.describe()}")
        for name, port in cls._port_templates.items():
            kind = {Input: "input", State: "state"}.get(type(port), "output")
            doc = f"  -- {port.doc.splitlines()[0]}" if port.doc else ""
            shape = "" if port.spec.structured else _shape_text(port._shape_decl)  # a structure has none
            lines.append(f"  {kind:<7} {name} {port.spec.type_name}{shape}{doc}")
        for name in cls._command_names:
            doc = (getattr(cls, name).__doc__ or "").strip().splitlines()
            lines.append(f"  command {name}()" + (f"  -- {doc[0]}" if doc else ""))
        return "\n".join(lines)

    def __repr__(self) -> str:
        lines = [f"{self.type_name}({self.name!r})"]
        for name, sig in self._signals.items():
            kind = {Input: "in ", State: "st "}.get(type(sig), "out")
            origin = ""
            if isinstance(sig, Input):
                origin = f" <- {sig.source.full_name}" if sig.source is not None else (" (set)" if sig.is_set else "")
            value = repr(sig.value).replace("\n", "")
            if len(value) > 60:
                value = value[:57] + "..."
            lines.append(f"  {kind} {name:<16} t={sig.time!s:<6} {value}{origin}")
        return "\n".join(lines)


def _shape_text(shape: Any) -> str:
    if shape is None:
        return "(any)"
    if callable(shape):
        return "(sized by parameters)"
    return str(tuple(shape) if not isinstance(shape, str) else (shape,))


_RESERVED = {n for n in dir(Entity) if not n.startswith("_")} - {"dt"}
