"""The public face of the library (issue 66, item 11): ``import coupling`` offers the
problem, the options, the solvers, the outputs, the configuration loader and the geometry
spec and builder, each the object of its own module (the deep paths keep working), loaded
on first use; the guide's example (docs/guide/python.md) needs no other import of the
library and runs."""
from __future__ import annotations

import ast
import importlib
import re
import subprocess
import sys

import pytest

from conftest import ROOT

import coupling

DEEP = {
    "GeometrySpec": "fem_py.spec",
    "build_domain": "fem_py.mesh",
    "make_material": "fem_py.forms",
    "SignoriniProblem": "coupling.problem",
    "SolverOptions": "coupling.options",
    "RunConfig": "coupling.options",
    "solve": "coupling.solvers",
    "solve_nested": "coupling.solvers.nested",
    "estimate": "coupling.adapt",
    "write_outputs": "coupling.io.outputs",
    "prepare_output_dir": "coupling.io.atomic",
    "load_config": "coupling.app.config",
    "problem_from_config": "coupling.app.from_config",
}


@pytest.mark.parametrize("name", sorted(DEEP))
def test_a_public_name_is_its_module_s_object(name):
    assert name in coupling.__all__ and name in dir(coupling)
    assert getattr(coupling, name) is getattr(importlib.import_module(DEEP[name]), name)


def test_the_adaptive_loop_and_the_subpackage_keep_their_names():
    import coupling.adapt

    assert coupling.solve_adaptive is coupling.adapt.adapt  # the function
    assert coupling.adapt.__name__ == "coupling.adapt"  # the subpackage, as before
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        coupling.nope


def test_import_coupling_loads_no_mpi():
    """The figure process imports coupling.io without MPI (tests/test_plots.py); the
    public face must not load it either."""
    code = (
        "import sys, coupling; heavy = [m for m in ('mpi4py', 'dolfinx', 'petsc4py') "
        "if m in sys.modules]; print(heavy)"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "[]"


def test_the_library_does_not_import_its_own_public_face():
    """The face is for scripts: a module of the library importing ``coupling`` itself
    would hide its layer (tests/test_layout.py)."""
    for path in sorted((ROOT / "coupling").rglob("*.py")) + sorted((ROOT / "fem_py").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level == 0:
                assert node.module != "coupling", path
            elif isinstance(node, ast.Import):
                assert all(a.name != "coupling" for a in node.names), path


def test_the_guide_s_example_runs_with_one_import_of_the_library(tmp_path):
    page = (ROOT / "docs" / "guide" / "python.md").read_text()
    code = re.search(r"```python\n(.*?)```", page, re.S).group(1)
    imports = {m.group(1) for m in re.finditer(r"^(?:from|import) ([a-z_0-9.]+)", code, re.M)}
    assert imports == {"pathlib", "mpi4py", "coupling"}, imports
    script = tmp_path / "example.py"
    script.write_text(code)
    proc = subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, cwd=tmp_path, timeout=300
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "converged: True" in proc.stdout
    assert (tmp_path / "out" / "summary.json").is_file()
