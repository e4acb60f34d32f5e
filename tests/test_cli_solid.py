"""``fembem solve`` of a body in R^3 (docs/design/three_dimensions.md): summary.json and
fields.npz (x (N, 3), cells (M, 4), the surface fields on Gamma's triangles), the same
on 1 and 2 ranks, and bad 3D input refused in one line (exit 2, nothing written)."""
from __future__ import annotations

import json
import re

import numpy as np
import pytest

from conftest import run_cli, run_mpi
from solid_files import box_toml, solid_msh

BOX = box_toml("[0.0, 0.0, 0.0]", 0.5, 0.125, 'u0 = "0.02*x"\nexact = "0.02*x"')


def _solve(tmp_path, name, text, ranks=1):
    config = tmp_path / f"{name}.toml"
    config.write_text(text)
    out = tmp_path / name
    args = ("solve", str(config), "--out", str(out), "--quiet")
    if ranks == 1:
        proc = run_cli(*args)
    else:
        proc = run_mpi(ranks, "-m", "coupling.app.cli", *args, check=False)
    return proc, out


def _load(out):
    with np.load(out / "fields.npz") as data:
        return json.loads((out / "summary.json").read_text()), {k: data[k] for k in data.files}


@pytest.mark.mpi
def test_box_solve_writes_3d_fields_the_same_on_two_ranks(tmp_path):
    proc, out = _solve(tmp_path, "one", BOX)
    assert proc.returncode == 0, proc.stderr
    summary, f = _load(out)
    assert summary["converged"] and summary["iterations"] <= 15
    assert (summary["dofs"], summary["boundary_dofs"], summary["signorini_dofs"]) == (125, 98, 9)
    assert summary["contact_nodes"] == int(f["active"].sum()) == 9  # pressed flat
    assert summary["complementarity"] <= 1e-6 and np.isfinite(summary["error"])
    assert summary["config"]["solver"]["preconditioner"] == "auto"
    assert summary["preconditioner"] == "amg"  # what "auto" is for a body
    assert summary["signorini_areas"] == pytest.approx([0.25])
    pngs = {"signorini.png", "surface.png", "slice.png", "history.png"}
    data = {"summary.json", "fields.npz", "solution.xdmf", "solution.h5"}
    assert set(summary["files"]) == data | pngs
    assert f["x"].shape == (125, 3) and f["cells"].shape == (6 * 4**3, 4)
    n = 98
    assert f["boundary_x"].shape == (n, 3) and f["boundary_triangles"].shape == (12 * 4**2, 3)
    for key in ("boundary_u", "phi", "ue", "pressure", "dn_ue", "active", "signorini"):
        assert f[key].shape == (n,), key
    # the fields agree with each other: u_e = u + phi - u0 on Gamma, phi >= 0 on Gamma_s
    # and 0 elsewhere, contact only on Gamma_s, the boundary nodes among the mesh nodes
    u0 = 0.02 * f["boundary_x"][:, 0]
    assert np.abs(f["ue"] - (f["boundary_u"] + f["phi"] - u0)).max() <= 1e-12
    assert np.all(f["phi"][f["signorini"]] >= 0) and np.all(f["phi"][~f["signorini"]] == 0)
    assert not np.any(f["active"] & ~f["signorini"])
    assert np.all(np.isin(f["boundary_x"][:, 2], f["x"][:, 2]))
    # solution.xdmf: u_h, the named faces and the boundary fields, for ParaView
    xdmf = (out / "solution.xdmf").read_text()
    for name in ("u", "faces", "gap", "ue", "pressure", "contact"):
        assert f'Attribute Name="{name}"' in xdmf, name
    # fembem evaluate at x,y,z points: a node inside (u_h there), a boundary node (both
    # traces), points outside (u_e by the representation formula)
    inside = int(np.flatnonzero(np.all(np.abs(f["x"]) < 0.2, axis=1))[0])
    node = int(np.flatnonzero(f["signorini"])[0])
    foot = f["boundary_x"][node]
    points = tmp_path / "points.csv"
    rows = [f["x"][inside], foot, foot - [0.0, 0.0, 1e-4], [1.0, 2.0, 3.0]]
    points.write_text("x,y,z\n" + "".join(",".join(repr(float(v)) for v in p) + "\n" for p in rows))
    proc = run_cli("evaluate", str(out), "--points", str(points))
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert lines[0] == "x,y,z,where,u,ue"
    table = [line.split(",") for line in lines[1:]]
    assert [r[3] for r in table] == ["inside", "boundary", "outside", "outside"]
    assert float(table[0][4]) == pytest.approx(f["u"][inside], abs=1e-14)
    assert float(table[1][4]) == pytest.approx(f["boundary_u"][node], abs=1e-14)
    assert float(table[1][5]) == pytest.approx(f["ue"][node], abs=1e-14)
    # u_e is continuous across Gamma: 1e-4 below the bottom face the representation formula
    # differs from the discrete trace by d du_e/dn (7e-6) plus the residual of the
    # discrete boundary integral equation there, O(h^2): measured 6e-4 .. 1.4e-3 at the
    # first four Signorini nodes, h = 1/8 (5e-5 on the smooth top face)
    assert abs(float(table[2][5]) - f["ue"][node]) <= 3e-3
    proc = run_cli("exterior", str(out), "--points", str(points))
    lines = proc.stderr.strip().splitlines()  # the first point is inside: one line
    assert proc.returncode == 2 and len(lines) == 1 and "inside Omega or on Gamma" in lines[0]
    points.write_text("1.0,2.0,3.0\n")
    proc = run_cli("exterior", str(out), "--points", str(points))
    assert proc.returncode == 0 and proc.stdout.splitlines()[1].split(",")[3] == table[3][5]
    points.write_text("1.0,2.0\n")  # x,y rows for a 3D result
    proc = run_cli("evaluate", str(out), "--points", str(points))
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1 and "three finite numbers x,y,z" in lines[0]
    # two ranks: the same run
    proc, out2 = _solve(tmp_path, "two", BOX, ranks=2)
    assert proc.returncode == 0, proc.stderr
    summary2, f2 = _load(out2)
    assert summary2["iterations"] == summary["iterations"] and summary2["mpi_ranks"] == 2
    assert np.array_equal(f2["cells"], f["cells"]) and np.array_equal(f2["active"], f["active"])
    for key in ("x", "u", "phi", "ue"):
        assert np.abs(f2[key] - f[key]).max() <= 1e-10 * np.abs(f[key]).max(), key


