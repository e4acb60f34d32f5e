"""Users' own geometry: gmsh mesh files, the automatic partition, the disk, the API
``domain_from_mesh``, and the one-line errors of bad input (issue 17).

Measured (serial, Carstensen material, f = 2, t0 = -1, d = 4h; docs/design/coarse_space.md):
on the square read from an unstructured .msh file PGPM needs 108, 155, 113 iterations at
h = 1/16, 1/32, 1/64 with the Galerkin coarse matrix that ``coarse_space = "auto"``
chooses there, against 129, 125, 128 on the generated square with the same h and d/h
(0.84x, 1.24x, 0.88x; with the paper's graph Laplacian on the imported mesh 155, 316, 167,
i.e. up to 2.5x; at h = 1/32 and d = 3.6h, 4.4h, 6h: 0.81x, 0.90x, 0.85x); ssn 11 steps
on both.
"""
from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from conftest import ROOT, run_cli, run_mpi
from mesh_files import bad_msh, disk_msh, square_msh

sys.path.insert(0, str(Path(__file__).parent))

COMM = MPI.COMM_WORLD


# ------------------------------------------------------------------ the partition
def _disk_arrays(h: float, n_boundary: int | None = None):
    """A disk mesh (or, with ``n_boundary``, the inscribed polygon) as arrays."""
    import gmsh

    gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        if n_boundary is None:
            gmsh.model.occ.addDisk(0, 0, 0, 0.25, 0.25)
            gmsh.model.occ.synchronize()
        else:
            geo = gmsh.model.geo
            t = 2 * np.pi * np.arange(n_boundary) / n_boundary
            p = [geo.addPoint(0.25 * math.cos(a), 0.25 * math.sin(a), 0, h) for a in t]
            lines = [geo.addLine(p[i], p[(i + 1) % n_boundary]) for i in range(n_boundary)]
            geo.addPlaneSurface([geo.addCurveLoop(lines)])
            geo.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
        gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
        gmsh.model.mesh.generate(2)
        tags, xyz, _ = gmsh.model.mesh.getNodes()
        order = np.argsort(tags)
        _, nodes = gmsh.model.mesh.getElementsByType(2)
        cells = np.searchsorted(tags[order], nodes).reshape(-1, 3)
        return xyz.reshape(-1, 3)[order, :2], cells
    finally:
        gmsh.finalize()


@pytest.mark.parametrize("d", [0.05, 0.1, 0.2])
def test_partition_is_connected_compact_and_covers_every_cell_once(d):
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    from fem_py.partition import cell_adjacency, part_diameters, partition_cells

    x, cells = _disk_arrays(0.01)
    label = partition_cells(x, cells, d)
    assert label.shape == (len(cells),) and label.min() == 0
    assert np.array_equal(np.unique(label), np.arange(label.max() + 1))  # every id used
    a, b, _ = cell_adjacency(cells)
    for k in range(label.max() + 1):
        mine = np.flatnonzero(label == k)
        keep = (label[a] == k) & (label[b] == k)
        index = np.full(len(cells), -1)
        index[mine] = np.arange(len(mine))
        graph = sp.csr_matrix(
            (np.ones(int(keep.sum())), (index[a[keep]], index[b[keep]])),
            shape=(len(mine), len(mine)),
        )
        assert connected_components(graph, directed=False)[0] == 1, k
    diam = part_diameters(x, cells, label)
    assert 0.5 * d < diam.min() and diam.max() < 2.5 * d, (diam.min() / d, diam.max() / d)


def test_partition_does_not_depend_on_how_finely_the_boundary_is_drawn():
    """A 480-gon and a 24-gon of the same circle: about the same number of subdomains
    (the old polygon path made one subdomain per coarse triangle: 42,530 for the 480-gon)."""
    from fem_py.partition import partition_cells

    counts = [partition_cells(*_disk_arrays(0.01, n), 0.1).max() + 1 for n in (24, 480)]
    assert abs(counts[0] - counts[1]) <= 0.2 * counts[1], counts


