"""bench/elastic.py runs end to end at a small size (its figures are for people: no timing
is asserted): the elastic fembem solve and the linear elasticity pipeline on a mesh of the
same cells, one record each, in 2D and 3D."""
from __future__ import annotations

import json

import pytest

from conftest import run_bench


@pytest.mark.parametrize("dim, n, dofs", [(2, 8, 162), (3, 4, 375)])
def test_elastic_bench_small_run(tmp_path, dim, n, dofs):
    out = tmp_path / "elastic.json"
    proc = run_bench(
        "elastic.py", "--dim", str(dim), "--sizes", str(n), "--json", str(out), timeout=300
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    (row,) = json.loads(out.read_text())
    assert row["run"]["dofs"] == row["pipeline"]["dofs"] == dofs
    assert row["run"]["converged"] and row["pipeline"]["converged"]
    assert f"n = {n}: {dofs} dofs" in proc.stdout and "KB per dof" in proc.stdout
