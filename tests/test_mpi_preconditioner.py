"""The distributed substructuring preconditioner (whole subdomains per rank) equals the
serial one to round-off, on 2 and 3 ranks (tests/mpi/distributed_preconditioner_check.py)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import ROOT, run_mpi
from fem_py.mesh.distribute import subdomain_owners
from fem_py.mesh.shapes import grid_partition

SCRIPT = str(ROOT / "tests" / "mpi" / "distributed_preconditioner_check.py")


@pytest.mark.mpi
@pytest.mark.parametrize("nprocs", [2, 3])
def test_distributed_equals_serial(tmp_path, nprocs):
    out = tmp_path / "report.json"
    run_mpi(nprocs, SCRIPT, str(out), timeout=300)
    report = json.loads(out.read_text())
    assert set(report) == {"square", "lshape-unstructured", "square-all"}
    for name, r in report.items():
        # the same operations summed in another order: agreement to a few ulps of the
        # largest entry (1e-13 allows the A_II and coarse solves' round-off)
        for key in ("apply", "matvec", "signorini"):
            assert r[key] <= 1e-13, (name, key, r[key])
        # C solved over the ranks, through its interface (another elimination order: the
        # same round-off bound, C being well conditioned at these sizes)
        assert r["coarse_factor"] == "InterfaceCoarseFactor", (name, r["coarse_factor"])
        # every rank owns whole subdomains, and all ranks have some
        assert sum(r["owned_subdomains"]) == r["subdomains"]
        assert min(r["owned_subdomains"]) > 0, (name, r["owned_subdomains"])


@pytest.mark.parametrize("nparts", [2, 3, 4, 7])
def test_subdomain_owners_balances_whole_subdomains(nparts):
    _, V, cells, _ = grid_partition("lshape", (0.5, 0.5), 1.0, 1 / 12)
    quads = np.array(cells)
    tris = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    subdomain = np.tile(np.arange(len(quads)), 2)
    owner = subdomain_owners(V, tris, subdomain, nparts)
    for s in range(len(quads)):
        assert np.unique(owner[subdomain == s]).size == 1
    cells_per_part = np.bincount(owner, minlength=nparts)
    # recursive bisection of whole subdomains: parts differ by at most a few subdomains
    assert cells_per_part.min() > 0
    assert cells_per_part.max() - cells_per_part.min() <= 2 * 2 * np.ceil(np.log2(nparts))
    np.testing.assert_array_equal(owner, subdomain_owners(V, tris, subdomain, nparts))


@pytest.mark.parametrize("ghosts", [[17, 3, 12], []])
def test_global_to_local_numbers(ghosts):
    """Owned numbers r0..r1-1 map to 0.., ghosts to r1-r0 + their place in ``ghosts``, any
    other number to -1, in the input's shape and with int32 input."""
    from coupling.preconditioners.distributed import _global_to_local

    to_local = _global_to_local(5, 10, np.array(ghosts, dtype=np.int64))
    g = np.array([[5, 9, 17, 3], [12, 4, 10, 0]], dtype=np.int32)
    expected = [[0, 4, 5, 6], [7, -1, -1, -1]] if ghosts else [[0, 4, -1, -1], [-1, -1, -1, -1]]
    assert to_local(g).tolist() == expected
    assert to_local(g[:, 1:3]).tolist() == [row[1:3] for row in expected]  # a strided view


@pytest.mark.mpi
@pytest.mark.parametrize("nprocs", [2, 3])
def test_coarse_problem_over_the_ranks_equals_a_direct_solve(tmp_path, nprocs):
    out = tmp_path / "report.json"
    run_mpi(nprocs, str(ROOT / "tests" / "mpi" / "interface_coarse_check.py"), str(out))
    report = json.loads(out.read_text())
    # every vertex is inside exactly one rank's subdomains, or shared
    assert report["covered"] == report["vertices"]
    for r in report["ranks"]:
        assert r["factor"] == "InterfaceCoarseFactor"
        # past INTERFACE_COARSE_MAX_VERTICES shared vertices, C whole on every rank
        assert r["beyond_the_limit"] == "RedundantCoarseFactor"
        assert r["shared"] > 0 and r["inside"] > 0
        assert r["corners_local"] and r["zero_elsewhere"]
        # C's condition number is below 400 (Gershgorin: spectrum in [0.1, 36.1], at most
        # 12 couplings of at most 1.5 a row): both solves agree with the direct one to
        # 400 x round-off
        assert r["interface"] <= 1e-13, r
        assert r["redundant"] <= 1e-13, r
