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


@pytest.mark.parametrize("structured", ["true", "false"])
def test_a_run_that_cannot_fit_is_refused_before_it_is_built(tmp_path, structured):
    config = tmp_path / "c.toml"
    config.write_text(SQUARE.format(shape="square", h=1e-5, d=4e-5, structured=structured))
    proc = run_cli("solve", str(config), "--out", str(tmp_path / "out"), timeout=60)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "needs about" in lines[0] and "geometry.h" in lines[0], lines
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.toml"]
    info = run_cli("info", str(config), "--json", timeout=60)
    assert info.returncode == 0, info.stderr
    report = json.loads(info.stdout)
    assert report["memory_estimate_bytes"] > report["memory_available_bytes"]
    assert report["dofs"] > 2e9  # (0.5 / 1e-5)^2 nodes and more
    assert report["sizes"].startswith("closed form" if structured == "true" else "estimated")
