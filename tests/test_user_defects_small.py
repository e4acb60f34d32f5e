"""Issue 29, items 6-13: the smaller defects a new user met."""
from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import run_cli
from coupling.io.plots import _BOUNDARY_FIELDS
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
    # a load that presses the body on: with the gap on the whole boundary int f dx > 0 is
    # what makes the solution unique (tests/test_free_constant.py)
    toml += '[data]\nf = "1"\n[output]\nplots = false\nxdmf = false\n'
    proc, summary = _solve(tmp_path, toml)
    assert summary["signorini_lengths"] == pytest.approx([2.0])
    assert "fembem: Signorini arcs of length 2\n" in proc.stdout + proc.stderr


def test_history_shows_the_quantity_the_stopping_rule_tested():
    """Item 9: ssn stops when the PGPM step from its last iterate is below tol, a quantity
    no record holds (the last Newton step is above tol): history.png draws it."""
    from mpi4py import MPI

    from coupling.io.history_figure import figure_history
    from coupling.io.plots import figure_inputs
    from coupling.manufactured import manufactured_problem, square_contact
    from coupling.options import SolverOptions
    from coupling.solvers import solve
    from fem_py.forms import make_material

    problem = manufactured_problem(
        MPI.COMM_SELF, square_contact(), make_material("carstensen"), cells=32
    )
    options = SolverOptions()
    solution = solve(problem, options)
    assert solution.converged and "PGPM step at xi_k" in solution.reason
    assert solution.stop_measure <= options.tol < solution.history[-1].step_norm
    fields = {"x": np.eye(3)[:, :2], "triangles": np.array([[0, 1, 2]]), "u": np.zeros(3)}
    fields |= {k: np.zeros(1) for k in _BOUNDARY_FIELDS}
    inputs = figure_inputs(
        fields, solution.history, tol=options.tol, stop_measure=solution.stop_measure
    )
    fig = figure_history(inputs.history, options.tol)
    drawn = {line.get_label(): line for line in fig.axes[0].get_lines()}
    (test,) = [line for label, line in drawn.items() if label.startswith("stopping test")]
    assert list(test.get_xdata()) == [solution.history[-1].iteration]
    assert list(test.get_ydata()) == [solution.stop_measure]


def test_a_truncated_mesh_file_is_said_to_be_cut_short(tmp_path):
    """Items 10 and 11: a mesh file cut short is reported as such, with the section and
    where it ends, and the key is named once."""
    from mesh_files import square_msh

    whole = square_msh(tmp_path / "whole.msh", 0.05).read_bytes()
    cut = whole[: whole.index(b"$Elements") + 200]
    (tmp_path / "cut.msh").write_bytes(cut)
    config = tmp_path / "c.toml"
    config.write_text('[geometry]\nmesh = "cut.msh"\nsubdomain_size = 0.125\n')
    proc = run_cli("info", str(config))
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("fembem: error: geometry.mesh: '"), lines
    assert "cut short: its $Elements section" in lines[0] and f"byte {len(cut)}" in lines[0]
    assert "mesh: mesh:" not in lines[0] and "not a gmsh mesh file" not in lines[0]


def test_evaluate_echoes_the_points_and_tells_outside_from_inside(tmp_path):
    """Item 13: the coordinates come back as written, and a point 1e-10 outside Omega
    (beyond the on-Gamma tolerance, 1e-11 of Gamma's diameter) is outside."""
    toml = '[geometry]\nh = 0.0625\nsubdomain_size = 0.125\nsignorini = ["bottom"]\n'
    toml += '[data]\nf = "1"\n[output]\nplots = false\nxdmf = false\n'
    _solve(tmp_path, toml, "--quiet")
    points = tmp_path / "p.csv"
    rows = ["0.1,0.1", "0.2500000001,0.0", "0.25, 0.0625", "1e-1,-0.25", "0.2499999999,0"]
    points.write_text("x,y\n" + "\n".join(rows) + "\n")
    proc = run_cli("evaluate", str(tmp_path / "out"), "--points", str(points))
    assert proc.returncode == 0, proc.stderr
    table = [ln.split(",") for ln in proc.stdout.strip().splitlines()[1:]]
    assert [f"{r[0]},{r[1]}" for r in table] == [ln.replace(" ", "") for ln in rows]
    assert [r[2] for r in table] == ["inside", "outside", "boundary", "boundary", "inside"]


@pytest.mark.mpi
@pytest.mark.parametrize("nprocs", [1, 2])
def test_readme_dolfinx_mesh_example_runs(tmp_path, nprocs):
    """Item 15: the guide's way from gmshio.model_to_mesh to domain_from_mesh runs,
    serially and on 2 ranks, and prints what the guide says (docs/guide/meshes.md)."""
    import re

    from conftest import ROOT, run_mpi

    readme = (ROOT / "docs" / "guide" / "meshes.md").read_text()
    section = readme[readme.index("## A DOLFINx mesh with facet tags") :]
    (code,) = re.findall(r"```python\n(.*?)```", section, re.S)[:1]
    script = tmp_path / "example.py"
    script.write_text(code)
    proc = run_mpi(nprocs, str(script), cwd=tmp_path)
    (printed,) = re.findall(r"it prints `(.*?)`", " ".join(section.split()))[:1]
    assert printed.startswith("converged: True;") and printed in proc.stdout, proc.stdout