# ------------------------------------------------------------------ mesh files
@pytest.fixture(scope="module")
def disk_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("msh")
    return {v: disk_msh(folder / f"disk{v}.msh", 0.04, version=v) for v in (2.2, 4.1)}


def _solve_file(path, **kw):
    from coupling.options import SolverOptions
    from coupling.problem import SignoriniProblem
    from coupling.solvers import solve
    from fem_py.forms import make_material
    from fem_py.mesh import GeometrySpec, build_domain

    domain = build_domain(
        COMM, GeometrySpec(mesh=str(path), subdomain_size=0.16, signorini=["contact"], **kw)
    )
    problem = SignoriniProblem(domain, make_material("carstensen"), f="2", t0="-1")
    return domain, problem, solve(problem, SolverOptions(tol=1e-10))


def test_msh_22_and_41_give_the_same_domain_and_solution(disk_files):
    d22, p22, r22 = _solve_file(disk_files[2.2])
    d41, p41, r41 = _solve_file(disk_files[4.1])
    assert d22.coarse.n_subdomains == d41.coarse.n_subdomains > 1
    assert d22.shape == "mesh" and len(d22.arcs) == 1 and not d22.signorini_is_whole_boundary
    assert r22.converged and r22.iterations == r41.iterations <= 15
    assert np.allclose(p22.boundary.nodes, p41.boundary.nodes)
    assert np.allclose(r22.phi, r41.phi, atol=1e-10)
    assert r22.contact.sum() > 0


def test_physical_subdomains_and_whole_boundary(disk_files):
    domain, _, result = _solve_file(disk_files[4.1], subdomains="physical")
    assert domain.coarse.n_subdomains == 1 and result.converged
    from fem_py.mesh import GeometrySpec, build_domain

    whole = build_domain(
        COMM, GeometrySpec(mesh=str(disk_files[4.1]), subdomain_size=0.1, signorini="all")
    )
    assert whole.signorini_is_whole_boundary


def test_domain_from_mesh_equals_the_file_route(disk_files):
    """The DOLFINx-convention API on a mesh read by dolfinx's gmshio (its own partition),
    with facet tags and group names: the same Domain as from the file."""
    import gmsh
    from dolfinx.io import gmshio

    from fem_py.mesh import GeometrySpec, build_domain, domain_from_mesh

    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    if COMM.rank == 0:
        gmsh.open(str(disk_files[4.1]))
    msh, _, ft = gmshio.model_to_mesh(gmsh.model, COMM, 0, gdim=2)
    gmsh.finalize()
    api = domain_from_mesh(
        msh, ft, signorini=["contact"], subdomain_size=0.16, names={"contact": 1}
    )
    ref = build_domain(
        COMM, GeometrySpec(mesh=str(disk_files[4.1]), subdomain_size=0.16, signorini=["contact"])
    )
    assert api.coarse.n_subdomains == ref.coarse.n_subdomains
    assert api.coarse.n_vertices == ref.coarse.n_vertices
    assert np.isclose(api.arcs[0].length, ref.arcs[0].length)


def test_disk_shape():
    from fem_py.mesh import GeometrySpec, build_domain

    c = 0.25 / math.sqrt(2)
    domain = build_domain(
        COMM,
        GeometrySpec(
            "disk", h=0.02, subdomain_size=0.08, radius=0.25, signorini=[[(-c, -c), (c, -c)]]
        ),
    )
    assert domain.shape == "disk" and domain.h == 0.02
    assert np.isclose(domain.arcs[0].length, 0.25 * math.pi / 2, rtol=1e-3)
    # arc ends are coarse vertices
    ends = np.array([domain.arcs[0].start, domain.arcs[0].end])
    assert np.linalg.norm(domain.coarse.vertex_coords[:, None] - ends, axis=2).min(0).max() < 1e-12
    with pytest.raises(ValueError, match="signorini arc 0: point .* is not on the circle"):
        build_domain(
            COMM, GeometrySpec("disk", h=0.02, subdomain_size=0.08, signorini=[[(0, 0), (c, -c)]])
        )


