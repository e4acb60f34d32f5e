"""The command line `fembem`, run as a subprocess: outputs, exit codes, errors, MPI.

The solve tests use a manufactured problem written entirely in the configuration
language (so the CLI alone can state it): the Carstensen material, the square
[-1/4, 1/4]^2 with the bottom side as Signorini arc, and

    u   = 0.2 + 3x + y + x^2,   grad u = (3 + 2x, 1),   G = |grad u| = sqrt((3 + 2x)^2 + 1)
    u_e = a + 0.1 log|x - x0|^2 + c.(x - x0)/|x - x0|^2,   a = 0.5, x0 = (0.03, -0.02),
          c = (0.05, -0.03)
    f   = -div(rho(G) grad u) = -(2 rho(G) + rho'(G) 2 (3 + 2x)^2 / G),  rho' = -1/(1 + G)^2
    t0  = rho(G) du/dn - du_e/dn,   u0 = u - u_e   (gap 0 on all of Gamma).

On the bottom side rho du/dn = -rho(G) < 0, so the exact contact set is the whole arc:
every Signorini node must end in contact. The errors are those of the discretisation;
measured at h = 1/16, 1/32, 1/64 they fall like h^2 (u_e at exterior points: max
0.095 h^2; u at the nodes: 0.29 h^2), so the bounds below are 0.15 h^2 and 0.45 h^2.
"""
from __future__ import annotations

import importlib.util
import json
import math
import re
import shutil
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

from conftest import ROOT, json_report, run_cli, run_mpi
from coupling.options import DEFAULTS

H = 1 / 32
FEMBEM = str(Path(sys.executable).parent / "fembem")

_G = "sqrt((3 + 2*x)^2 + 1)"
_RHO = f"(2 + 1/(1 + {_G}))"
_RX, _RY = "(x - 0.03)", "(y + 0.02)"
_R2 = f"({_RX}^2 + {_RY}^2)"
_DIP = f"(0.05*{_RX} - 0.03*{_RY})"
UE = f"0.5 + 0.1*log({_R2}) + {_DIP}/{_R2}"
_UE_X = f"(0.2*{_RX}/{_R2} + 0.05/{_R2} - 2*{_DIP}*{_RX}/{_R2}^2)"
_UE_Y = f"(0.2*{_RY}/{_R2} - 0.03/{_R2} - 2*{_DIP}*{_RY}/{_R2}^2)"
U = "0.2 + 3*x + y + x^2"

MANUFACTURED_TOML = f"""\
[geometry]
h = {H}
subdomain_size = {4 * H}
signorini = ["bottom"]

[material]
rho = "carstensen"

[data]
a = 0.5
f = "-(2*{_RHO} - 2*(3 + 2*x)^2/({_G}*(1 + {_G})^2))"
u0 = "{U} - ({UE})"
t0 = "{_RHO}*((3 + 2*x)*nx + ny) - nx*{_UE_X} - ny*{_UE_Y}"
"""

#: Exterior points: far, near a corner, and 1e-4 (h/300) below the Signorini side.
EXTERIOR_POINTS = np.array([[0.6, 0.0], [0.0, 0.6], [-0.3, 0.3], [0.26, -0.26], [0.0, -0.2501]])


def exact(expression: str, points: np.ndarray) -> np.ndarray:
    from fem_py.forms import numpy_function

    return numpy_function(expression, ("x", "y"))(points[:, 0], points[:, 1])


def assert_bad_input(proc, *fragments: str) -> str:
    """Exit code 2 and exactly one line on stderr, naming what is wrong; no traceback."""
    assert proc.returncode == 2, (proc.returncode, proc.stdout, proc.stderr)
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("fembem: error: "), proc.stderr
    for fragment in fragments:
        assert fragment in lines[0], (fragment, lines[0])
    return lines[0]


