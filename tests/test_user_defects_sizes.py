"""Issue 29, item 3: the size of a run is known before anything is allocated. For the
structured square and L-shape the counts are in closed form (the coarse grid too), in
O(1) memory; for gmsh shapes they are estimated from the area and h before meshing; a run
that cannot fit is refused with exit code 2 and one line, `info` included."""
from __future__ import annotations

import json
import tracemalloc

import numpy as np
import pytest
from mpi4py import MPI

from conftest import run_cli
from coupling.app.sizing import size_of_domain
from fem_py.mesh import GeometrySpec, build_domain, domain_size
from fem_py.mesh.shapes import grid_counts, grid_partition
from fem_py.mesh.size_estimate import mesh_size_estimate
from solid_files import group_bottom_faces

SQUARE = """\
[geometry]
shape = "{shape}"
h = {h}
subdomain_size = {d}
structured = {structured}
signorini = ["bottom"]
"""


@pytest.mark.parametrize("shape", ["square", "lshape"])
def test_grid_counts_are_those_of_the_grid(shape):
    for nc in range(1 if shape == "square" else 2, 13, 1 if shape == "square" else 2):
        _, V, cells, _ = grid_partition(shape, (0.0, 0.0), 0.5, 0.5 / nc)
        cells = np.asarray(cells)
        a, b = cells.ravel(), np.roll(cells, -1, axis=1).ravel()
        _, count = np.unique(np.minimum(a, b) * len(V) + np.maximum(a, b), return_counts=True)
        assert grid_counts(shape, nc) == (len(V), len(count), len(cells), int((count == 1).sum()))


@pytest.mark.parametrize(
    "shape,h,d,signorini",
    [
        ("square", 1 / 16, 1 / 4, ["bottom", "top"]),
        ("square", 1 / 12, 1 / 6, "all"),
        ("lshape", 1 / 16, 1 / 8, ["notch_bottom", "left"]),
        ("lshape", 1 / 24, 1 / 4, [[[-0.25, -0.25], [0.25, -0.25]]]),
    ],
)
def test_closed_form_sizes_are_those_of_the_mesh(shape, h, d, signorini):
    args = dict(h=h, subdomain_size=d, signorini=signorini, structured=True)
    built = size_of_domain(build_domain(MPI.COMM_SELF, GeometrySpec(shape, **args)))
    size = domain_size(GeometrySpec(shape, **args))
    counts = ("dofs", "boundary_dofs", "signorini_dofs", "subdomains")
    assert [getattr(size, k) for k in counts] == [getattr(built, k) for k in counts]
    assert [size.h_min, size.h_max] == pytest.approx([built.h_min, built.h_max], rel=1e-12)


def test_closed_form_size_costs_no_memory_per_coarse_cell():
    # 250,000 coarse cells: the grid alone would take tens of MB
    tracemalloc.start()
    size = domain_size(GeometrySpec("square", h=2.5e-4, subdomain_size=1e-3, structured=True))
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert size.subdomains == 500**2 and size.dofs == 2001**2
    assert peak < 1e6


@pytest.mark.parametrize(
    "shape,extra,area",
    [("disk", {"radius": 0.25}, np.pi / 16), ("square", {}, 0.25), ("lshape", {}, 0.1875)],
)
def test_gmsh_size_estimate_is_close_below_the_mesh(shape, extra, area):
    args = dict(h=0.01, subdomain_size=0.08, structured=False, **extra)
    built = size_of_domain(build_domain(MPI.COMM_SELF, GeometrySpec(shape, **args)))
    guess = mesh_size_estimate(GeometrySpec(shape, **args))
    # measured 0.81-0.95 of the mesh's dofs (the square's coarse lines are mesh lines):
    # an underestimate refuses no run that fits; the mesh's exact size is checked after
    assert 0.75 * built.dofs <= guess.dofs <= built.dofs
    assert guess.boundary_dofs == pytest.approx(built.boundary_dofs, rel=0.1)
    tracemalloc.start()
    mesh_size_estimate(GeometrySpec(shape, **{**args, "h": 1e-6, "subdomain_size": 1e-5}))
    assert tracemalloc.get_traced_memory()[1] < 1e6
    tracemalloc.stop()


