"""The 3D contact problem on the box and on the gmsh ball gives the same iterations, phi
and u_h on 1, 2 and 3 ranks (tests/mpi/solid_problem_check.py; relative 1e-10: the sums
of the distributed assembly are ordered differently, and on the ball the amg
preconditioner's inner solve, whose GAMG hierarchy depends on the partition, stops at the
relative residual coupling.options.AMG_RTOL = 1e-12; on the box its geometric multigrid
is the same operator on any number of ranks, and one V-cycle of it preconditions the
Newton steps' CG)."""
from __future__ import annotations

import numpy as np
import pytest

from conftest import ROOT, run_mpi

SCRIPT = str(ROOT / "tests" / "mpi" / "solid_problem_check.py")


@pytest.mark.mpi
@pytest.mark.parametrize(
    "shape, preconditioner, ranks",
    [("box", "exact", (1, 2)), ("box", "amg", (1, 2, 3)), ("ball", "amg", (1, 2, 3))],
)
def test_contact_is_rank_independent(tmp_path, shape, preconditioner, ranks):
    runs = {}
    for r in ranks:
        out = tmp_path / f"r{r}.npz"
        run_mpi(r, SCRIPT, str(out), shape, preconditioner)
        runs[r] = np.load(out)
    one = runs[1]
    assert 0 < np.count_nonzero(one["phi"]) < one["phi"].size  # a partial contact set
    for r in ranks[1:]:
        other = runs[r]
        assert int(other["iterations"]) == int(one["iterations"])
        for key in ("u", "phi"):
            assert np.linalg.norm(other[key] - one[key]) <= 1e-10 * np.linalg.norm(one[key])
