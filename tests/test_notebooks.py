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


@pytest.mark.parametrize("path", params())
def test_stored_without_outputs(path: Path):
    notebook = nbformat.read(path, as_version=4)
    nbformat.validate(notebook)
    code = [cell for cell in notebook.cells if cell.cell_type == "code"]
    assert code, f"{path.name} has no code cell"
    for cell in code:
        assert cell.outputs == [] and cell.execution_count is None, \
            f"{path.name}: cell {cell.id} is stored with outputs (clear them before committing)"
    assert "widgets" not in notebook.metadata, f"{path.name} is stored with widget state"


def test_the_kernel_is_this_interpreter(kernel_specs: KernelSpecManager):
    assert kernel_specs.find_kernel_specs().keys() == {KERNEL}
    assert KernelManager(kernel_name=KERNEL, kernel_spec_manager=kernel_specs).kernel_spec.argv[0] == sys.executable


@pytest.mark.parametrize("path", params())
def test_runs(path: Path, kernel_specs: KernelSpecManager, tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    monkeypatch.setenv("DGRAPH_NOTEBOOK_OUT", str(tmp_path))  # the kernel inherits the environment
    monkeypatch.setenv("MPLBACKEND", "module://matplotlib_inline.backend_inline")
    notebook = nbformat.read(path, as_version=4)
    notebook.cells.append(nbformat.v4.new_code_cell("import sys\nprint(sys.executable)"))
    client = NotebookClient(notebook, timeout=CELL_TIMEOUT, kernel_name=KERNEL, allow_errors=False,
                            km=KernelManager(kernel_name=KERNEL, kernel_spec_manager=kernel_specs),
                            resources={"metadata": {"path": str(FOLDER)}})
    start = time.perf_counter()
    try:
        client.execute()  # raises CellExecutionError, with the cell and its traceback, if a cell raises
    finally:
        nbformat.write(notebook, tmp_path / path.name)  # executed as far as it went, to read after a failure
    print(f"{path.name}: {time.perf_counter() - start:.1f} s")
    assert notebook.cells[-1].outputs[0]["text"].strip() == sys.executable
    figures = sum("image/png" in output.get("data", {}) for cell in notebook.cells
                  for output in cell.get("outputs", []))
    assert figures, f"{path.name} showed no figure (every notebook here plots inline)"
