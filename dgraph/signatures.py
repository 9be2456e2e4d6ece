"""Entity constructors for type checkers and IDEs, written into the entity classes.

At run time every entity is built by ``Entity.__init__(name, **params)``, and
``inspect.signature(Gain)`` shows the parameters (:mod:`dgraph.entity`). Type checkers and IDEs
(mypy, pyright/Pylance, PyCharm, jedi) read the source only, so each entity class also carries the
constructor its parameters make, for them alone::

    @dg.register
    class Gain(dg.Entity):
        size = dg.Param(None, kind="int", doc="vector size (None: scalar)")
        ...
        if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
            def __init__(self, name: str, *, size: int | None = None) -> None: ...

``python -m dgraph.signatures`` writes (or rewrites) that block in every registered entity class
of dgraph and dgraph_sim, after the class's last parameter; ``python -m dgraph.signatures MODULE``
in the entity classes of a module of your own; ``--check`` only lists the blocks that are missing
or out of date (``tests/test_signatures.py`` fails on them). A parameter's type comes from its kind
(:data:`TYPES`), ``Literal[...]`` for choices, ``| None`` if it may be None.
"""

from __future__ import annotations

import argparse
import ast
import importlib
import inspect
import math
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

from dgraph.entity import Entity, _generic_init
from dgraph.params import Param
from dgraph.registry import entity_types

TYPES: dict[str, str] = {
    "float": "float", "int": "int", "bool": "bool", "str": "str", "path": "str", "name_or_path": "str | Any",
    "vector": "ArrayLike", "str_list": "Sequence[str]", "path_list": "Sequence[str]", "int_list": "Sequence[int]",
    "object": "Any",
}
"""The type a type checker sees for each parameter kind (what the constructor accepts:
a ``vector`` is any array-like, converted to an ndarray)."""

IMPORTS: dict[str, str] = {
    "TYPE_CHECKING": "from typing import TYPE_CHECKING", "Any": "from typing import Any",
    "Literal": "from typing import Literal", "Sequence": "from collections.abc import Sequence",
    "ArrayLike": "from numpy.typing import ArrayLike",
}
"""Where each name a block uses comes from (added to the module if it lacks it)."""

MARK = "# written by python -m dgraph.signatures from the parameters"
WIDTH = 120


def _literal(value: Any) -> str | None:
    """``value`` as source text, or None if it is not a plain constant."""
    if value is None or isinstance(value, bool | int):
        return repr(value)
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else None
    if isinstance(value, str):
        return f'"{value}"' if '"' not in value and "\\" not in value else repr(value)
    return None


def _default(value: Any) -> str:
    """The default as written in the signature: a constant, a list or tuple of constants as a
    tuple (every sequence kind takes one), else ``...``."""
    text = _literal(value)
    if text is not None:
        return text
    if isinstance(value, list | tuple):
        items = [text for text in map(_literal, value) if text is not None]
        if len(items) == len(value):
            return "(" + ", ".join(items) + ("," if len(items) == 1 else "") + ")"
    return "..."


def annotation(decl: Param) -> str:
    """The type of a parameter: its kind's, or ``Literal[...]`` of its choices; ``| None`` if optional."""
    text = TYPES.get(decl.kind, "Any")
    if decl.choices is not None:
        choices = [text for text in map(_literal, decl.choices) if text is not None]
        if len(choices) == len(decl.choices) and not any(isinstance(c, float) for c in decl.choices):
            text = "Literal[" + ", ".join(choices) + "]"
    if decl.optional and text != "Any":
        text += " | None"
    return text


def init_lines(cls: type[Entity], indent: str = "    ") -> list[str]:
    """The ``if TYPE_CHECKING:`` block declaring ``cls``'s constructor, indented for its class body."""
    arguments = ["self", "name: str"]
    if cls._param_decls:
        arguments.append("*")
    for pname, decl in cls._param_decls.items():
        argument = f"{pname}: {annotation(decl)}"
        arguments.append(argument if decl.required else f"{argument} = {_default(decl.default)}")
    inner = indent * 2
    one_line = f"{inner}def __init__({', '.join(arguments)}) -> None: ..."
    lines = [f"{indent}if TYPE_CHECKING:  {MARK}"]
    if len(one_line) <= WIDTH:
        return [*lines, one_line]
    lines.append(f"{inner}def __init__(")
    row = ""
    for argument in arguments:  # as many arguments a line as fit
        candidate = f"{row} {argument}," if row else f"{inner}{indent}{argument},"
        if row and len(candidate) > WIDTH:
            lines.append(row)
            candidate = f"{inner}{indent}{argument},"
        row = candidate
    return [*lines, row, f"{inner}) -> None: ..."]


def _block_span(node: ast.ClassDef) -> tuple[int, int] | None:
    """Lines (0-based, end excluded) of the class's ``if TYPE_CHECKING:`` block that declares
    ``__init__``, or None."""
    for stmt in node.body:
        if (isinstance(stmt, ast.If) and isinstance(stmt.test, ast.Name) and stmt.test.id == "TYPE_CHECKING"
                and any(isinstance(s, ast.FunctionDef) and s.name == "__init__" for s in stmt.body)):
            return stmt.lineno - 1, stmt.end_lineno or stmt.lineno
    return None


def _is_param(stmt: ast.stmt) -> bool:
    """True for ``x = Param(...)`` or ``x = dg.Param(...)``."""
    if not isinstance(stmt, ast.Assign) or not isinstance(stmt.value, ast.Call):
        return False
    func = stmt.value.func
    return (isinstance(func, ast.Name) and func.id == "Param") or (isinstance(func, ast.Attribute)
                                                                   and func.attr == "Param")


