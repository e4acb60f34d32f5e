"""bench/solid.py runs end to end at a small size (its figures are for people: no timing
is asserted): the fembem solve of the box and the 3D Poisson pipeline, one record each."""
from __future__ import annotations

import json

from conftest import run_bench


def test_solid_bench_small_run(tmp_path):
    out = tmp_path / "solid.json"
    proc = run_bench("solid.py", "--sizes", "4", "--json", str(out), timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    (row,) = json.loads(out.read_text())
    assert row["n"] == 4 and row["run"]["dofs"] == row["poisson"]["dofs"] == 125
    assert row["run"]["converged"] and row["peak_bytes"] > 0
    assert "n = 4: 125 dofs" in proc.stdout and "KB per dof" in proc.stdout
