"""bench/placed_cells.py makes the same mesh both ways (create_mesh and placed cells) on one and two
ranks (its times are for people: none is asserted), and rejects bad arguments with one line."""
from __future__ import annotations

import pytest

from conftest import run_bench


@pytest.mark.mpi
def test_placed_cells_bench_makes_the_same_mesh_on_one_and_two_ranks():
    proc = run_bench("placed_cells.py", "--cells", "8", "--ranks", "1", "2", "--repeat", "1")
    assert proc.returncode == 0, proc.stderr
    rows = [line for line in proc.stdout.splitlines() if line.startswith("| 8 |")]
    assert len(rows) == 2
    for ranks, row in zip(("1", "2"), rows):
        cells = [c.strip() for c in row.split("|")[1:-1]]
        assert cells[1] == "128" and cells[2] == ranks  # 2 x 8 x 8 triangles
        for seconds in cells[3:5]:  # the fastest time of each path, in seconds
            assert seconds.endswith(" s") and float(seconds.removesuffix(" s")) >= 0
        # the cells, the ghost cells, the area and an integral agree on both meshes
        assert cells[6] == "yes"


@pytest.mark.parametrize(
    "args",
    [["--cells", "0"], ["--repeat", "0"], ["--ranks", "0"], ["--cells", "2", "--ranks", "3"]],
)
def test_placed_cells_bench_rejects_bad_arguments(args):
    proc = run_bench("placed_cells.py", *args)
    assert proc.returncode == 2
    assert proc.stderr.strip().startswith("error:") and len(proc.stderr.strip().splitlines()) == 1
