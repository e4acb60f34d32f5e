"""The adaptive loop under MPI: the same levels (dofs, marked cells, subdomains after the
split of graded ones, iteration counts, estimator, errors, contact sets) and the same
refined mesh and subdomain tags up to the ordering as in serial."""
from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import ROOT, run_mpi

SCRIPT = str(ROOT / "tests" / "mpi" / "adapt_parallel.py")


@pytest.mark.mpi
@pytest.mark.parametrize("case", ["corner", "contact"])
def test_adaptive_levels_independent_of_ranks(tmp_path, case):
    runs = {}
    for nprocs in (1, 2):
        out = tmp_path / f"p{nprocs}.json"
        run_mpi(nprocs, SCRIPT, str(out), case)
        runs[nprocs] = json.loads(out.read_text())
    serial, par = runs[1], runs[2]
    assert len(serial["rows"]) == len(par["rows"])
    for s, p in zip(serial["rows"], par["rows"]):
        sizes = ("dofs", "boundary_dofs", "signorini_dofs", "cells", "subdomains", "marked")
        for key in sizes + ("contact_nodes", "iterations", "cg_iterations"):
            assert s[key] == p[key], key
        assert s["converged"] and p["converged"] and p["mismatch"] == 0
        assert p["estimator"] == pytest.approx(s["estimator"], rel=1e-8)
        assert p["error"] == pytest.approx(s["error"], rel=1e-8)
    assert serial["rows"][-1]["subdomains"] > serial["rows"][0]["subdomains"]  # split
    np.testing.assert_allclose(np.array(par["cells"]), np.array(serial["cells"]), atol=1e-14)


SOLID_SCRIPT = str(ROOT / "tests" / "mpi" / "adapt_solid_parallel.py")


@pytest.mark.mpi
def test_adaptive_body_levels_independent_of_ranks(tmp_path):
    """The box with contact (tests/test_adapt_solid.py), two refinements: the same levels,
    estimator and errors (to round-off: the refined surface's nodes are ordered by their
    coordinates; measured 6e-15), the same refined mesh and named faces on 1, 2 and 3
    ranks."""
    runs = {}
    for nprocs in (1, 2, 3):
        out = tmp_path / f"p{nprocs}.json"
        run_mpi(nprocs, SOLID_SCRIPT, str(out))
        runs[nprocs] = json.loads(out.read_text())
    serial = runs[1]
    for par in (runs[2], runs[3]):
        assert len(serial["rows"]) == len(par["rows"]) == 3
        for s, p in zip(serial["rows"], par["rows"]):
            sizes = ("dofs", "boundary_dofs", "signorini_dofs", "cells", "marked")
            for key in sizes + ("contact_nodes", "iterations", "cg_iterations"):
                assert s[key] == p[key], key
            assert s["converged"] and p["converged"] and p["mismatch"] == 0
            assert p["estimator"] == pytest.approx(s["estimator"], rel=1e-10)
            assert p["error"] == pytest.approx(s["error"], rel=1e-10)
        cells, faces = np.array(par["cells"]), np.array(par["faces"])
        np.testing.assert_allclose(cells, np.array(serial["cells"]), atol=1e-15)
        np.testing.assert_array_equal(faces, np.array(serial["faces"]))
    assert serial["rows"][-1]["dofs"] > serial["rows"][0]["dofs"]
