"""The 3D H-matrix S_h distributed by rows over 2 ranks (the 2D HMatrix code, comm=...)
against the serial operator (tests/mpi/surface_steklov_check.py)."""
from __future__ import annotations

import numpy as np
import pytest

from conftest import ROOT, run_mpi

SCRIPT = str(ROOT / "tests" / "mpi" / "surface_steklov_check.py")


@pytest.mark.mpi
def test_distributed_surface_operator_equals_the_serial_one(tmp_path):
    out = tmp_path / "s.npz"
    run_mpi(2, SCRIPT, str(out), "3")
    d = np.load(out)
    # the same blocks cut to the ranks' rows: products differ by the order of the sums
    assert np.linalg.norm(d["y"] - d["y_serial"]) <= 1e-12 * np.linalg.norm(d["y_serial"])
    distributed, serial = d["iterations"]
    assert distributed == serial > 0
    assert d["same_everywhere"]
    assert np.all(d["bytes_per_rank"] < d["serial_bytes"])
    # W_h's block from the blocks of both ranks: every entry is one rank's, so exactly the
    # serial block; and the integrated block to the H-matrix tolerance (1e-10)
    assert np.array_equal(d["block"], d["block_serial"]) and len(d["block"]) > 100
    integrated = d["block_integrated"]
    assert np.linalg.norm(d["block"] - integrated) <= 1e-8 * np.linalg.norm(integrated)
    # in single precision (blocks held in single at tol 1e-5): summed over the ranks in
    # double, then rounded once, the serial block's entries to the bit
    assert d["single"].dtype == np.float32 and np.array_equal(d["single"], d["single_serial"])
    assert np.linalg.norm(d["single"] - integrated) <= 1e-5 * np.linalg.norm(integrated)
