"""Entity constructors as type checkers see them (dgraph.signatures)."""

import importlib
import inspect
import sys
import textwrap

import dgraph as dg
from dgraph import signatures


def test_the_block_is_written_after_the_parameters_and_rewritten_when_they_change(tmp_path, monkeypatch):
    module = tmp_path / "springs.py"
    module.write_text(textwrap.dedent('''\
        from __future__ import annotations

        import dgraph as dg


        class Spring(dg.Entity):
            """A spring."""

            k = dg.Param(kind="float", doc="stiffness, N/m")
            rest = dg.Param([0.0, 0.0], kind="vector")
            size = dg.Param(None, kind="int")
            x = dg.Input(shape=("size",))
        '''))
    monkeypatch.syspath_prepend(str(tmp_path))
    assert signatures.main(["springs"]) == 0
    text = module.read_text()
    assert '    size = dg.Param(None, kind="int")\n' \
           "    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters\n" \
           "        def __init__(self, name: str, *, k: float, rest: ArrayLike = (0.0, 0.0), size: int | None = None)" \
           " -> None: ...\n    x = dg.Input" in text
    assert "from typing import TYPE_CHECKING\n" in text and "from numpy.typing import ArrayLike\n" in text
    springs = importlib.import_module("springs")
    assert list(inspect.signature(springs.Spring).parameters) == ["name", "k", "rest", "size"]
    assert signatures.main(["--check", "springs"]) == 0
    assert signatures.main(["springs"]) == 0 and module.read_text() == text  # written once

    module.write_text(text.replace('size = dg.Param(None, kind="int")', 'size = dg.Param(3, kind="int")'))
    del sys.modules["springs"]
    assert signatures.main(["--check", "springs"]) == 1
    assert signatures.main(["springs"]) == 0
    assert "size: int = 3) -> None: ...\n" in module.read_text() and module.read_text().count("TYPE_CHECKING:") == 1


def test_a_parameter_type_is_that_of_its_kind_or_its_choices():
    assert signatures.annotation(dg.Param(kind="str_list")) == "Sequence[str]"
    assert signatures.annotation(dg.Param(None, kind="vector")) == "ArrayLike | None"
    assert signatures.annotation(dg.Param("lin", kind="str", choices=("lin", "cub"))) == 'Literal["lin", "cub"]'


def test_a_long_constructor_is_wrapped_within_the_line_length():
    from dgraph.entities.solvers import InverseDynamicsSolver

    lines = signatures.init_lines(InverseDynamicsSolver)
    assert len(lines) > 3 and max(map(len, lines)) <= 120 and lines[-1] == "        ) -> None: ..."
    compile("class C:\n" + "\n".join(lines) + "\n", "<block>", "exec")
