"""Issue 29, items 6-13: the smaller defects a new user met."""
from __future__ import annotations

import json

import pytest

from conftest import run_cli
from mesh_files import t1_msh


def _solve(tmp_path, toml: str, *args: str):
    config = tmp_path / "c.toml"
    config.write_text(toml)
    out = tmp_path / "out"
    proc = run_cli("solve", str(config), "--out", str(out), *args)
    assert proc.returncode == 0, proc.stderr
    return proc, json.loads((out / "summary.json").read_text())


def test_an_unnamed_physical_group_is_given_by_its_number_without_warning(tmp_path):
    """Items 6 and 7: gmsh's t1.geo names its curve group 5 by number only; it covers 88 %
    of Gamma, but a group has no ends to swap."""
    t1_msh(tmp_path / "t1.msh")
    toml = '[geometry]\nmesh = "t1.msh"\nsubdomain_size = 0.05\nsignorini = [5]\n'
    toml += '[data]\nf = "1"\nt0 = "-1"\n[output]\nplots = false\nxdmf = false\n'
    proc, summary = _solve(tmp_path, toml)
    assert summary["signorini_lengths"] == pytest.approx([0.7])
    assert "warning" not in proc.stderr, proc.stderr


def test_the_printed_length_of_all_is_the_whole_boundary(tmp_path):
    """Item 8: "all" is closed: its printed length includes the closing segment."""
    toml = '[geometry]\nh = 0.0625\nsubdomain_size = 0.125\nsignorini = "all"\n'
    toml += "[output]\nplots = false\nxdmf = false\n"
    proc, summary = _solve(tmp_path, toml)
    assert summary["signorini_lengths"] == pytest.approx([2.0])
    assert "fembem: Signorini arcs of length 2\n" in proc.stdout + proc.stderr