def _insertion_line(node: ast.ClassDef) -> int:
    """Where a new block goes: after the class's last parameter, else after its docstring."""
    after = None
    for stmt in node.body:
        if _is_param(stmt) or (after is None and isinstance(stmt, ast.Expr) and isinstance(stmt.value, ast.Constant)
                               and isinstance(stmt.value.value, str)):
            after = stmt
    if after is not None:
        return after.end_lineno or after.lineno
    first = node.body[0]
    return min([first.lineno, *(d.lineno for d in getattr(first, "decorator_list", []))]) - 1


def _classes_of(module: str) -> list[type[Entity]]:
    """The entity classes defined in ``module`` (an entity's constructor is its own if it has one)."""
    mod = importlib.import_module(module)
    return [c for c in vars(mod).values()
            if isinstance(c, type) and issubclass(c, Entity) and c is not Entity and c.__module__ == module]


def _needs_block(cls: type[Entity]) -> bool:
    """Whether ``cls`` needs a block of its own: its constructor is the generic one and its
    parameters are not exactly those of the entity class it derives from (whose block it inherits)."""
    if not _generic_init(cls):
        return False
    parent = next((b for b in cls.__mro__[1:] if issubclass(b, Entity) and b._param_decls), None)
    return parent is None or not _generic_init(parent) or init_lines(parent) != init_lines(cls)


def builtin_classes() -> list[type[Entity]]:
    """The registered entity types of dgraph and dgraph_sim."""
    return [c for c in entity_types().values() if c.__module__.split(".")[0] in ("dgraph", "dgraph_sim")]


def stale(classes: list[type[Entity]]) -> list[str]:
    """``module.Class`` of each class whose block is missing or differs from what its parameters make."""
    out = []
    for cls in classes:
        if not _needs_block(cls):
            continue
        source = Path(inspect.getfile(cls)).read_text().splitlines()
        node = next(n for n in ast.parse("\n".join(source)).body
                    if isinstance(n, ast.ClassDef) and n.name == cls.__name__)
        span = _block_span(node)
        indent = " " * node.body[0].col_offset
        if span is None or source[span[0]:span[1]] != init_lines(cls, indent):
            out.append(f"{cls.__module__}.{cls.__qualname__}")
    return out


def write(classes: list[type[Entity]]) -> list[Path]:
    """Write the block of each class (a class with a constructor of its own, or the parameters of
    its parent entity class, is left alone);
    returns the files changed. Names the blocks use are imported if the module lacks them."""
    by_file: dict[Path, list[type[Entity]]] = {}
    for cls in classes:
        if _needs_block(cls):
            by_file.setdefault(Path(inspect.getfile(cls)), []).append(cls)
    changed = []
    for path, file_classes in by_file.items():
        text = path.read_text()
        lines = text.splitlines()
        tree = ast.parse(text)
        nodes = {n.name: n for n in tree.body if isinstance(n, ast.ClassDef)}
        edits = []
        for cls in file_classes:
            node = nodes[cls.__name__]
            block = init_lines(cls, " " * node.body[0].col_offset)
            span = _block_span(node)
            edits.append((span or (_insertion_line(node),) * 2, block))
        for (start, end), block in sorted(edits, key=lambda e: e[0], reverse=True):  # bottom up
            lines[start:end] = block
        lines = _add_imports(lines, tree, "\n".join(b for _, bl in edits for b in bl))
        new = "\n".join(lines) + "\n"
        if new != text:
            path.write_text(new)
            changed.append(path)
    ruff = shutil.which("ruff") or shutil.which("ruff", path=str(Path(sys.executable).parent))
    if changed and ruff:  # merge and sort the imports added
        subprocess.run([ruff, "check", "--quiet", "--select", "I", "--fix", *map(str, changed)], check=False)
    return changed


def _add_imports(lines: list[str], tree: ast.Module, blocks: str) -> list[str]:
    """``lines`` with an import of each name of :data:`IMPORTS` that ``blocks`` uses and the module
    does not bind, after ``from __future__ import annotations`` (or at the top)."""
    bound = {alias.asname or alias.name for n in tree.body if isinstance(n, ast.Import | ast.ImportFrom)
             for alias in n.names}
    used = {n.id for n in ast.walk(ast.parse("if 1:\n" + blocks)) if isinstance(n, ast.Name)}
    missing = [IMPORTS[name] for name in IMPORTS if name in used and name not in bound]
    if not missing:
        return lines
    future = next((n.end_lineno for n in tree.body if isinstance(n, ast.ImportFrom) and n.module == "__future__"), 0)
    return [*lines[:future], *missing, *lines[future:]]


def main(argv: list[str] | None = None) -> int:
    """``python -m dgraph.signatures [--check] [MODULE ...]``."""
    parser = argparse.ArgumentParser(prog="python -m dgraph.signatures", description=__doc__.splitlines()[0])
    parser.add_argument("modules", nargs="*", help="modules whose entity classes to write (default: dgraph's)")
    parser.add_argument("--check", action="store_true", help="only list the blocks missing or out of date")
    args = parser.parse_args(argv)
    classes = [c for m in args.modules for c in _classes_of(m)] if args.modules else builtin_classes()
    if args.check:
        out = stale(classes)
        for name in out:
            print(f"{name}: constructor for type checkers missing or out of date")
        return 1 if out else 0
    for path in write(classes):
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