@pytest.fixture(scope="module")
def config(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("config") / "manufactured.toml"
    path.write_text(MANUFACTURED_TOML)
    return path


@pytest.fixture(scope="module")
def run(config, tmp_path_factory):
    """One serial `fembem solve` of the manufactured problem with every output on."""
    out = tmp_path_factory.mktemp("run") / "out"
    proc = run_cli("solve", str(config), "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    return out, proc


# ----------------------------------------------------------------------- outputs
def test_solve_writes_the_documented_outputs(run):
    out, proc = run
    summary = json.loads((out / "summary.json").read_text())
    for key in (
        "converged",
        "reason",
        "iterations",
        "energy",
        "dofs",
        "boundary_dofs",
        "signorini_dofs",
        "contact_nodes",
        "tau",
        "C0_estimate",
        "timings",
        "history",
    ):
        assert key in summary, key
    n = round(0.5 / H)
    assert summary["converged"] and summary["dofs"] == (n + 1) ** 2
    assert summary["boundary_dofs"] == 4 * n and summary["signorini_dofs"] == n - 1
    # the mesh facts (issue 17): 4 x 4 coarse squares of side 4h, right triangles of legs h
    assert summary["subdomains"] == 16
    assert summary["subdomain_diameter"] == pytest.approx(math.sqrt(2) * 4 * H, rel=1e-12)
    assert summary["h_min"] == pytest.approx(H) and summary["h_max"] == pytest.approx(
        math.sqrt(2) * H
    )
    assert summary["signorini_lengths"] == pytest.approx([0.5])
    assert "16 subdomains of mean diameter 0.1768, h from 0.03125 to 0.04419" in proc.stdout
    assert len(summary["history"]) == summary["iterations"]
    assert summary["config"]["material"]["rho"] == "carstensen"
    assert summary["preconditioner"] == "substructuring"  # "auto" in the plane
    for name in (
        "fields.npz",
        "solution.xdmf",
        "solution.h5",
        "u.png",
        "boundary.png",
        "whole_plane.png",
        "history.png",
    ):
        assert (out / name).is_file(), name
        assert name in summary["files"]
    for name in ("u.png", "boundary.png", "whole_plane.png", "history.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not [p.name for p in out.iterdir() if p.name.startswith(".")]  # no temporaries

    # progress: the first iteration and every 25th, with energy, step and contact size
    progress = [ln for ln in proc.stdout.splitlines() if ln.lstrip().startswith("it ")]
    assert len(progress) == 1 + summary["iterations"] // 25
    assert re.search(r"J_h = \S+ +step = \S+ +contact = \d+", progress[0])
    assert "converged" in proc.stdout.splitlines()[-1]

    f = np.load(out / "fields.npz")
    nodes = f["boundary_x"]
    n_gamma = len(nodes)
    assert n_gamma == summary["boundary_dofs"]
    x, y = nodes.T
    assert np.isclose(0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y), 0.25)  # CCW
    for key in ("boundary_u", "phi", "ue", "dn_ue", "active", "signorini"):
        assert f[key].shape == (n_gamma,), key
    assert f["active"].dtype == bool and f["signorini"].sum() == summary["signorini_dofs"]
    assert summary["contact_nodes"] == f["active"].sum()
    assert not (f["active"] & ~f["signorini"]).any()
    assert np.all(f["phi"] >= 0) and np.all(f["phi"][~f["signorini"]] == 0)
    np.testing.assert_array_equal(f["active"], f["signorini"] & (f["phi"] == 0))
    # u_e = u + phi - u0 on Gamma, and boundary_u is u at the boundary nodes
    np.testing.assert_allclose(
        f["ue"], f["boundary_u"] + f["phi"] - exact(f"{U} - ({UE})", nodes), atol=1e-13
    )
    index = {tuple(p): i for i, p in enumerate(np.round(f["x"], 12))}
    at_nodes = [index[tuple(p)] for p in np.round(nodes, 12)]
    np.testing.assert_array_equal(f["u"][at_nodes], f["boundary_u"])


def test_solution_and_exterior_command_match_the_manufactured_solution(run, tmp_path):
    out, _ = run
    f = np.load(out / "fields.npz")
    assert np.abs(f["u"] - exact(U, f["x"])).max() <= 0.45 * H**2
    assert f["active"][f["signorini"]].all()  # the exact contact set is the whole arc

    points = tmp_path / "points.csv"
    points.write_text("x,y\n" + "".join(f"{x!r},{y!r}\n" for x, y in EXTERIOR_POINTS))
    proc = run_cli("exterior", str(out), "--points", str(points))
    assert proc.returncode == 0, proc.stderr
    table = np.loadtxt(proc.stdout.splitlines()[1:], delimiter=",")
    np.testing.assert_array_equal(table[:, :2], EXTERIOR_POINTS)
    assert np.abs(table[:, 2] - exact(UE, EXTERIOR_POINTS)).max() <= 0.15 * H**2

    csv = tmp_path / "ue.csv"
    proc = run_cli("exterior", str(out), "--points", str(points), "--out", str(csv))
    assert proc.returncode == 0 and proc.stdout == ""
    np.testing.assert_array_equal(np.loadtxt(csv, delimiter=",", skiprows=1), table)


def test_exterior_rejects_bad_points_and_missing_runs(run, tmp_path):
    out, _ = run
    inside = tmp_path / "inside.csv"
    inside.write_text("0.6,0.0\n0.1,0.1\n")
    assert_bad_input(run_cli("exterior", str(out), "--points", str(inside)), "--points")
    assert_bad_input(
        run_cli("exterior", str(out), "--points", str(tmp_path / "no.csv")), "--points", "not found"
    )
    bad = tmp_path / "bad.csv"
    bad.write_text("0.6;0.0\n")
    assert_bad_input(run_cli("exterior", str(out), "--points", str(bad)), "two numbers x,y")
    assert_bad_input(
        run_cli("exterior", str(tmp_path), "--points", str(inside)), "fields.npz", "not found"
    )


def test_existing_folder_refused_and_force_leaves_no_stale_files(run, config, tmp_path):
    out = tmp_path / "out"
    shutil.copytree(run[0], out)
    assert_bad_input(run_cli("solve", str(config), "--out", str(out)), "not empty", "--force")
    proc = run_cli(
        "solve",
        str(config),
        "--out",
        str(out),
        "--force",
        "--quiet",
        "--set",
        "output.plots=false",
        "--set",
        "output.xdmf=false",
        "--set",
        "geometry.h=0.0625",
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == ""  # --quiet
    assert sorted(p.name for p in out.iterdir()) == ["fields.npz", "summary.json"]
    assert json.loads((out / "summary.json").read_text())["dofs"] == 81


def test_empty_configuration_solves_to_zero(tmp_path):
    """All data zero: the minimiser of J_h is u = 0, phi = 0, found at the first step."""
    path = tmp_path / "empty.toml"
    path.write_text("")
    out = tmp_path / "out"
    proc = run_cli(
        "solve",
        str(path),
        "--out",
        str(out),
        "--quiet",
        "--set",
        "geometry.h=0.0625",
        "--set",
        "output.plots=false",
        "--set",
        "output.xdmf=false",
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert json.loads((out / "summary.json").read_text())["converged"]
    assert not np.load(out / "fields.npz")["u"].any()


def test_no_convergence_writes_outputs_and_exits_3(config, tmp_path):
    out = tmp_path / "out"
    proc = run_cli(
        "solve",
        str(config),
        "--out",
        str(out),
        "--quiet",
        "--set",
        "solver.max_iterations=3",
        "--set",
        "output.plots=false",
        "--set",
        "output.xdmf=false",
    )
    assert proc.returncode == 3, proc.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["converged"] is False and summary["iterations"] == 3
    assert "max_iterations" in summary["reason"]
    assert np.load(out / "fields.npz")["u"].size == summary["dofs"]


# ------------------------------------------------------------------------ errors
BAD_INPUTS = [
    # (TOML text, --set overrides, what the one-line message must name)
    ("[mesh]\nh = 0.1\n", [], ["unknown section [mesh]"]),
    ("", ["geometry.hh=0.1"], ["unknown key geometry.hh"]),
    ('[geometry]\nh = "small"\n', [], ["geometry.h must be a finite number"]),
    ("", ["geometry.h=0"], ["geometry.h must be positive"]),
    ("", ["geometry.h=0.05", "geometry.subdomain_size=0.06"], ["geometry.subdomain_size"]),
    (
        "",
        ["geometry.signorini=[[[0.0, 0.0], [0.25, -0.25]]]"],
        ["geometry.signorini", "not on the boundary"],
    ),
    (
        '[geometry]\nshape = "polygon"\nvertices = [[0, 0], [0, 0.5], [0.5, 0]]\n',
        [],
        ["geometry.vertices", "clockwise"],
    ),
    ("", ["geometry.width=0.8"], ["geometry.allow_large", "diam(Omega)"]),
    ("", ["data.f=sinn(x)"], ["data.f", "unknown function 'sinn'"]),
    ("", ["data.t0=nz*x"], ["data.t0", "unknown name 'nz'"]),
    ("", ["data.u0=1/0"], ["data.u0", "division by zero"]),
    ("", ["material.rho=2 + sin(t)"], ["material.rho", "not strictly increasing"]),
    ("", ["material.rho=power", "material.p=0.5"], ["material.p", "p > 1"]),
]


@pytest.mark.parametrize(
    "toml, overrides, fragments",
    BAD_INPUTS,
    ids=[b[2][0].split()[0] + f"-{i}" for i, b in enumerate(BAD_INPUTS)],
)
def test_bad_input_exits_2_with_one_line_naming_the_key(tmp_path, toml, overrides, fragments):
    path = tmp_path / "c.toml"
    path.write_text(toml)
    args = [a for o in overrides for a in ("--set", o)]
    proc = run_cli("solve", str(path), "--out", str(tmp_path / "out"), *args)
    assert_bad_input(proc, *fragments)


def test_missing_configuration_file(tmp_path):
    assert_bad_input(run_cli("solve", str(tmp_path / "none.toml")), "none.toml", "not found")


def test_debug_shows_the_traceback(tmp_path):
    proc = run_cli("solve", str(tmp_path / "none.toml"), "--debug")
    assert proc.returncode != 0 and "Traceback" in proc.stderr and "ConfigError" in proc.stderr


# ---------------------------------------------------------------- check-jacobian
def test_check_jacobian_passes_for_carstensen_with_json_report(tmp_path):
    from fem_py.forms.jacobian_check import MATRIX_TOL, SLOPE_TOL

    path = tmp_path / "c.toml"
    path.write_text('[geometry]\nh = 0.0625\n[material]\nrho = "carstensen"\n')
    report = json_report("check-jacobian", path)
    assert report["passed"] is True and report["material"] == "carstensen"
    assert report["matrix_rel_diff"] <= MATRIX_TOL
    assert all(abs(s - 2) <= SLOPE_TOL for s in report["slope2"])
    assert all(abs(s - 1) <= SLOPE_TOL for s in report["slope1"])


# --------------------------------------------------------------------------- MPI
@pytest.mark.mpi
def test_mpirun_solve_matches_the_serial_run(run, config, tmp_path):
    serial_out, _ = run
    out = tmp_path / "out"
    run_mpi(
        2, FEMBEM, "solve", str(config), "--out", str(out), "--quiet", "--set", "output.plots=false"
    )
    serial = json.loads((serial_out / "summary.json").read_text())
    par = json.loads((out / "summary.json").read_text())
    assert par["mpi_ranks"] == 2 and par["converged"]
    for key in ("iterations", "dofs", "boundary_dofs", "signorini_dofs", "contact_nodes"):
        assert par[key] == serial[key], key
    # The iterates do not depend on the number of ranks but for round-off in reductions
    # summed in another order; both runs stop at the same iteration, within kappa * tol
    # <= 100 * 1e-8 of the minimiser (tests/test_pgpm.py), so they agree to 1e-6.
    assert abs(par["energy"] - serial["energy"]) <= 1e-12 * abs(serial["energy"])
    fs, fp = np.load(serial_out / "fields.npz"), np.load(out / "fields.npz")
    np.testing.assert_allclose(fp["boundary_x"], fs["boundary_x"], rtol=0, atol=1e-15)
    np.testing.assert_array_equal(fp["active"], fs["active"])
    for key in ("boundary_u", "phi", "ue"):
        assert np.abs(fp[key] - fs[key]).max() <= 1e-6 * np.abs(fs[key]).max(), key
    order_s, order_p = (np.lexsort(np.round(f["x"], 12).T) for f in (fs, fp))
    assert np.abs(fp["u"][order_p] - fs["u"][order_s]).max() <= 1e-6 * np.abs(fs["u"]).max()
    assert (out / "solution.xdmf").is_file()


@pytest.mark.mpi
def test_mpirun_errors_print_once_and_do_not_hang(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text("[geometry]\nsignorini = [[[0.0, 0.0], [0.25, -0.25]]]\n")
    proc = run_mpi(
        2, FEMBEM, "solve", str(path), "--out", str(tmp_path / "out"), timeout=120, check=False
    )
    assert proc.returncode == 2, proc.stderr
    errors = [ln for ln in proc.stderr.splitlines() if ln.startswith("fembem: error")]
    assert len(errors) == 1 and "geometry.signorini" in errors[0], proc.stderr


# ------------------------------------------------------------------------ docs
def _docs_reference():
    """docs/_ext/fembem_docs/reference.py (plain Python: no Sphinx needed to import it)."""
    path = ROOT / "docs" / "_ext" / "fembem_docs" / "reference.py"
    spec = importlib.util.spec_from_file_location("fembem_docs_reference", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_configuration_reference_documents_every_key_with_its_default():
    """The generated configuration reference of the docs has a row | `section.key` |
    `default` | ... for each key, whose default, read as TOML, equals the value in
    coupling.options.DEFAULTS (the single source of the defaults), and a meaning."""
    reference = _docs_reference()
    page = "\n".join(reference.config_markdown(section) for section in DEFAULTS)
    rows = {
        m.group(1): (tomllib.loads(f"v = {m.group(2)}")["v"], m.group(3))
        for m in re.finditer(
            r"^\| `([a-z_0-9]+\.[a-z_0-9]+)` \| `([^`]*)` \|.*\| ((?:[^|\\]|\\.)*) \|$",
            page,
            re.M,
        )
    }
    expected = {
        f"{section}.{key}": value
        for section, table in DEFAULTS.items()
        for key, value in table.items()
    }
    assert rows.keys() == expected.keys()
    for key, value in expected.items():
        default, meaning = rows[key]
        assert default == value and type(default) is type(value), key
        assert meaning.strip(), key


def test_configuration_reference_speaks_of_bodies_too():
    """Issue 66, item 8: the reference said the expressions were in x, y (nx, ny) and
    that geometry.mesh names physical curve groups; a body takes z (nz) and surface
    groups."""
    reference = _docs_reference()
    rows = {
        m.group(1): m.group(0)
        for section in ("geometry", "data")
        for m in re.finditer(r"^\| `([a-z_0-9.]+)` \|.*$", reference.config_markdown(section), re.M)
    }
    for key in ("data.f", "data.exact"):
        assert "`z`" in rows[key] and "(x, y, z)" in rows[key], rows[key]
    for key in ("data.u0", "data.t0"):
        assert "`nz`" in rows[key] and "nz)" in rows[key], rows[key]
    assert "surface groups" in rows["geometry.mesh"]
    page = (ROOT / "docs" / "guide" / "configuration.md").read_text()
    assert "also `z`, and `nz`" in page
