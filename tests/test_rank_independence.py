"""Iterates that do not depend on the number of ranks: the whole histories of pgpm and of
the default method (C0, tau, J_h, the step norm and the contact count of every
iteration) agree to round-off on 1, 2 and 3 ranks, and fields are gathered in the same
(input) numbering, on a structured and an unstructured (gmsh) mesh.

Tolerances: the runs differ only in the order of the reductions (sums over ranks, the
distributed preconditioner's scatters), i.e. round-off of about 1e-16 relative per
operation; measured differences are below 2e-14 after 200 iterations, so 1e-12 bounds
them with a margin and still fails at the first iteration that takes another path.
"""
from __future__ import annotations

import numpy as np
import pytest

from conftest import ROOT, run_mpi

SCRIPT = str(ROOT / "tests" / "mpi" / "histories.py")


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    out = {}
    for nprocs in (1, 2, 3):
        path = tmp_path_factory.mktemp("ranks") / f"p{nprocs}.npz"
        run_mpi(nprocs, SCRIPT, str(path))
        out[nprocs] = dict(np.load(path))
    return out


@pytest.mark.mpi
@pytest.mark.parametrize("nprocs", [2, 3])
def test_histories_agree_to_round_off(runs, nprocs):
    serial, par = runs[1], runs[nprocs]
    keys = [k[: -len("_history")] for k in serial if k.endswith("_history")]
    assert len(keys) == 4
    for key in keys:
        h1, hp = serial[f"{key}_history"], par[f"{key}_history"]
        assert h1.shape == hp.shape, f"{key}: {len(h1)} vs {len(hp)} iterations"
        np.testing.assert_array_equal(hp[:, 3], h1[:, 3])  # contact counts
        np.testing.assert_allclose(hp[:, :3], h1[:, :3], rtol=1e-12, atol=1e-12, err_msg=key)
        assert abs(par[f"{key}_C0"] - serial[f"{key}_C0"]) <= 1e-12 * serial[f"{key}_C0"]
        np.testing.assert_allclose(par[f"{key}_phi"], serial[f"{key}_phi"], atol=1e-12)


@pytest.mark.mpi
@pytest.mark.parametrize("nprocs", [2, 3])
def test_fields_in_the_same_numbering(runs, nprocs):
    serial, par = runs[1], runs[nprocs]
    for key in ("square_pgpm", "lshape_pgpm"):
        # coordinates: written down per rank, equal up to the round-off of x0 + i h
        np.testing.assert_allclose(par[f"{key}_x"], serial[f"{key}_x"], atol=1e-15)
        np.testing.assert_array_equal(par[f"{key}_triangles"], serial[f"{key}_triangles"])
        np.testing.assert_allclose(par[f"{key}_u"], serial[f"{key}_u"], atol=1e-12)
