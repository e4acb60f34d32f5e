"""The PGPM iterates do not depend on the number of MPI ranks (contact problem)."""
from __future__ import annotations

import numpy as np
import pytest

from conftest import ROOT, run_mpi

SCRIPT = str(ROOT / "tests" / "mpi" / "pgpm_parallel.py")


@pytest.mark.mpi
@pytest.mark.parametrize("preconditioner", ["substructuring", "exact"])
def test_iterates_independent_of_ranks(tmp_path, preconditioner):
    runs = {}
    for nprocs in (1, 2, 3):
        out = tmp_path / f"p{nprocs}.npz"
        run_mpi(nprocs, SCRIPT, str(out), "16", preconditioner)
        runs[nprocs] = np.load(out)
    serial = runs[1]
    assert serial["converged"]
    for nprocs in (2, 3):
        par = runs[nprocs]
        # whole subdomains per rank: the substructuring B is distributed, not gathered
        expected = {
            "substructuring": "DistributedSubstructuringPreconditioner",
            "exact": "RootPreconditioner",
        }[preconditioner]
        assert str(par["preconditioner_class"]) == expected
        assert par["iterations"] == serial["iterations"]
        np.testing.assert_allclose(par["x"], serial["x"], atol=1e-15)
        # tol = 1e-10: the solutions agree far below the stopping tolerance (round-off
        # of the reductions in a different order is all that differs)
        assert np.linalg.norm(par["u"] - serial["u"]) <= 1e-9 * np.linalg.norm(serial["u"])
        assert np.linalg.norm(par["phi"] - serial["phi"]) <= 1e-9 * np.linalg.norm(serial["phi"])
        assert abs(par["energy"] - serial["energy"]) <= 1e-12 * abs(serial["energy"])