# ------------------------------------------------------------------ convergence, iterations
def test_manufactured_solution_on_a_disk_from_a_file_converges_like_h2(tmp_path):
    from coupling.manufactured import disk_contact, solution_errors
    from coupling.options import SolverOptions
    from coupling.problem import SignoriniProblem
    from coupling.solvers import solve
    from fem_py.forms import make_material
    from fem_py.mesh import GeometrySpec, build_domain

    solution, material = disk_contact(), make_material("carstensen")
    errors = []
    for h, version in ((1 / 32, 2.2), (1 / 64, 4.1), (1 / 128, 4.1)):
        path = disk_msh(tmp_path / f"d{h}.msh", h, version=version) if COMM.rank == 0 else None
        path = COMM.bcast(str(path), root=0)
        domain = build_domain(
            COMM, GeometrySpec(mesh=path, subdomain_size=4 * h, signorini=["contact"])
        )
        data = solution.data(domain.mesh, material)
        problem = SignoriniProblem(domain, material, **data)
        result = solve(problem, SolverOptions())
        assert result.converged and result.iterations <= 15
        errors.append(solution_errors(problem, solution, result))
    for key in ("nodal_u", "gap"):
        e = [err[key] for err in errors]
        rates = [math.log2(e[i] / e[i + 1]) for i in range(2)]
        assert min(rates) > 1.5 and sum(rates) / 2 > 1.7, (key, e, rates)
    # the contact set: right away from the switch point x = 0 (one node of 80 measured
    # off at h = 1/128, next to the excluded band)
    assert sum(err["contact_mismatch"] for err in errors) <= 1, errors


def test_imported_square_iterations_against_the_generated_one(tmp_path):
    from coupling.options import SolverOptions
    from coupling.problem import SignoriniProblem
    from coupling.solvers import solve
    from fem_py.forms import make_material
    from fem_py.mesh import GeometrySpec, build_domain

    h = 1 / 32
    path = square_msh(tmp_path / "sq.msh", h)
    counts = {}
    for kind in ("generated", "imported"):
        if kind == "generated":
            domain = build_domain(
                COMM,
                GeometrySpec(
                    "square", h=h, subdomain_size=4 * h, signorini=["bottom"], structured=False
                ),
            )
        else:
            domain = build_domain(
                COMM, GeometrySpec(mesh=str(path), subdomain_size=4 * h, signorini=["bottom"])
            )
        problem = SignoriniProblem(domain, make_material("carstensen"), f="2", t0="-1")
        counts[kind] = [solve(problem, SolverOptions(method=m)).iterations for m in ("pgpm", "ssn")]
    assert counts["imported"][1] <= 15
    # the target; measured 155 against 125 (module docstring)
    assert counts["imported"][0] <= 1.3 * counts["generated"][0], counts


# ------------------------------------------------------------------ MPI
def test_two_ranks_equal_serial(disk_files, tmp_path):
    _, _, serial = _solve_file(disk_files[4.1])
    out = tmp_path / "mpi.json"
    run_mpi(2, str(ROOT / "tests" / "mpi" / "own_mesh_check.py"), str(disk_files[4.1]), str(out))
    got = json.loads(out.read_text())
    assert got["iterations"] == serial.iterations
    assert np.allclose(got["phi"], serial.phi, atol=1e-9)


# ------------------------------------------------------------------ bad input
@pytest.fixture(scope="module")
def bad_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("bad")
    files = {k: bad_msh(folder / f"{k}.msh", k) for k in ("3d", "quads", "order2", "hole")}
    files["two_bodies"] = bad_msh(folder / "two_bodies.msh", "two_bodies")
    files["interior_curve"] = bad_msh(folder / "interior_curve.msh", "interior_curve")
    (folder / "text.msh").write_text("this is not a mesh\n")
    files["text"] = folder / "text.msh"
    files["disk"] = disk_msh(folder / "disk.msh", 0.05)
    files["big"] = disk_msh(folder / "big.msh", 0.2, radius=0.6)
    return files


