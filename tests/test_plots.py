"""The images of u.png and whole_plane.png: the rasterised P1 field equals u_h at the
pixel centres (against a closed form and against matplotlib's own point location and
linear interpolation), pixels outside Omega are masked, and a run under mpirun -n 2
writes the same figures as a serial one."""
from __future__ import annotations

import json
import sys
from pathlib import Path

import matplotlib.tri as mtri
import numpy as np
import pytest

from conftest import ROOT, run_cli, run_mpi, solved_fields
from coupling.io.figure_data import PLOT_FILES, RASTER_PIXELS, PixelGrid, coarsen, rasterise

FEMBEM = str(Path(sys.executable).parent / "fembem")


def grid_mesh(n: int, jitter: float = 0.0, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """The unit square cut into 2 n^2 triangles (diagonals alternating, so both
    orientations of the node order occur), interior nodes moved by up to ``jitter`` h."""
    g = np.linspace(0.0, 1.0, n + 1)
    X, Y = np.meshgrid(g, g)
    x = np.column_stack([X.ravel(), Y.ravel()])
    inner = (x > 0).all(axis=1) & (x < 1).all(axis=1)
    x[inner] += np.random.default_rng(seed).uniform(-jitter, jitter, (inner.sum(), 2)) / n
    k = np.arange(n * (n + 1)).reshape(n, n + 1)[:, :n].ravel()
    up = np.column_stack([k, k + 1, k + n + 2]), np.column_stack([k, k + n + 2, k + n + 1])
    down = np.column_stack([k, k + 1, k + n + 1]), np.column_stack([k + 1, k + n + 1, k + n + 2])
    odd = (k % (n + 1) + k // (n + 1)) % 2 == 1
    triangles = np.concatenate(
        [np.where(odd[:, None], d, u) for u, d in zip(up, down)]
        + [np.where(odd[:, None], down[0], up[0])[::3, ::-1]]  # some clockwise duplicates
    )
    return x, triangles


def test_pixel_grid():
    grid = PixelGrid.covering(np.array([-1.0, 0.0]), np.array([2.0, 1.0]), pixels=300)
    assert (grid.nx, grid.ny, grid.size) == (300, 100, 0.01)
    assert grid.extent == pytest.approx((-1.0, 2.0, 0.0, 1.0), abs=1e-12)
    xc, yc = grid.centres()
    np.testing.assert_allclose(xc[[0, -1]], [-0.995, 1.995], rtol=0, atol=1e-12)
    np.testing.assert_allclose(yc[[0, -1]], [0.005, 0.995], rtol=0, atol=1e-12)
    assert PixelGrid.covering(np.zeros(2), np.ones(2)).nx == RASTER_PIXELS


@pytest.mark.parametrize("n, pixels", [(1, 1000), (7, 120), (60, 90)])
def test_a_linear_field_is_reproduced_at_every_pixel_centre(n, pixels):
    """P1 reproduces linear functions: the image is the function at the centres, to
    round-off, whether triangles span many pixels (batches of one triangle) or few."""
    x, triangles = grid_mesh(n, jitter=0.2)
    grid = PixelGrid.covering(x.min(axis=0), x.max(axis=0), pixels=pixels)
    image = rasterise(x, triangles, 1.0 + 2.0 * x[:, 0] - 3.0 * x[:, 1], grid)
    xc, yc = grid.centres()
    X, Y = np.meshgrid(xc, yc)
    assert image.shape == (grid.ny, grid.nx) and not image.mask.any()  # Omega fills the box
    np.testing.assert_allclose(image.data, 1.0 + 2.0 * X - 3.0 * Y, rtol=0, atol=1e-13)


def test_the_image_equals_the_p1_interpolant_at_the_pixel_centres():
    x, triangles = grid_mesh(12, jitter=0.2, seed=1)
    u = np.sin(3 * x[:, 0]) * np.cos(2 * x[:, 1]) + np.random.default_rng(2).normal(0, 0.1, len(x))
    grid = PixelGrid.covering(x.min(axis=0) - 0.05, x.max(axis=0) + 0.05, pixels=157)
    image = rasterise(x, triangles, u, grid)
    xc, yc = grid.centres()
    X, Y = np.meshgrid(xc, yc)
    tri = mtri.Triangulation(x[:, 0], x[:, 1], triangles[: 2 * 12**2])  # no duplicates
    reference = mtri.LinearTriInterpolator(tri, u)(X, Y)
    np.testing.assert_array_equal(image.mask, np.ma.getmaskarray(reference))
    assert image.count() > 0.8 * image.size
    np.testing.assert_allclose(image.compressed(), reference.compressed(), rtol=0, atol=1e-12)


def test_pixels_outside_omega_are_masked():
    """An L-shape (the unit square without its upper-right quarter) in a larger box."""
    x, triangles = grid_mesh(8)
    centroids = x[triangles].mean(axis=1)
    triangles = triangles[~((centroids > 0.5).all(axis=1))]
    grid = PixelGrid.covering(np.array([-0.25, -0.25]), np.array([1.25, 1.25]), pixels=150)
    image = rasterise(x, triangles, np.ones(len(x)), grid)
    xc, yc = grid.centres()
    X, Y = np.meshgrid(xc, yc)
    inside = (X > 0) & (X < 1) & (Y > 0) & (Y < 1) & ~((X > 0.5) & (Y > 0.5))
    np.testing.assert_array_equal(~image.mask, inside)  # no centre lies on Gamma here
    np.testing.assert_allclose(image.compressed(), 1.0, rtol=0, atol=1e-14)


def _png_size(path: Path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")


@pytest.mark.mpi
def test_figures_under_mpirun_are_those_of_the_serial_run(tmp_path):
    config = tmp_path / "c.toml"
    config.write_text(
        '[geometry]\nshape = "square"\nh = 0.03125\nsubdomain_size = 0.125\n'
        'structured = true\nsignorini = ["bottom"]\n[material]\nrho = "carstensen"\n'
        '[data]\nf = "1 + x"\nt0 = "-1"\nu0 = "0.1"\n[solver]\nmethod = "ssn"\n'
        "[output]\nxdmf = false\n"
    )
    serial, parallel = tmp_path / "serial", tmp_path / "parallel"
    proc = run_cli("solve", str(config), "--out", str(serial), "--quiet")
    assert proc.returncode == 0, proc.stderr
    proc = run_mpi(2, FEMBEM, "solve", str(config), "--out", str(parallel), "--quiet")
    # drawn by the figure process, which is no rank of the job (it once joined it: orte_init)
    assert "figure process failed" not in proc.stderr, proc.stderr[-2000:]
    files = [json.loads((out / "summary.json").read_text())["files"] for out in (serial, parallel)]
    assert files[0] == files[1] and set(PLOT_FILES) <= set(files[0])
    for name in PLOT_FILES:
        assert _png_size(parallel / name) == _png_size(serial / name), name
    # the images drawn from either run's fields agree to the solver tolerance
    images = []
    for out in (serial, parallel):
        with np.load(out / "fields.npz") as f:
            grid = PixelGrid.covering(f["x"].min(axis=0), f["x"].max(axis=0))
            images.append(rasterise(f["x"], f["triangles"], f["u"], grid))
    np.testing.assert_array_equal(images[0].mask, images[1].mask)
    assert np.abs(images[0] - images[1]).max() <= 1e-6 * np.abs(images[0]).max()


@pytest.mark.parametrize("pixels", [60, 61])
def test_the_coarsened_image_is_the_image_on_the_coarse_grid(pixels):
    """whole_plane.png reuses the image of u.png: every other pixel centre, seen through
    pixels twice as large over a box twice as wide, equals a rasterisation on that grid."""
    x, triangles = grid_mesh(9, jitter=0.2, seed=3)
    x = x * [1.0, 0.6] + [0.3, -0.2]  # not a square, not at the origin
    u = np.cos(4 * x[:, 0] + x[:, 1])
    fine = PixelGrid.covering(x.min(axis=0), x.max(axis=0), pixels=pixels)
    centre, half = 0.5 * (x.min(axis=0) + x.max(axis=0)), np.ptp(x, axis=0).max()
    coarse, image = coarsen(rasterise(x, triangles, u, fine), fine, centre - half, centre + half)
    assert coarse.size == 2 * fine.size
    left, right, bottom, top = np.array(coarse.extent) + 1e-12 * np.array([-1, 1, -1, 1])
    assert left <= centre[0] - half and right >= centre[0] + half  # up to round-off
    assert bottom <= centre[1] - half and top >= centre[1] + half
    direct = rasterise(x, triangles, u, coarse)
    assert image.count() > 0
    np.testing.assert_array_equal(image.mask, direct.mask)
    np.testing.assert_allclose(image.compressed(), direct.compressed(), rtol=0, atol=1e-12)


def test_surface_figure_turns_the_normals_of_a_closed_surface_outward():
    """surface.png draws the triangles facing the eye only: their normals must point out
    of the body whatever the triangles' orientation (here the cube, both ways round)."""
    from bem_cpp.surfaces import cube
    from coupling.io.body_figures import outward_normals

    X, T = cube(4)
    for tri in (T, T[:, ::-1]):
        corners = X[tri]
        normals = outward_normals(corners)
        centroids = corners.mean(axis=1)
        assert (np.einsum("ij,ij->i", normals, centroids) > 0).all()  # the cube's centre: 0


def test_the_figure_process_starts_outside_the_mpi_job():
    """The figure process of a rank gets the rank's environment without the variables of
    the MPI job (if it initialises MPI, for a body's figures, it is an MPI process of its
    own, not a rank that fails to join), with the Open MPI and PMIx settings kept."""
    from coupling.io.figure_worker import outside_the_mpi_job

    rank = {
        "PATH": "/usr/bin",
        "OMPI_MCA_pmix": "^s1,s2,cray,isolated",
        "OMPI_ALLOW_RUN_AS_ROOT": "1",
        "PMIX_MCA_mca_base_component_show_load_errors": "1",
        "OMPI_COMM_WORLD_RANK": "0",
        "OMPI_COMM_WORLD_SIZE": "2",
        "OMPI_MCA_orte_hnp_uri": "1.0;tcp://127.0.0.1:1",
        "OMPI_MCA_ess": "^singleton",
        "OMPI_MCA_ess_base_vpid": "0",
        "OMPI_UNIVERSE_SIZE": "2",
        "PMIX_RANK": "0",
        "PMIX_NAMESPACE": "1",
        "PMIX_SERVER_URI4": "1.0;tcp4://127.0.0.1:1",
        "PMI_RANK": "0",
    }
    assert outside_the_mpi_job(rank) == {
        "PATH": "/usr/bin",
        "OMPI_MCA_pmix": "^s1,s2,cray,isolated",
        "OMPI_ALLOW_RUN_AS_ROOT": "1",
        "PMIX_MCA_mca_base_component_show_load_errors": "1",
    }


def test_planar_figures_are_drawn_without_mpi(tmp_path):
    """What the figure process of a planar run does, the render of pickled FigureInputs,
    imports no MPI (it imported the body figures' modules, and through the mesh libraries
    MPI, in every run: under mpirun the process then tried to join the job)."""
    import pickle
    import subprocess

    from coupling.io.plots import figure_inputs

    config = tmp_path / "c.toml"
    config.write_text(
        '[geometry]\nshape = "square"\nh = 0.0625\nsubdomain_size = 0.125\n'
        'structured = true\nsignorini = ["bottom"]\n[data]\nt0 = "-1"\n'
        "[output]\nxdmf = false\nplots = false\n"
    )
    proc = run_cli("solve", str(config), "--out", str(tmp_path / "out"), "--quiet")
    assert proc.returncode == 0, proc.stderr
    with np.load(tmp_path / "out" / "fields.npz") as f:
        inputs = figure_inputs(dict(f), [], tol=1e-8)
    pickled = tmp_path / "inputs.pkl"
    pickled.write_bytes(pickle.dumps(inputs))
    code = (
        "import pickle, sys; from coupling.io import figures; "
        f"pngs = figures.render(pickle.loads(open({str(pickled)!r}, 'rb').read())); "
        "assert 'u.png' in pngs; sys.exit(3 if 'mpi4py' in sys.modules else 0)"
    )
    assert subprocess.run([sys.executable, "-c", code], cwd=ROOT).returncode == 0
    # the figure process draws boundary.png and history.png from the boundary arrays
    # and the records while the run gathers and rasterises u_h, u.png from these inputs
    # while the run computes u_e's samples, then whole_plane.png from the whole inputs
    from types import SimpleNamespace

    from coupling.io.figure_worker import FigureWorker
    from coupling.io.figures import render
    from coupling.io.plots import boundary_figure_inputs, exterior_samples

    records = [
        SimpleNamespace(iteration=k, energy=-k, step_norm=0.1**k, contact=3) for k in (1, 2)
    ]
    with np.load(tmp_path / "out" / "fields.npz") as f:
        early = boundary_figure_inputs(dict(f), records, tol=1e-8)
        samples = exterior_samples(dict(f))
    assert set(render(early)) == {"boundary.png", "history.png"}  # no image of u_h yet
    assert "whole_plane.png" not in render(inputs)  # no samples yet
    whole = inputs._replace(exterior_points=samples.points, exterior_ue=samples.ue)
    sent = []
    with FigureWorker() as worker:
        pngs = worker.render(early, lambda: sent.append(1) or inputs, lambda: whole)
    assert sent and set(pngs) == set(PLOT_FILES)
    assert all(png.startswith(b"\x89PNG") for png in pngs.values())


def test_the_figure_process_warms_up_on_every_planar_figure():
    """The figure process's warm-up draws each planar figure once (a small square), so
    that matplotlib's fonts, parsers and mathtext strings of every figure are ready
    before the run's inputs come."""
    from coupling.io.figures import _warm_up_inputs, render

    assert set(render(_warm_up_inputs())) == set(PLOT_FILES)


def test_the_section_of_a_body_draws_u_e_to_a_fraction_of_a_colour_step():
    """slice.png's u_e comes from the representation formula compressed to
    SLICE_POTENTIAL_TOL, not the solver's 1e-6: on a surface of 3,458 vertices and the
    exterior pixels of a section through it, it stays within 1e-3 of the image's range of
    the direct sums (a colour map resolves about 1/256), and no exterior pixel is taken
    for an interior one (the compressed solid angle)."""
    import bem_cpp
    from bem_cpp.surfaces import cube
    from coupling.io.body_figure_data import SLICE_POTENTIAL_TOL

    X, T = cube(24, side=0.5)
    ue = np.sin(3 * X[:, 0]) + X[:, 1] * X[:, 2]
    flux = np.cos(2 * X[:, 1]) - X[:, 0]
    g = np.linspace(-0.5, 0.5, 61) + 1.0 / 180
    P, Q = np.meshgrid(g, g)
    points = np.column_stack([P.ravel(), Q.ravel(), np.zeros(P.size)])
    points = points[(np.abs(points[:, :2]) > 0.26).any(axis=1)]

    def u_e(compression):
        return bem_cpp.exterior_potential(
            X, ue, flux, points, compression=compression, tol=SLICE_POTENTIAL_TOL, triangles=T
        )

    direct = u_e("none")
    assert np.abs(u_e("hmatrix") - direct).max() <= 1e-3 * np.ptp(direct)


def test_a_body_s_figures_are_drawn_by_the_figure_process_in_two_parts(tmp_path):
    """The figure process of a 3D run draws the figures on Gamma and the history from the
    first inputs, then slice.png from the section the run computed meanwhile (they were
    all drawn in the run's own process after the section); an error of the section ends
    the figure process and reaches the run."""
    from types import SimpleNamespace

    from coupling.io.body_figure_data import section, surface_inputs
    from coupling.io.figure_worker import FigureWorker
    from coupling.io.plots import history_arrays

    fields = solved_fields(
        tmp_path,
        "c",
        '[geometry]\nshape = "box"\ncenter = [0.0, 0.0, 0.0]\nwidth = 0.5\nh = 0.125\n'
        'signorini = ["bottom"]\n[data]\nt0 = "-1"',
    )
    records = [
        SimpleNamespace(iteration=k, energy=-k, step_norm=0.1**k, contact=9) for k in (1, 2)
    ]
    surface = surface_inputs(fields, history_arrays(records, 0.01), tol=1e-8)
    asked = []

    def whole():
        asked.append(True)
        return surface._replace(section=section(fields))

    with FigureWorker(body=True) as worker:  # a body's figure modules imported at once
        pngs = worker.render(surface, whole)
    assert asked and set(pngs) == {"signorini.png", "surface.png", "history.png", "slice.png"}
    assert all(png.startswith(b"\x89PNG") for png in pngs.values())

    def failing():
        raise ValueError("no section")

    with FigureWorker() as worker:
        with pytest.raises(ValueError, match="no section"):
            worker.render(surface, failing)
        assert worker._process.poll() is not None  # ended, not left waiting


@pytest.mark.parametrize("elev, nearer", [(90, "blue"), (-90, "red")])
def test_surface_figure_draws_the_nearer_of_two_overlapping_triangles_last(elev, nearer):
    """surface.png's triangles are sorted by depth in the axes' view and drawn farthest
    first (a painter's order, as mplot3d's polygons): of two triangles one above the other
    the one nearer the eye covers the other, seen from above and from below."""
    import io

    import matplotlib.pyplot as plt
    from matplotlib.colors import to_rgba

    from coupling.io.body_figures import GouraudSurface

    square = np.array([[-1.0, -1.0], [1.0, -1.0], [0.0, 1.0]])
    corners = np.stack([np.column_stack([square, np.full(3, z)]) for z in (0.0, 1.0)])
    colours = np.array([[to_rgba("red")] * 3, [to_rgba("blue")] * 3])
    fig = plt.figure(figsize=(2, 2), dpi=50)
    ax = fig.add_subplot(projection="3d")
    ax.add_collection(GouraudSurface(corners, colours), autolim=False)
    ax.set(xlim=(-1, 1), ylim=(-1, 1), zlim=(0, 1))
    ax.set_axis_off()
    ax.view_init(elev=elev, azim=-90)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    plt.close(fig)
    image = plt.imread(io.BytesIO(buffer.getvalue()))
    centre = image[image.shape[0] // 2, image.shape[1] // 2, :3]
    np.testing.assert_allclose(centre, to_rgba(nearer)[:3], atol=0.02)


def test_the_open_gap_is_drawn_as_the_captions_say():
    """Issue 66, item 6: README and the docs said "red: computed contact, blue: open gap"
    while the open part was drawn white on a black edge, panel by panel (a dashed band,
    half clipped by the axes' frame). Each part is now one line in its colour, white far
    from the colormap's (tests/test_user_defects_small.py), drawn over the frame; the
    captions say white."""
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    from matplotlib.colors import to_rgba

    from coupling.io.gamma_drawing import draw_boundary

    t = np.linspace(0.0, 1.0, 9)[:-1]
    nodes = np.concatenate(
        [np.column_stack([t, 0 * t]), np.column_stack([1 + 0 * t, t])]
        + [np.column_stack([1 - t, 1 + 0 * t]), np.column_stack([0 * t, 1 - t])]
    )
    signorini = np.zeros(len(nodes), bool)
    signorini[1:8] = True  # the bottom side's inner nodes: its 8 panels are Gamma_s
    phi = np.where(signorini & (nodes[:, 0] > 0.55), 0.1, 0.0)  # open on the right half
    fields = dict(boundary_x=nodes, signorini=signorini, phi=phi, active=signorini & (phi == 0))
    fig, ax = plt.subplots()
    try:
        draw_boundary(ax, fields)
        parts = {c.get_label(): c for c in ax.collections if isinstance(c, LineCollection)}
        contact = parts[r"$\Gamma_s$ in contact ($\phi_h = 0$)"]
        open_gap = parts[r"$\Gamma_s$ open ($\phi_h > 0$)"]
        assert tuple(contact.get_colors()[0]) == to_rgba("tab:red")
        assert tuple(open_gap.get_colors()[0]) == to_rgba("white")
        for part, (x0, x1) in ((contact, (0.0, 0.5)), (open_gap, (0.5, 1.0))):
            (line,) = part.get_paths()  # one line along the run, not one per panel
            assert line.vertices[:, 0].min() == x0 and line.vertices[:, 0].max() == x1
            assert not part.get_clip_on()  # Gamma_s on the axes' frame is drawn whole
    finally:
        plt.close(fig)
    for page in ("README.md", "docs/getting-started.md", "docs/guide/outputs.md"):
        text = " ".join((ROOT / page).read_text().split())
        assert "white" in text and "blue: open" not in text and "blue where open" not in text
        assert "blue those with an open gap" not in text, page
