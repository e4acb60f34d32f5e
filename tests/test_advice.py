"""Warnings for valid but suspicious inputs (materials, Signorini arcs), and the message
for a material name that is not one."""
from __future__ import annotations

from types import SimpleNamespace

from conftest import run_cli
from coupling.app.advice import arc_warnings, material_warnings
from fem_py.forms import make_material

DATA = '[data]\nf = "1"\nt0 = "-1"\n'


def test_material_warnings():
    assert material_warnings(make_material("carstensen")) == []
    assert material_warnings(make_material("linear")) == []
    (line,) = material_warnings(SimpleNamespace(alpha=1e-7, beta=1.0))
    assert "alpha = 1e-07" in line and "ill-conditioned" in line
    (line,) = material_warnings(make_material("1 + 2000*t"))
    assert "beta/alpha" in line and "iteration counts" in line


def test_arc_warnings():
    assert arc_warnings([0.5, 0.25], [False, False], 2.0) == []
    assert arc_warnings([2.0], [True], 2.0) == []  # signorini = "all"
    (line,) = arc_warnings([0.25, 1.5], [False, False], 2.0)
    assert line.startswith("geometry.signorini[1]: the arc covers 75% of Gamma")


def test_cli_names_the_materials_and_warns_about_a_long_arc(tmp_path):
    config = tmp_path / "c.toml"
    config.write_text('[material]\nrho = "Carstensen"\n')
    proc = run_cli("solve", str(config), "--out", str(tmp_path / "a"))
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [
        "fembem: error: material.rho: unknown material 'Carstensen'; the named materials are "
        "linear, carstensen, power (lower case), or give rho(t) as an expression in t, e.g. "
        '"2 + 1/(1+t)"'
    ]
    config.write_text(
        DATA + "[geometry]\nh = 0.0625\nsignorini = [[[-0.25, 0.25], [0.25, 0.25]]]\n"
    )
    proc = run_cli("solve", str(config), "--out", str(tmp_path / "b"), "--quiet")
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr.startswith("fembem: warning: geometry.signorini[0]: the arc covers 75%")
    config.write_text(
        DATA + "[geometry]\nh = 0.0625\nsignorini = [[[0.25, 0.25], [-0.25, 0.25]]]\n"
    )
    proc = run_cli("solve", str(config), "--out", str(tmp_path / "c"))
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr
    assert "Signorini arcs of length 0.5" in proc.stdout
    assert "material linear: alpha = 1, beta = 1" in proc.stdout