@pytest.mark.parametrize(
    "case, geometry, message",
    [
        # issue 29 item 11: the key once ("geometry.mesh: file", not "geometry.mesh: mesh:")
        ("missing", {}, r"geometry.mesh: file .*nope.msh' not found"),
        ("text", {}, r"geometry.mesh: '.*text.msh' is not a gmsh mesh file"),
        # a 3D mesh file is a body (tests/test_cli_solid.py); a planar key is refused with it
        ("3d", {"subdomain_size": 0.1}, r"geometry.subdomain_size: .*for a 3D body"),
        ("quads", {}, r"Quadrilateral 4 elements; fembem needs linear 3-node triangles"),
        ("order2", {}, r"Triangle 6 elements"),
        ("hole", {}, r"Omega has a hole .* one simply connected Omega"),
        ("two_bodies", {}, r"2 separate bodies; the exterior problem needs one simply connected"),
        (
            "disk",
            {"signorini": ["nope"]},
            r"no physical curve group 'nope'; its curve groups " r"are 'contact', 'free', 'left'",
        ),
        ("disk", {"signorini": ["omega"]}, r"group 'omega' .* is a surface, not a curve"),
        ("interior_curve", {"signorini": ["inside"]}, r"group 'inside' .* has no boundary facets"),
        ("disk", {"signorini": ["free", "left"]}, r"groups 'free' and 'left' overlap"),
        ("big", {}, r"geometry.allow_large: diam\(Omega\) = 1.199 >= 1"),
        ("disk", {"h": 0.1}, r"geometry.h: the mesh file geometry.mesh sets the geometry"),
        ("disk", {"shape": "square"}, r"geometry.shape: the mesh file"),
    ],
)
def test_bad_input_is_one_line_exit_2_and_no_output(bad_files, tmp_path, case, geometry, message):
    path = bad_files.get(case, tmp_path / "nope.msh")
    lines = [f'mesh = "{path}"'] + [f"{k} = {json.dumps(v)}" for k, v in geometry.items()]
    config = tmp_path / "c.toml"
    config.write_text("[geometry]\n" + "\n".join(lines) + "\n")
    out = tmp_path / "out"
    proc = run_cli("solve", str(config), "--out", str(out), "--quiet")
    assert proc.returncode == 2, proc.stderr
    err = proc.stderr.strip()
    assert len(err.splitlines()) == 1 and err.startswith("fembem: error: "), err
    import re

    assert re.search(message, err), err
    assert not out.exists() and not any(p.name.startswith(".out") for p in tmp_path.iterdir())


def test_relative_mesh_path_is_relative_to_the_configuration_file(tmp_path):
    from coupling.app.config import load_config

    (tmp_path / "sub").mkdir()
    config = tmp_path / "sub" / "c.toml"
    config.write_text('[geometry]\nmesh = "m.msh"\nsignorini = ["contact"]\n')
    assert load_config(config).geometry.mesh == str(tmp_path / "sub" / "m.msh")


