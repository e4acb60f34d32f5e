"""The elastic contact problem gives the same iterations, gaps and u_h on 1 and 2 ranks
(tests/mpi/elastic_check.py; relative 1e-10: the distributed sums are ordered differently,
and on the 4^3 box the amg preconditioner's inner solve, whose GAMG hierarchy depends on the
partition, stops at the relative residual coupling.options.AMG_RTOL = 1e-12; on the square
and the 8^3 box the preconditioner is the lattice's multigrid, one V-cycle the same on any
number of ranks, which the Newton steps' CG applies as it is; with the H-matrix S_h of the
8^3 box M_s is read from its Lame W_h, collective, the same bits on every rank)."""
from __future__ import annotations

import numpy as np
import pytest

from conftest import ROOT, run_mpi

SCRIPT = str(ROOT / "tests" / "mpi" / "elastic_check.py")


@pytest.mark.mpi
@pytest.mark.parametrize(
    "dim, operator, cubes",
    [(2, "dense", 4), (2, "hmatrix", 4), (3, "dense", 4), (3, "dense", 8), (3, "hmatrix", 8)],
    ids=["square-dense", "square-hmatrix", "box-gamg", "box-lattice", "box-hmatrix"],
)
def test_elastic_contact_is_rank_independent(tmp_path, dim, operator, cubes):
    runs = {}
    for r in (1, 2):
        out = tmp_path / f"r{r}.npz"
        run_mpi(r, SCRIPT, str(out), str(dim), operator, str(cubes))
        runs[r] = np.load(out)
    one, two = runs[1], runs[2]
    normal = one["phi"][: one["phi"].size // dim]  # the normal gaps come first
    assert 0 < np.count_nonzero(normal) < normal.size  # a partial contact set
    assert int(two["iterations"]) == int(one["iterations"])
    for key in ("u", "phi"):
        assert np.linalg.norm(two[key] - one[key]) <= 1e-10 * np.linalg.norm(one[key])
