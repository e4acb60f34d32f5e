"""The 3D contact problem on the box gives the same iterations, phi and u_h on 1 and 2
ranks (tests/mpi/solid_problem_check.py; relative 1e-10: the sums of the distributed
assembly are ordered differently)."""
from __future__ import annotations

import numpy as np
import pytest

from conftest import ROOT, run_mpi

SCRIPT = str(ROOT / "tests" / "mpi" / "solid_problem_check.py")


@pytest.mark.mpi
def test_box_contact_is_rank_independent(tmp_path):
    runs = {}
    for ranks in (1, 2):
        out = tmp_path / f"r{ranks}.npz"
        run_mpi(ranks, SCRIPT, str(out), "4")
        runs[ranks] = np.load(out)
    one, two = runs[1], runs[2]
    assert int(one["iterations"]) == int(two["iterations"])
    assert 0 < np.count_nonzero(one["phi"]) < one["phi"].size  # a partial contact set
    for key in ("u", "phi"):
        assert np.linalg.norm(two[key] - one[key]) <= 1e-10 * np.linalg.norm(one[key])
