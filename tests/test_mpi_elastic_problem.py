"""The elastic contact problem gives the same iterations, gaps and u_h on 1 and 2 ranks
(tests/mpi/elastic_check.py; relative 1e-10: the distributed sums are ordered differently,
and the amg preconditioner's inner solve, whose GAMG hierarchy depends on the partition,
stops at the relative residual coupling.options.AMG_RTOL = 1e-12)."""
from __future__ import annotations

import numpy as np
import pytest

from conftest import ROOT, run_mpi

SCRIPT = str(ROOT / "tests" / "mpi" / "elastic_check.py")


@pytest.mark.mpi
@pytest.mark.parametrize("dim, operator", [(2, "dense"), (2, "hmatrix"), (3, "dense")])
def test_elastic_contact_is_rank_independent(tmp_path, dim, operator):
    runs = {}
    for r in (1, 2):
        out = tmp_path / f"r{r}.npz"
        run_mpi(r, SCRIPT, str(out), str(dim), operator)
        runs[r] = np.load(out)
    one, two = runs[1], runs[2]
    normal = one["phi"][: one["phi"].size // dim]  # the normal gaps come first
    assert 0 < np.count_nonzero(normal) < normal.size  # a partial contact set
    assert int(two["iterations"]) == int(one["iterations"])
    for key in ("u", "phi"):
        assert np.linalg.norm(two[key] - one[key]) <= 1e-10 * np.linalg.norm(one[key])
