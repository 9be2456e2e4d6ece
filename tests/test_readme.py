"""The README's Python example runs and does what it says."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_python_example_converges(capsys):
    code = re.search(r"```python\n(.*?)```", README.read_text(), re.S).group(1)
    namespace: dict = {}
    exec(compile(code, "README.md", "exec"), namespace)
    assert np.allclose(namespace["robot"].q.value, [1.0, -0.5], atol=1e-3)
    out = capsys.readouterr().out
    assert "robot.q is the state of robot" in out and "flowchart LR" in out


def test_readme_graph_file_is_the_shipped_one():
    import yaml

    block = re.search(r"```yaml\n(.*?)```", README.read_text(), re.S).group(1)
    shipped = README.with_name("graphs").joinpath("pd_double_integrator.yaml").read_text()
    assert yaml.safe_load(block) == yaml.safe_load(shipped)