@pytest.fixture(scope="module")
def disk_fields(tmp_path_factory):
    """fields.npz of a contact run on the disk (a curved Gamma) and on the square."""
    from coupling.io.outputs import load_fields

    out = {}
    wide = "vertices = [[-0.3, -0.1], [0.3, -0.1], [0.3, 0.1], [-0.3, 0.1]]\n"
    for shape, extra in (
        ("disk", "radius = 0.25\nstructured = false\n"),
        ("square", ""),
        ("polygon", wide),
    ):
        folder = tmp_path_factory.mktemp(shape)
        (folder / "c.toml").write_text(
            f'[geometry]\nshape = "{shape}"\n{extra}h = 0.03125\nsubdomain_size = 0.125\n'
            + {"disk": 'signorini = "all"\n', "square": 'signorini = ["bottom"]\n'}.get(
                shape, 'signorini = ["side0"]\n'
            )
            + '[data]\nf = "2"\nt0 = "-1 - 2*x"\n[output]\nplots = false\nxdmf = false\n'
        )
        proc = run_cli("solve", str(folder / "c.toml"), "--out", str(folder / "out"), "--quiet")
        assert proc.returncode == 0, proc.stderr
        out[shape] = load_fields(folder / "out")
    return out


def _dotted(fig) -> int:
    return sum(1 for ax in fig.axes for line in ax.get_lines() if line.get_linestyle() == ":")


def test_boundary_figure_marks_corners_not_curve_nodes(disk_fields):
    """Item 12: no dotted "corner" line at every node of a curve; four on the square."""
    from coupling.io.figures import _figure_boundary

    assert _dotted(_figure_boundary(disk_fields["disk"])) == 0
    assert _dotted(_figure_boundary(disk_fields["square"])) == 4 * 4  # 4 corners, 4 axes


def test_pressure_axis_is_not_flattened_by_corner_spikes(disk_fields):
    """Item 12: the pressure axis spans the pressure away from the corners."""
    from coupling.io.figures import _figure_boundary

    fields = dict(disk_fields["square"])
    pressure = fields["pressure"].copy()
    typical = np.abs(pressure).max()
    pressure[0] = 1e3 * typical  # a spike at the corner (-0.25, -0.25), node 0
    fields["pressure"] = pressure
    lo, hi = _figure_boundary(fields).axes[1].get_ylim()
    assert hi < 2 * typical and lo > -2 * typical


def test_u_figure_open_contact_is_visible_and_legend_clear_of_the_label(disk_fields):
    """Item 12: the open part of Gamma_s is drawn in a colour far from every colour of
    the colormap, and the legend does not overlap the x label."""
    import matplotlib

    from coupling.io.figures import _figure_u
    from coupling.io.plots import figure_inputs

    fields = disk_fields["polygon"]  # wide: short axes
    inputs = figure_inputs(fields, [], tol=1e-8)
    fig = _figure_u(fields, inputs.image, inputs.grid)
    (ax,) = [a for a in fig.axes if a.get_legend() is not None]
    drawn = {c.get_label(): c for c in ax.collections}
    (open_part,) = [c for label, c in drawn.items() if "open" in label]
    rgb = open_part.get_colors()[0][:3]
    cmap = matplotlib.colormaps["viridis"](np.linspace(0, 1, 256))[:, :3]
    assert np.linalg.norm(cmap - rgb, axis=1).min() > 0.3
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    legend = ax.get_legend().get_window_extent(renderer)
    label = ax.xaxis.label.get_window_extent(renderer)
    assert not legend.overlaps(label)


def test_adapt_figure_labels_what_it_draws(tmp_path):
    """Item 12: without an exact solution adapt.png draws the estimator only, and says so."""
    import matplotlib.pyplot as plt

    from coupling.io import levels

    saved = {}
    original = plt.Figure.savefig

    def keep(fig, *args, **kwargs):
        saved["label"] = fig.axes[0].get_ylabel()
        return original(fig, *args, **kwargs)

    plt.Figure.savefig = keep
    try:
        rows = [{"dofs": 100 * 4**k, "estimator": 2.0**-k} for k in range(3)]
        levels._plot(tmp_path / "adapt.png", rows)
    finally:
        plt.Figure.savefig = original
    assert saved["label"] == "estimator"


def test_an_adaptive_run_draws_its_final_mesh(tmp_path):
    """Item 12: mesh.png, the adapted mesh, beside adapt.png."""
    toml = '[geometry]\nshape = "lshape"\nh = 0.0625\nsubdomain_size = 0.125\n'
    toml += '[data]\nf = "1"\n[adapt]\nsteps = 2\n[solver]\nnested = false\n'
    toml += "[output]\nxdmf = false\n"
    _, summary = _solve(tmp_path, toml, "--quiet")
    assert {"adapt.png", "mesh.png"} <= set(summary["files"])
    from matplotlib.image import imread

    image = imread(tmp_path / "out" / "mesh.png")
    assert image.shape[0] > 500 and image[..., :3].min() < 0.2  # drawn lines
