"""``fembem solve`` of the elastic problem (docs/guide/elasticity.md): summary.json (the
equation, the net force, the complementarity of the normal gap and traction), fields.npz
with vector fields, solution.xdmf with u_h as a vector, the figures (deformed.png,
signorini.png, exterior.png, history.png), the same on 1 and 2 ranks, the plane and the
box; bad elastic input refused in one line (exit 2, nothing written)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import points_table, run_cli, run_mpi

SQUARE = """[problem]
equation = "elasticity"

[geometry]
shape = "square"
h = 0.0625
subdomain_size = 0.125
signorini = ["bottom"]

[material]
model = "hencky"
bulk = 2.0
shear = "1 + 1/(1 + s)"

[exterior]
E = 1.5
nu = 0.3

[data]
f = ["1", "0"]
u0 = ["0", "0.05*x"]
a = [0.0, -0.01]
"""

BOX = """[problem]
equation = "elasticity"
tangential = "stick"

[geometry]
shape = "box"
width = 0.5
h = 0.125
signorini = ["bottom"]

[material]
model = "linear-elastic"
E = 2.5
nu = 0.25

[data]
f = ["1", "0", "0"]
u0 = ["0", "0", "0.05*x"]
"""


def _solve(tmp_path, name, text, ranks=1, *extra):
    config = tmp_path / f"{name}.toml"
    config.write_text(text)
    out = tmp_path / name
    args = ("solve", str(config), "--out", str(out), "--quiet", *extra)
    if ranks == 1:
        return run_cli(*args), out
    return run_mpi(ranks, "-m", "coupling.app.cli", *args, check=False), out


#: The figures of an elastic run (coupling.io.elastic_figure_data.ELASTIC_PLOT_FILES).
FIGURES = ("deformed.png", "signorini.png", "exterior.png", "history.png")


def _png_size(path) -> tuple[int, int]:
    """(width, height) in pixels of a PNG file, from its IHDR chunk."""
    head = path.read_bytes()[:24]
    assert head[:8] == b"\x89PNG\r\n\x1a\n" and head[12:16] == b"IHDR", path.name
    return int.from_bytes(head[16:20], "big"), int.from_bytes(head[20:24], "big")


def _check_figures(out, summary):
    """The four figures are listed in summary.json, written, and of a sane size."""
    assert set(FIGURES) <= set(summary["files"])
    for name in FIGURES:
        size = (out / name).stat().st_size
        assert 10_000 < size < 2_000_000, (name, size)
        width, height = _png_size(out / name)
        assert 400 <= width <= 2000 and 300 <= height <= 1500, (name, width, height)


def _load(out):
    with np.load(out / "fields.npz") as data:
        return json.loads((out / "summary.json").read_text()), {k: data[k] for k in data.files}


@pytest.mark.mpi
@pytest.mark.parametrize("text, d", [(SQUARE, 2), (BOX, 3)])
def test_elastic_solve_writes_vector_fields_the_same_on_two_ranks(tmp_path, text, d):
    proc, out = _solve(tmp_path, "one", text)
    assert proc.returncode == 0, proc.stderr
    summary, f = _load(out)
    assert summary["equation"] == "elasticity" and summary["converged"]
    assert summary["preconditioner"] == "amg"
    n, m = f["x"].shape[0], f["boundary_x"].shape[0]
    assert f["u"].shape == f["x"].shape == (n, d) and summary["dofs"] == d * n
    for key in ("ue", "jump", "traction", "boundary_u", "dn_ue"):
        assert f[key].shape == (m, d), key
    for key in ("phi", "pressure", "active", "signorini"):
        assert f[key].shape == (m,), key
    s = f["signorini"]
    assert 0 < f["active"].sum() < s.sum()  # the bottom partly open (u0 tilts it)
    assert summary["contact_nodes"] == int(f["active"].sum())
    assert summary["complementarity"] <= 1e-6
    assert np.all(f["phi"][s] >= 0)  # and the pressure <= 0 as complementarity measures
    # the net force on the medium balances the body's load: f = e_1 on a body of volume
    # 1/4 (square) or 1/8 (box), no t0. The balance is K_h r = -M_h r for the translations
    # r: round-off in 2D, the Sauter-Schwab rules' accuracy in 3D (the sum of K_h r + M_h r
    # is 2.2e-6 of that of M_h r on this box; the force is off by 1.0e-6 relative)
    load = np.zeros(d)
    load[0] = 0.25 if d == 2 else 0.125
    assert np.allclose(summary["force"], load, rtol=0, atol=(1e-9 if d == 2 else 3e-6) * load[0])
    _check_figures(out, summary)
    assert "figure process failed" not in proc.stderr  # drawn by the figure process
    xdmf = (out / "solution.xdmf").read_text()
    assert '<Attribute Name="u" AttributeType="Vector" Center="Node">' in xdmf
    assert f'Dimensions="{n} 3"' in xdmf
    proc, two = _solve(tmp_path, "two", text, 2)
    assert proc.returncode == 0, proc.stderr
    summary2, f2 = _load(two)
    _check_figures(two, summary2)
    assert "figure process failed" not in proc.stderr
    assert summary2["iterations"] == summary["iterations"]
    for key in ("u", "ue", "phi", "pressure"):
        assert np.allclose(f2[key], f[key], rtol=0, atol=1e-9 * np.abs(f[key]).max()), key


def test_a_rerun_without_plots_removes_the_elastic_figures(tmp_path):
    proc, out = _solve(tmp_path, "run", SQUARE)
    assert proc.returncode == 0, proc.stderr
    assert all((out / name).is_file() for name in FIGURES)
    proc, out = _solve(tmp_path, "run", SQUARE, 1, "--force", "--set", "output.plots=false")
    assert proc.returncode == 0, proc.stderr
    summary, _ = _load(out)
    assert not any((out / name).exists() for name in FIGURES)
    assert not any(name.endswith(".png") for name in summary["files"])


@pytest.mark.parametrize(
    "change, message",
    [
        ('data.f=["0", "-1", "2"]', "data.f has 3 components; a 2D displacement has 2"),
        ('data.u0=["0"]', "data.u0 must be a vector of 2 or 3 expressions"),
        ("data.f=1", "data.f must be a vector for elasticity"),
        ("material.rho=carstensen", "material.rho belongs to the scalar equation"),
        ("material.E=2", 'material.E is not a key of model "hencky"'),
        ("material.bulk=0", "material.bulk must be positive"),
        ("material.shear=1/(1 + s)^3", "not strictly increasing"),
        ("exterior.nu=0.5", "exterior.nu (Poisson's ratio) must lie in (-1, 1/2)"),
        ("problem.tangential=glue", 'problem.tangential must be one of "slip", "stick"'),
        ("solver.preconditioner=substructuring", "a preconditioner of the scalar equation"),
        ("adapt.steps=2", "adaptivity is for the scalar equation so far"),
        ("problem.equation=scalar", "of elasticity; set problem.equation"),
    ],
)
def test_bad_elastic_input_is_refused_in_one_line(tmp_path, change, message):
    proc, out = _solve(tmp_path, "bad", SQUARE, 1, "--set", change)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], proc.stderr
    assert not out.exists()


def test_a_plane_boundary_too_large_for_the_elastic_single_layer_is_refused(tmp_path):
    """In 2D the elastic V_h is definite only on a small enough boundary (docs/method.md
    section 12): a square of side 8 is refused with the factor to scale it by."""
    text = SQUARE.replace("h = 0.0625", "h = 1.0\nwidth = 8.0\nallow_large = true").replace(
        "subdomain_size = 0.125", "subdomain_size = 2.0"
    )
    proc, out = _solve(tmp_path, "large", text)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert "not positive definite" in lines[-1] and "scale the geometry by a factor" in lines[-1]


@pytest.mark.parametrize(
    "text",
    [
        SQUARE,
        BOX.replace(
            'model = "linear-elastic"\nE = 2.5\nnu = 0.25',
            'model = "hencky"\nbulk = 1.5\nshear = "0.5 + 1/(1 + s^2)"',
        ),
    ],
)
def test_check_jacobian_compares_the_elastic_jacobians(tmp_path, text):
    """The hand-written tangent D sigma of a Hencky body equals the UFL-derived one (to
    round-off: 1.5e-16 measured) and the residual's Taylor remainders fall like eps and
    eps^2 (slopes 1.00 and 1.98-2.00 measured)."""
    config = tmp_path / "c.toml"
    config.write_text(text)
    proc = run_cli("check-jacobian", str(config), "--json")
    assert proc.returncode == 0, proc.stderr
    report = json.loads(proc.stdout)
    assert report["material"] == "hencky" and report["passed"]
    assert report["matrix_rel_diff"] <= 1e-13
    assert all(abs(s - 2.0) <= 0.1 for s in report["slope2"])
    assert all(abs(s - 1.0) <= 0.01 for s in report["slope1"])


def test_evaluate_and_exterior_give_the_displacement_components(tmp_path):
    """``fembem evaluate`` of an elastic run: u_x, u_y inside and on Gamma, the trace of u_e
    on Gamma (u_e = u - u0 on Gamma_t) and outside by Somigliana's identity, which tends to
    the trace as the point nears Gamma; ``fembem exterior``: u_e and the medium's stress."""
    proc, out = _solve(tmp_path, "run", SQUARE)
    assert proc.returncode == 0, proc.stderr
    points = "x,y\n0,0\n0.25,0.1\n0.2501,0.1\n0.6,0.3\n"
    lines = points_table("evaluate", out, tmp_path / "points.csv", points)
    assert lines[0] == "x,y,where,u_x,u_y,ue_x,ue_y,sigma_xx,sigma_yy,sigma_xy"
    rows = [line.split(",") for line in lines[1:]]
    assert [r[2] for r in rows] == ["inside", "boundary", "outside", "outside"]
    assert rows[0][5:7] == ["", ""] and rows[2][3:5] == ["", ""]
    # the stress: the body's inside, none on Gamma (two sides), the medium's outside
    assert np.isfinite(np.array(rows[0][7:], float)).all() and rows[1][7:] == ["", "", ""]
    u, ue = np.array(rows[1][3:5], float), np.array(rows[1][5:7], float)
    assert np.allclose(ue, u - [0.0, 0.05 * 0.25], atol=1e-12)  # u0 = (0, 0.05 x) on Gamma_t
    near = np.array(rows[2][5:7], float)
    assert np.abs(near - ue).max() <= 1e-2 * np.abs(ue).max()  # 1e-4 outside the trace
    lines = points_table("exterior", out, tmp_path / "outside.csv", "0.6,0.3\n-0.5,0.2\n")
    assert lines[0] == "x,y,ue_x,ue_y,sigma_xx,sigma_yy,sigma_xy"
    first = np.array(lines[1].split(",")[2:], float)
    assert np.allclose(first, np.array(rows[3][5:], float), rtol=1e-12)  # u_e and sigma
    assert all(np.isfinite(np.array(line.split(","), float)).all() for line in lines[1:])


