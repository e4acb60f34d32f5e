"""bench/direct_topology.py builds its probe and makes the same mesh both ways (its times
are for people: none is asserted), and rejects bad arguments with one line."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

from conftest import ROOT

SCRIPT = str(ROOT / "bench" / "direct_topology.py")


def test_direct_topology_makes_the_same_mesh():
    proc = subprocess.run(
        [sys.executable, SCRIPT, "--cells", "8", "--repeat", "1"],
        capture_output=True,
        text=True,
        timeout=600,
        cwd=ROOT,
        env=dict(os.environ),
    )
    assert proc.returncode == 0, proc.stderr
    row = [line for line in proc.stdout.splitlines() if line.startswith("| 8 |")]
    assert len(row) == 1
    cells = [c.strip() for c in row[0].split("|")[1:-1]]
    assert cells[1] == "128"  # 2 x 8 x 8 triangles
    for seconds in cells[2:4]:  # the fastest time of each path, in seconds
        assert seconds.endswith(" s") and float(seconds.removesuffix(" s")) >= 0
    assert cells[5] == "yes"  # area and integral equal to round-off on both meshes


@pytest.mark.parametrize("args", [["--cells", "0"], ["--repeat", "0"]])
def test_direct_topology_rejects_bad_arguments(args):
    proc = subprocess.run([sys.executable, SCRIPT, *args], capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 2
    assert proc.stderr.strip().startswith("error:") and len(proc.stderr.strip().splitlines()) == 1
