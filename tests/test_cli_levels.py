"""`fembem solve` with levels: adaptive (`[adapt] steps`) and nested (`[solver] nested`)
runs write one record per level into summary.json and levels.csv / levels.png; every
run reports the a posteriori estimator; bad combinations are refused with one line."""
from __future__ import annotations

import csv
import json

import pytest

from conftest import run_cli

CONFIG = """
[geometry]
shape = "lshape"
h = 0.015625
subdomain_size = 0.0625
signorini = ["bottom"]
[material]
rho = "carstensen"
[data]
f = "1 + x"
t0 = "-1"
u0 = "0.1"
"""


@pytest.fixture
def config(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text(CONFIG)
    return path


def test_adaptive_run_writes_its_levels(config, tmp_path):
    out = tmp_path / "out"
    proc = run_cli("solve", str(config), "--out", str(out), "--quiet", "--set", "adapt.steps=2")
    assert proc.returncode == 0, proc.stderr
    summary = json.loads((out / "summary.json").read_text())
    levels = summary["levels"]
    assert len(levels) == 3
    dofs = [lv["dofs"] for lv in levels]
    assert dofs == sorted(dofs) and dofs[0] < dofs[-1]
    assert all(lv["converged"] for lv in levels)
    assert summary["dofs"] == dofs[-1] and summary["estimator"] == levels[-1]["estimator"]
    assert levels[-1]["estimator"] < levels[0]["estimator"]
    with open(out / "levels.csv") as f:
        rows = list(csv.DictReader(f))
    assert [int(r["dofs"]) for r in rows] == dofs
    assert {"levels.csv", "levels.png"} <= set(summary["files"])


def test_every_run_reports_the_estimator(config, tmp_path):
    out = tmp_path / "out"
    assert run_cli("solve", str(config), "--out", str(out), "--quiet").returncode == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["estimator"] > 0 and "levels" not in summary
    assert not (out / "levels.csv").exists()


@pytest.mark.parametrize(
    "sets,fragment",
    [
        (["adapt.max_dofs=100"], "adapt.max_dofs = 100 is below the starting mesh's 833 dofs"),
        (["solver.nested=true"], "solver.nested = true and adapt.steps > 0 do not combine"),
    ],
)
def test_bad_level_settings_are_refused(config, tmp_path, sets, fragment):
    out = tmp_path / "out"
    args = [a for s in ["adapt.steps=2", *sets] for a in ("--set", s)]
    proc = run_cli("solve", str(config), "--out", str(out), *args)
    assert proc.returncode == 2
    (line,) = proc.stderr.strip().splitlines()
    assert fragment in line and not out.exists()