@pytest.mark.parametrize("d", [2, 3])
def test_the_body_stress_of_an_affine_displacement_is_hookes(tmp_path, d):
    """``evaluate``'s stress inside the body: for u = G x (every P1 cell the same strain)
    and a linear elastic body, sigma = lambda tr(eps) I + 2 mu eps with Lame's lambda, mu
    of E, nu (textbook formulas, not the code's bulk and deviatoric split), to round-off."""
    from coupling.app.from_config import run_material
    from coupling.io.evaluation import evaluate
    from coupling.io.outputs import load_fields

    text = BOX if d == 3 else SQUARE.replace('model = "hencky"', 'model = "linear-elastic"')
    text = text.replace('bulk = 2.0\nshear = "1 + 1/(1 + s)"', "E = 2.5\nnu = 0.25")
    proc, out = _solve(tmp_path, "run", text, 1, "--set", "output.plots=false")
    assert proc.returncode == 0, proc.stderr
    fields = dict(load_fields(out))
    G = np.arange(1.0, d * d + 1).reshape(d, d) / 10 - 0.3
    fields["u"] = fields["x"] @ G.T
    points = np.full((2, d), 0.05)
    points[1, 0] = -0.1
    sigma = evaluate(fields, points, run_material(out, d))["sigma"]
    E, nu = 2.5, 0.25
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    eps = 0.5 * (G + G.T)
    hooke = lam * np.trace(eps) * np.eye(d) + 2 * mu * eps
    assert np.abs(sigma - hooke).max() <= 1e-13 * np.abs(hooke).max()


def test_info_counts_the_elastic_unknowns_as_the_run_does(tmp_path):
    """``fembem info``: d dofs per node, d gap unknowns per Signorini node with "slip", the
    amg preconditioner; the counts of the run itself."""
    config = tmp_path / "c.toml"
    config.write_text(SQUARE)
    proc = run_cli("info", str(config), "--json")
    assert proc.returncode == 0, proc.stderr
    report = json.loads(proc.stdout)
    proc, out = _solve(tmp_path, "run", SQUARE)
    summary = json.loads((out / "summary.json").read_text())
    assert report["equation"] == "elasticity" and report["preconditioner"] == "amg"
    for key in ("dofs", "boundary_dofs", "signorini_dofs"):
        assert report[key] == summary[key], key
