"""Entity constructors as type checkers see them (dgraph.signatures): written in every entity
class, up to date with its parameters, and read by real static checkers (mypy; pyright, which
Pylance is, if installed)."""

import importlib
import inspect
import json
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import dgraph as dg
from dgraph import signatures

ROOT = Path(__file__).resolve().parents[1]


def test_every_entity_class_declares_its_constructor_for_type_checkers():
    """Each registered entity carries the __init__ its parameters make (``python -m dgraph.signatures``
    writes it; a changed parameter without it fails here)."""
    classes = signatures.builtin_classes()
    assert dg.registry.plugin_errors() == {}  # a family that does not load is not checked
    stale = set(signatures.stale(classes))
    assert stale == set(), "run: python -m dgraph.signatures"


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


def test_a_subclass_with_its_parents_parameters_inherits_the_block_and_one_with_more_gets_its_own(tmp_path,
                                                                                                  monkeypatch):
    module = tmp_path / "dampers.py"
    module.write_text(textwrap.dedent('''\
        from __future__ import annotations

        import dgraph as dg


        class Damper(dg.Entity):
            """A damper."""

            c = dg.Param(1.0, kind="float")


        class QuietDamper(Damper):
            """The same parameters."""


        class TunedDamper(Damper):
            """One more."""

            k = dg.Param(0.0, kind="float")
        '''))
    monkeypatch.syspath_prepend(str(tmp_path))
    assert signatures.main(["dampers"]) == 0
    text = module.read_text()
    assert text.count("TYPE_CHECKING:  #") == 2  # Damper's and TunedDamper's: QuietDamper inherits Damper's
    assert "def __init__(self, name: str, *, c: float = 1.0, k: float = 0.0) -> None: ..." in text
    assert signatures.main(["--check", "dampers"]) == 0


def test_a_parameter_type_is_that_of_its_kind_or_its_choices():
    assert signatures.annotation(dg.Param(kind="str_list")) == "Sequence[str]"
    assert signatures.annotation(dg.Param(None, kind="vector")) == "ArrayLike | None"
    assert signatures.annotation(dg.Param("lin", kind="str", choices=("lin", "cub"))) == 'Literal["lin", "cub"]'


def test_a_long_constructor_is_wrapped_within_the_line_length():
    from dgraph.entities.solvers import InverseDynamicsSolver

    lines = signatures.init_lines(InverseDynamicsSolver)
    assert len(lines) > 3 and max(map(len, lines)) <= 120 and lines[-1] == "        ) -> None: ..."
    compile("class C:\n" + "\n".join(lines) + "\n", "<block>", "exec")


# one entity of each family: (import, call with its required parameters)
FAMILIES = {
    "operators": ("from dgraph.entities.operators import Gain", 'Gain("e", size=2)'),
    "robot": ("from dgraph.entities.robot import RobotModel", 'RobotModel("e", model="talos")'),
    "features": ("from dgraph.entities.features import FramePose", 'FramePose("e", frame="arm")'),
    "tasks": ("from dgraph.entities.tasks import Task", 'Task("e")'),
    "contacts": ("from dgraph.entities.contacts import Contact6d", 'Contact6d("e", frame="sole")'),
    "solvers": ("from dgraph.entities.solvers import InverseDynamicsSolver", 'InverseDynamicsSolver("e", tasks=["t"])'),
    "mujoco device": ("from dgraph_sim.device import MujocoDevice", 'MujocoDevice("e", model="talos")'),
}


def _snippet(folder: Path) -> list[str]:
    """For each family: build an entity right, misspell a parameter, reveal the constructor
    (each line ends with its family); ``dgraph`` and ``dgraph_sim`` linked as installed (the
    editable install's finder is an import hook, which type checkers cannot follow)."""
    (folder / "dgraph").symlink_to(ROOT / "dgraph")
    (folder / "dgraph_sim").symlink_to(ROOT / "sim")
    lines = []
    for i, (family, (imp, call)) in enumerate(FAMILIES.items()):
        cls = call.split("(")[0]
        lines += [imp, f"right{i} = {call}  # {family}",
                  f"wrong{i} = {call[:-1]}, sise=2)  # {family}", f"reveal_type({cls}.__init__)  # {family}"]
    (folder / "snippet.py").write_text("\n".join(lines) + "\n")
    return lines


def _mypy(folder: Path) -> list[tuple[int, str]]:
    api = pytest.importorskip("mypy.api")
    out, err, _ = api.run([str(folder / "snippet.py"), "--follow-imports=silent", "--ignore-missing-imports",
                           "--no-error-summary", "--hide-error-context", "--cache-dir", str(folder / ".mypy_cache")])
    assert not err, err
    found = [re.match(r".*snippet\.py:(\d+): (error|note): (.*)$", line) for line in out.splitlines()]
    return [(int(m.group(1)), f"{m.group(2)}: {m.group(3)}") for m in found if m]


def _pyright(folder: Path) -> list[tuple[int, str]]:
    pytest.importorskip("pyright")
    run = subprocess.run([sys.executable, "-m", "pyright", "--outputjson", "--pythonpath", sys.executable,
                          "snippet.py"], cwd=folder, capture_output=True, text=True, timeout=300)
    report = json.loads(run.stdout)
    return [(d["range"]["start"]["line"] + 1, f"{d['severity']}: {d['message']}") for d in report["generalDiagnostics"]]


CHECKERS = {"mypy": _mypy, "pyright": _pyright}


@pytest.fixture(scope="module", params=list(CHECKERS))
def checker_report(request, tmp_path_factory):
    """What the checker says about each family's lines, and the parameters of the constructor it
    reveals, as ``name: type`` with `` =`` and the default where there is one."""
    folder = tmp_path_factory.mktemp(request.param)
    lines = _snippet(folder)
    report: dict[str, dict[str, list[str]]] = {f: {"errors": [], "arguments": []} for f in FAMILIES}
    for number, message in CHECKERS[request.param](folder):
        family = report[lines[number - 1].rsplit("# ", 1)[1]]
        if message.startswith("error"):
            family["errors"].append(message)
        revealed = re.search(r'Revealed type is "def \((.*)\)"$|Type of "[\w.]+" is "\((.*)\) -> None"$', message)
        if revealed:
            text = (revealed.group(1) or revealed.group(2)).split("*, ", 1)[-1] if "*, " in message else ""
            family["arguments"] = re.split(r", (?=\w+: )", text) if text else []
    return request.param, report


UNEXPECTED = {"mypy": 'error: Unexpected keyword argument "sise" for "{}"  [call-arg]',
              "pyright": 'error: No parameter named "sise"'}


@pytest.mark.parametrize("family", list(FAMILIES))
def test_a_static_checker_sees_the_parameters_of_an_entity(checker_report, family):
    """Right keywords type-check, a misspelt one is an unexpected keyword argument, and the
    revealed constructor lists the parameters with their types and defaults."""
    checker, report = checker_report
    cls = FAMILIES[family][1].split("(")[0]
    assert report[family]["errors"] == [UNEXPECTED[checker].format(cls)], report[family]
    decls = dg.get_type(cls)._param_decls
    arguments = report[family]["arguments"]
    assert [a.split(":")[0] for a in arguments] == list(decls), arguments  # every parameter, in order
    assert [" =" in a for a in arguments] == [not d.required for d in decls.values()], arguments  # defaults
