"""fem_py.mesh.placed: the mesh made from cells already on their ranks is the mesh
``dolfinx.mesh.create_mesh`` makes from the same cells and ghost links, on 1, 2 and 3 ranks,
in 2D and 3D; bad arrays are refused with one line."""
from __future__ import annotations

import json

import numpy as np
import pytest
from mpi4py import MPI

from conftest import ROOT, run_mpi
from fem_py.mesh.placed import mesh_of_placed_cells


@pytest.mark.mpi
@pytest.mark.parametrize("ranks", [1, 2, 3])
def test_placed_cells_make_create_meshs_mesh(tmp_path, ranks):
    out = tmp_path / "placed"
    run_mpi(ranks, str(ROOT / "tests" / "mpi" / "placed_cells_check.py"), str(out), timeout=240)
    for rank in range(ranks):
        result = json.loads((tmp_path / f"placed.{rank}").read_text())
        for name, r in result.items():
            assert r["differ"] == [], (rank, name, r)
            assert r["owned"] > 0
            assert (r["ghosts"] > 0) == (ranks > 1), (rank, name)  # the ghost layer is there


def test_placed_cells_refuse_wrong_shapes():
    comm = MPI.COMM_SELF
    x = np.zeros((3, 2))
    with pytest.raises(ValueError, match="cells must be n x 3 for a triangle"):
        mesh_of_placed_cells(
            comm, "triangle", np.zeros((1, 4), dtype=np.int64), x, np.zeros((0, 2))
        )
    with pytest.raises(ValueError, match="x must be m x gdim with gdim >= 3"):
        mesh_of_placed_cells(comm, "tetrahedron", np.zeros((1, 4), dtype=np.int64), x, [])