@pytest.mark.parametrize(
    "kind, order, signorini, message",
    [
        ("box", 2, '["bottom"]', "Tetrahedron 10"),
        ("surface", 1, '["bottom"]', "surface mesh only"),
        ("cavity", 1, '["bottom"]', "1 cavity"),
        ("two", 1, '["bottom"]', "2 separate bodies"),
        ("box", 1, '["contact"]', "no physical surface group 'contact'"),
        ("box", 1, '["omega"]', "'omega' .* is a volume, not a surface"),
    ],
)
def test_bad_3d_files_are_one_line(tmp_path, kind, order, signorini, message):
    path = solid_msh(tmp_path / f"{kind}.msh", kind, h=0.5, order=order)
    text = f'[geometry]\nmesh = "{path}"\nsignorini = {signorini}\n'
    proc, out = _solve(tmp_path, "bad", text)
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and not out.exists(), proc.stderr
    assert len(lines) == 1 and re.search(message, lines[0]), lines


@pytest.mark.parametrize(
    "extra, message",
    [
        ('[solver]\npreconditioner = "substructuring"\n', "solver.preconditioner"),
    ],
)
def test_planar_options_of_a_body_are_one_line(tmp_path, extra, message):
    proc, out = _solve(tmp_path, "bad", BOX + extra)
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and not out.exists(), proc.stderr
    assert len(lines) == 1 and message in lines[0], lines


def test_a_body_that_cannot_fit_is_refused_before_it_is_built(tmp_path):
    # 400 cubes per side: 6.4e7 dofs, 9.6e5 on Gamma; the 3D estimate (coupling.app.sizing)
    # is about 267 GB, refused from the closed-form sizes before any mesh
    proc, out = _solve(tmp_path, "huge", BOX.replace("h = 0.125", "h = 0.00125"))
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and not out.exists(), proc.stderr
    assert len(lines) == 1 and "6.45e+07 dofs, 9.6e+05 on Gamma" in lines[0], lines


def test_nested_solve_of_a_box_writes_its_levels(tmp_path):
    # 20 cubes per side (9,261 dofs) from 10 (1,331): 5 (216 dofs) is too few for a
    # level at 4 h (NESTED_COARSENING_3D)
    proc, out = _solve(tmp_path, "nested", BOX.replace("h = 0.125", "h = 0.025"))
    assert proc.returncode == 0, proc.stderr
    summary, _ = _load(out)
    assert [level["dofs"] for level in summary["levels"]] == [11**3, 21**3]
    assert summary["converged"] and "levels.csv" in summary["files"]
    assert summary["iterations"] <= 5  # from the prolonged coarse solution


def test_adaptive_solve_of_a_box_writes_its_levels_and_indicators(tmp_path):
    """[adapt] and [output] indicators for a body (refused before issue 67): adapt.csv,
    adapt.png, mesh.png, and eta_T per tetrahedron in fields.npz."""
    extra = "[adapt]\nsteps = 1\ntheta = 0.3\n\n[output]\nindicators = true\n"
    proc, out = _solve(tmp_path, "adapt", BOX + extra)
    assert proc.returncode == 0, proc.stderr
    summary, fields = _load(out)
    assert {"adapt.csv", "adapt.png", "mesh.png"} <= set(summary["files"])
    levels = summary["levels"]
    assert len(levels) == 2 and levels[1]["dofs"] > levels[0]["dofs"] == 125
    assert summary["estimator"] == levels[-1]["estimator"] > 0
    assert fields["indicators"].shape == (len(fields["cells"]),) == (levels[-1]["cells"],)
    assert np.sum(fields["indicators"] ** 2) == pytest.approx(summary["estimator"] ** 2, rel=1e-12)
    assert (out / "adapt.csv").read_text().count("\n") == 3


def test_estimator_of_a_plain_box_solve(tmp_path):
    proc, out = _solve(tmp_path, "estimate", BOX + "[output]\nestimator = true\n")
    assert proc.returncode == 0, proc.stderr
    summary, _ = _load(out)
    assert summary["estimator"] > 0 and "levels" not in summary