# ------------------------------------------------------------------ the demo
@pytest.mark.parametrize("nprocs", [None, 2])
def test_own_mesh_demo(tmp_path, nprocs):
    """demos/demo_own_mesh.py, serially and on 2 ranks (the same numbers)."""
    import subprocess

    argv = [str(ROOT / "demos" / "demo_own_mesh.py"), "--cells", "16", "--out", str(tmp_path)]
    if nprocs:
        run_mpi(nprocs, *argv)
    else:
        proc = subprocess.run(
            [sys.executable, *argv], capture_output=True, text=True, timeout=300, cwd=ROOT
        )
        assert proc.returncode == 0, proc.stderr[-4000:]
    results = json.loads((tmp_path / "results.json").read_text())
    # measured at h = 1/32: 22 subdomains, ssn 11 steps, max |u - u_h| = 2.34e-3,
    # gap error 2.07e-3, 5 of 12 Signorini nodes in contact
    assert results["converged"] and results["iterations"] <= 15
    assert results["subdomains"] == 22 and results["errors"]["contact_mismatch"] == 0
    assert results["errors"]["nodal_u"] < 3e-3 and results["errors"]["gap"] < 3e-3
    assert 0 < results["contact"] < results["signorini_nodes"]
    assert (tmp_path / "subdomains.png").is_file() and (tmp_path / "disk.msh").is_file()


@pytest.mark.parametrize("structured", [False, True])
def test_finely_drawn_polygon_gets_subdomains_of_size_d(structured):
    """A 480-gon and a 48-gon of one circle at h = 1/64, d = 1/16 (sides 0.0033 and 0.033,
    both < d): the 48-gon gave 454 subdomains (coarse triangles following the vertex
    spacing) and the 480-gon 21,515 dofs (boundary nodes at every vertex); now the
    polygon is resampled at h (unstructured, automatic partition) or d (structured,
    coarse triangles), keeping its corners and the arc ends (issue 17's targets)."""
    from fem_py.mesh import GeometrySpec, build_domain

    h, d = 1 / 64, 1 / 16
    sizes = {}
    for n in (48, 480):
        t = 2 * np.pi * np.arange(n) / n
        V = 0.25 * np.column_stack([np.cos(t), np.sin(t)])
        arc = [V[n * 5 // 8].tolist(), V[n * 7 // 8].tolist()]
        domain = build_domain(
            COMM,
            GeometrySpec(
                "polygon",
                h=h,
                subdomain_size=d,
                vertices=V.tolist(),
                signorini=[arc],
                structured=structured,
            ),
        )
        area = 0.5 * n * 0.25**2 * np.sin(2 * np.pi / n)
        dofs = domain.mesh.topology.index_map(0).size_global
        sizes[n] = dofs
        assert domain.coarse.n_subdomains <= 3 * area / d**2, (n, domain.coarse.n_subdomains)
        assert domain.coarse.n_subdomains >= area / d**2 / 3, (n, domain.coarse.n_subdomains)
        assert domain.h_max <= 2 * h, (n, domain.h_max / h)
        ends = np.array([domain.arcs[0].start, domain.arcs[0].end])
        dist = np.linalg.norm(domain.coarse.vertex_coords[:, None] - ends, axis=2).min(0)
        assert dist.max() < 1e-12  # the arc ends are coarse vertices
    assert max(sizes.values()) <= 1.5 * min(sizes.values()), sizes


def test_coarsened_polygon_keeps_corners_and_arc_ends():
    from fem_py.polyline import coarsened_polygon

    # a finely drawn square (sides of 0.5 cut into 200 pieces) and a point inside a piece
    t = np.linspace(0, 1, 201)[:-1]
    side = np.column_stack([t, np.zeros_like(t)]) * 0.5
    square = np.concatenate(
        [side, side[:, ::-1] * [-1, 1] + [0.5, 0], 0.5 - side, side[:, ::-1] * [1, -1] + [0, 0.5]]
    )
    keep = [np.array([0.1234, 0.0])]
    p = coarsened_polygon(square, 0.1, keep, math.pi / 6, 1e-12)
    corners = np.array([[0, 0], [0.5, 0], [0.5, 0.5], [0, 0.5]])
    for q in list(corners) + keep:
        assert np.linalg.norm(p - q, axis=1).min() < 1e-12, q
    sides = np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1)
    assert sides.max() <= 0.1 + 0.0025 + 1e-12 and sides.min() >= 0.04, sides
    # counter-clockwise still, and every vertex one of the given ones (or a kept point)
    area = 0.5 * np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1])
    assert area == pytest.approx(0.25)