def _refused_before_it_is_built(config):
    """Checks that ``fembem solve`` of ``config`` (alone in its folder) is refused in one line
    naming geometry.h, writing nothing, and that ``fembem info`` reports the estimate above
    the available memory; returns that report."""
    folder = config.parent
    proc = run_cli("solve", str(config), "--out", str(folder / "out"), timeout=60)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "needs about" in lines[0] and "geometry.h" in lines[0], lines
    assert sorted(p.name for p in folder.iterdir()) == [config.name]
    info = run_cli("info", str(config), "--json", timeout=60)
    assert info.returncode == 0, info.stderr
    report = json.loads(info.stdout)
    assert report["memory_estimate_bytes"] > report["memory_available_bytes"]
    return report


@pytest.mark.parametrize("structured", ["true", "false"])
def test_a_run_that_cannot_fit_is_refused_before_it_is_built(tmp_path, structured):
    config = tmp_path / "c.toml"
    config.write_text(SQUARE.format(shape="square", h=1e-5, d=4e-5, structured=structured))
    report = _refused_before_it_is_built(config)
    assert report["dofs"] > 2e9  # (0.5 / 1e-5)^2 nodes and more
    assert report["sizes"].startswith("closed form" if structured == "true" else "estimated")


# Issue 66, item 1: the ball (a gmsh mesh in 3D) and a user's OpenCASCADE model are
# estimated from their volume, surface and h before gmsh meshes them.

BALL = """\
[geometry]
shape = "ball"
radius = 0.25
h = {h}
signorini = ["bottom"]
"""


def test_ball_size_estimate_is_close_below_the_mesh():
    spec = GeometrySpec("ball", radius=0.25, h=0.035, signorini=["bottom"])
    built = size_of_domain(build_domain(MPI.COMM_SELF, spec))
    guess = mesh_size_estimate(spec)
    # measured 0.85-0.94 of the mesh's dofs at h = r/5 .. r/28
    assert 0.8 * built.dofs <= guess.dofs <= built.dofs
    assert guess.boundary_dofs == pytest.approx(built.boundary_dofs, rel=0.15)
    assert guess.signorini_dofs == pytest.approx(built.signorini_dofs, rel=0.15)
    assert guess.dim == 3
    tracemalloc.start()
    mesh_size_estimate(GeometrySpec("ball", radius=0.25, h=1e-6))
    assert tracemalloc.get_traced_memory()[1] < 1e6
    tracemalloc.stop()


def _block_with_a_hole(gmsh):
    """demos/demo_own_body.py's block 0.6 x 0.4 x 0.3 with a hole of radius 0.08, its
    bottom face the physical group "bottom" (2) and the other faces "rest" (3)."""
    occ = gmsh.model.occ
    block = occ.addBox(0.0, 0.0, 0.0, 0.6, 0.4, 0.3)
    drill = occ.addCylinder(0.3, -0.1, 0.15, 0.0, 0.6, 0.0, 0.08)
    (body,), _ = occ.cut([(3, block)], [(3, drill)])
    occ.synchronize()
    return group_bottom_faces(gmsh, body[1])


def test_gmsh_model_size_of_an_occ_body_before_meshing():
    import gmsh

    from fem_py.mesh.size_estimate import gmsh_model_size

    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        bottom = _block_with_a_hole(gmsh)
        guess = gmsh_model_size(0.03, signorini=["bottom"])
        assert gmsh_model_size(0.03, signorini=[2]) == guess  # a group by its number
        everything = gmsh_model_size(0.03)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.03)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.model.mesh.generate(3)
        nodes = len(gmsh.model.mesh.getNodes()[0])
        surface = {
            n for _, t in gmsh.model.getEntities(2) for n in gmsh.model.mesh.getNodes(2, t, True)[0]
        }
        contact = set(gmsh.model.mesh.getNodes(2, bottom[0], True)[0])
    finally:
        gmsh.finalize()
    # measured 1.01 of the mesh's nodes, 0.92 of its surface nodes, 0.84 of the bottom's
    assert guess.dim == 3 and 0.8 * nodes <= guess.dofs <= 1.1 * nodes
    assert guess.boundary_dofs == pytest.approx(len(surface), rel=0.15)
    assert guess.signorini_dofs == pytest.approx(len(contact), rel=0.25)
    assert everything.signorini_dofs == everything.boundary_dofs


def test_a_ball_that_cannot_fit_is_refused_before_it_is_meshed(tmp_path):
    # 0.55 (4/3 pi 0.25^3) / h^3 = 2.9e8 dofs: gmsh would mesh it for hours
    config = tmp_path / "c.toml"
    config.write_text(BALL.format(h=5e-4))
    report = _refused_before_it_is_built(config)
    assert report["dofs"] > 2e8 and report["dim"] == 3
    assert report["sizes"].startswith("estimated")
