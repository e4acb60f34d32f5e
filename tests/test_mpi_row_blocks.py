"""S_h held by rows across ranks (coupling.distributed.RowBlocks) equals the whole matrix:
its blocks, products and full() on 2 and 3 ranks (tests/mpi/row_blocks_check.py)."""
from __future__ import annotations

import json

import pytest

from conftest import ROOT, run_mpi

SCRIPT = str(ROOT / "tests" / "mpi" / "row_blocks_check.py")


@pytest.mark.mpi
@pytest.mark.parametrize("nprocs, counts", [(2, [3, 4]), (3, [2, 2, 3])])
def test_row_blocks_equal_the_whole_matrix(tmp_path, nprocs, counts):
    out = tmp_path / "report.json"
    run_mpi(nprocs, SCRIPT, str(out))
    report = json.loads(out.read_text())
    assert report["row_counts"] == counts  # rows [r n / P, (r + 1) n / P)
    assert report["rows_equal"] and report["product_within_roundoff"] and report["full_equal"]
    # a block of the wrong shape is refused on every rank with a line naming its rows
    assert all(
        e is not None and e.startswith(f"rank {r} must hold rows")
        for r, e in enumerate(report["errors"])
    )
