"""fem_py under ``mpirun -n 2`` equals fem_py in serial (energy, residual and Jacobian
norms, coarse structure, boundary map), and the parallel global dof numbers point at the
right nodes. The parallel values come from tests/mpi/fem_parallel_check.py."""
from __future__ import annotations

import importlib.util
import json

import numpy as np
import pytest
from mpi4py import MPI

from conftest import ROOT, run_mpi

SCRIPT = ROOT / "tests" / "mpi" / "fem_parallel_check.py"


def _serial():
    spec = importlib.util.spec_from_file_location("fem_parallel_check", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.compute(MPI.COMM_SELF)


@pytest.mark.mpi
def test_serial_equals_two_ranks(tmp_path):
    out = tmp_path / "parallel.json"
    run_mpi(2, str(SCRIPT), str(out), timeout=240)
    par = json.loads(out.read_text())
    ser = _serial()
    assert set(par) == set(ser)
    for name in ser:
        s, p = ser[name], par[name]
        assert all(p["numbering_ok"].values()), (name, p["numbering_ok"])
        assert all(s["numbering_ok"].values()), (name, s["numbering_ok"])
        assert p["jacobian_check_passed"] and s["jacobian_check_passed"]
        # sums in a different order: agreement to round-off
        for key in (
            "energy",
            "residual_norm",
            "jacobian_norm_ufl",
            "jacobian_norm_handwritten",
            "load_norm",
            "stiffness_norm",
        ):
            assert p[key] == pytest.approx(s[key], rel=1e-12), (name, key)
        for key in (
            "n_dofs",
            "n_subdomains",
            "n_skeleton_facets",
            "vertex_on_boundary",
            "edge_vertices",
            "edge_arc",
            "edge_subdomains",
            "interior_per_subdomain",
            "signorini",
            "arc_of_signorini",
        ):
            assert p[key] == s[key], (name, key)
        # coordinates are recomputed from the distributed geometry: equal to round-off
        for key in ("vertex_coords", "boundary_nodes", "trace_u", "boundary_load"):
            assert np.allclose(p[key], s[key], rtol=1e-13, atol=1e-14), (name, key)
        assert all(
            np.allclose(a, b, atol=1e-14) for a, b in zip(p["edge_coords"], s["edge_coords"])
        )
