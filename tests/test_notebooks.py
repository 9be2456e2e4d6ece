"""The notebooks of notebooks/: stored without outputs, and each runs from top to bottom.

Every notebook is executed with nbclient on a kernel started by *this* interpreter (a kernel
spec written for ``sys.executable``, so never a global ``python3`` kernel of another
environment), with the notebook's folder as working directory, as Jupyter runs it. A cell that
raises fails the test with the cell and its traceback. Files the notebooks write go to
``DGRAPH_NOTEBOOK_OUT`` (a temporary folder here; ``out/notebooks`` when run by hand).
Notebooks that simulate TALOS for seconds are marked ``sim`` (``make test-fast`` leaves them
out); a new notebook is ``sim`` unless listed in ``FAST``.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import nbformat
import pytest
from jupyter_client.kernelspec import KernelSpecManager
from jupyter_client.manager import KernelManager
from nbclient import NotebookClient
from nbclient.exceptions import CellExecutionError

ROOT = Path(__file__).resolve().parents[1]
FOLDER = ROOT / "notebooks"
NOTEBOOKS = sorted(FOLDER.glob("*.ipynb"))
FAST = {"01_build_and_inspect.ipynb"}  # a fraction of a second of TALOS: kept in `make test-fast`
KERNEL = "dgraph-test-python"
CELL_TIMEOUT = 600  # s; a whole notebook takes well under this


def params() -> list[pytest.param]:
    return [pytest.param(path, id=path.stem, marks=() if path.name in FAST else pytest.mark.sim)
            for path in NOTEBOOKS]


@pytest.fixture(scope="module")
def kernel_specs(tmp_path_factory: pytest.TempPathFactory) -> KernelSpecManager:
    """A kernel spec manager that knows only a kernel run by this interpreter."""
    folder = tmp_path_factory.mktemp("kernels") / KERNEL
    folder.mkdir()
    spec = {"argv": [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"],
            "display_name": f"Python ({sys.executable})", "language": "python"}
    (folder / "kernel.json").write_text(json.dumps(spec))
    return KernelSpecManager(kernel_dirs=[str(folder.parent)], ensure_native_kernel=False)


def test_the_notebooks_are_there():
    names = {path.name for path in NOTEBOOKS}
    assert {"01_build_and_inspect.ipynb", "02_talos_graph_file.ipynb", "03_energy_tank.ipynb",
            "04_compare_controllers.ipynb"} <= names
    assert FAST <= names


def stored_problems(notebook: nbformat.NotebookNode) -> list[str]:
    """What keeps ``notebook`` from being stored as it is: outputs, execution counts, widget state."""
    problems = [f"cell {cell.get('id')} has outputs or an execution count" for cell in notebook.cells
                if cell.cell_type == "code" and (cell.outputs or cell.execution_count is not None)]
    if "widgets" in notebook.metadata:
        problems.append("widget state in the metadata")
    return problems


def execute(notebook: nbformat.NotebookNode, kernel_specs: KernelSpecManager, out: Path) -> float:
    """Run every cell of ``notebook`` in place, in notebooks/, on this interpreter's kernel; the
    wall time (s). Raises ``CellExecutionError`` (the cell and its traceback) if a cell raises."""
    client = NotebookClient(notebook, timeout=CELL_TIMEOUT, kernel_name=KERNEL, allow_errors=False,
                            km=KernelManager(kernel_name=KERNEL, kernel_spec_manager=kernel_specs),
                            resources={"metadata": {"path": str(FOLDER)}})
    start = time.perf_counter()
    try:
        client.execute()
    finally:
        nbformat.write(notebook, out / "executed.ipynb")  # executed as far as it went, to read after a failure
    return time.perf_counter() - start


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[path.stem for path in NOTEBOOKS])
def test_stored_without_outputs(path: Path):
    notebook = nbformat.read(path, as_version=4)
    nbformat.validate(notebook)
    assert any(cell.cell_type == "code" for cell in notebook.cells), f"{path.name} has no code cell"
    assert stored_problems(notebook) == [], f"{path.name}: clear the outputs before committing"


def test_outputs_are_noticed():
    notebook = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("1", id="a"),
                                               nbformat.v4.new_code_cell("2", id="b")])
    assert stored_problems(notebook) == []
    notebook.cells[0].outputs = [nbformat.v4.new_output("stream", text="1\n")]
    notebook.cells[1].execution_count = 3
    notebook.metadata["widgets"] = {}
    assert stored_problems(notebook) == ["cell a has outputs or an execution count",
                                         "cell b has outputs or an execution count", "widget state in the metadata"]


def test_the_kernel_is_this_interpreter(kernel_specs: KernelSpecManager):
    assert kernel_specs.find_kernel_specs().keys() == {KERNEL}
    assert KernelManager(kernel_name=KERNEL, kernel_spec_manager=kernel_specs).kernel_spec.argv[0] == sys.executable


def test_a_cell_that_raises_fails(kernel_specs: KernelSpecManager, tmp_path: Path):
    notebook = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("import sys\nprint(sys.executable)"),
                                               nbformat.v4.new_code_cell("raise ValueError('broken on purpose')"),
                                               nbformat.v4.new_code_cell("print('never')")])
    with pytest.raises(CellExecutionError, match="broken on purpose"):
        execute(notebook, kernel_specs, tmp_path)
    assert notebook.cells[0].outputs[0]["text"].strip() == sys.executable
    assert notebook.cells[2].outputs == []


@pytest.mark.parametrize("path", params())
def test_runs(path: Path, kernel_specs: KernelSpecManager, tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    monkeypatch.setenv("DGRAPH_NOTEBOOK_OUT", str(tmp_path))  # the kernel inherits the environment
    monkeypatch.setenv("MPLBACKEND", "module://matplotlib_inline.backend_inline")
    notebook = nbformat.read(path, as_version=4)
    seconds = execute(notebook, kernel_specs, tmp_path)
    print(f"{path.name}: {seconds:.1f} s")
    figures = sum("image/png" in output.get("data", {}) for cell in notebook.cells
                  for output in cell.get("outputs", []))
    assert figures, f"{path.name} showed no figure (every notebook here plots inline)"
