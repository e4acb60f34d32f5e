"""fem_py.forms.P1Matrix (DOLFINx's CSR storage, scipy products) gives the Jacobian
products, the stiffness rows and the ranks' shares of DOLFINx's PETSc assembly, in serial
and on 3 ranks (tests/mpi/p1_matrix_check.py)."""
from __future__ import annotations

import importlib.util
import json

import pytest
from mpi4py import MPI

from conftest import ROOT, run_mpi

SCRIPT = ROOT / "tests" / "mpi" / "p1_matrix_check.py"
#: The products and rows sum the same terms as PETSc's, possibly in another order (the
#: ghost rows' sums): agreement to a few units of round-off relative to the largest entry.
ROUND_OFF = 1e-14


def _check(result: dict) -> None:
    assert result["is_p1_matrix"]
    for kind in ("ufl", "handwritten"):
        assert result[f"product_{kind}"] <= ROUND_OFF, (kind, result)
        assert result[f"ghosts_zero_{kind}"], kind
    assert result["stiffness_shape"]
    assert result["stiffness_rows"] <= ROUND_OFF, result
    assert result["stiffness_alone"] == 0.0
    assert result["stiffness_local"] <= ROUND_OFF, result


def test_p1_matrix_serial():
    spec = importlib.util.spec_from_file_location("p1_matrix_check", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    result = module.compute(MPI.COMM_SELF)
    _check(result)
    assert result["extra_columns"] == 0  # one rank: every column is a local dof


@pytest.mark.mpi
def test_p1_matrix_three_ranks(tmp_path):
    out = tmp_path / "p1.json"
    run_mpi(3, str(SCRIPT), str(out), timeout=240)
    result = json.loads(out.read_text())
    _check(result)
    # the case mult pads: some rank's rows reach a column outside its cells
    assert result["extra_columns"] >= 1, result
