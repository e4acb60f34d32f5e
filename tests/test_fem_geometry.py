"""fem_py.mesh: mesh and coarse-partition invariants (docs/method.md section 6) for the
square, the L-shape and a polygon, structured and unstructured, and the error cases."""
from __future__ import annotations

import numpy as np
import pytest
from mpi4py import MPI

from fem_py.dofs import p1_space
from fem_py.mesh import GeometrySpec, build_domain
from fem_py.mesh.domain import max_facet_length
from fem_py.tags import GAMMA_T_TAG, SIGNORINI_TAG0

COMM = MPI.COMM_WORLD
H, D = 1.0 / 32, 1.0 / 8
POLY = [(0.0, 0.0), (0.5, 0.0), (0.6, 0.35), (0.3, 0.55), (-0.05, 0.4)]

CASES = {
    "square": dict(shape="square", signorini=["bottom"]),
    "square-structured": dict(
        shape="square", structured=True, signorini=["left", ((0.125, -0.25), (0.25, 0.0))]
    ),
    "square-inserted": dict(shape="square", signorini=[((-0.2, -0.25), (0.25, 0.1))]),
    "lshape": dict(shape="lshape", signorini=["notch_bottom", "notch_left"]),
    "lshape-structured": dict(shape="lshape", structured=True, signorini="all"),
    "polygon": dict(shape="polygon", vertices=POLY, signorini=[((0.2, 0.0), (0.55, 0.175))]),
    "polygon-structured": dict(
        shape="polygon", vertices=POLY, structured=True, signorini=["side3"]
    ),
}


@pytest.fixture(scope="module", params=list(CASES))
def domain(request):
    kw = {"structured": False, **CASES[request.param]}
    return build_domain(COMM, GeometrySpec(kw.pop("shape"), h=H, subdomain_size=D, **kw))


def _serial_mesh_data(dom):
    """Cells (dofs), cell tags, dof coordinates of the serial mesh."""
    assert COMM.size == 1
    V = p1_space(dom.mesh)
    X = V.tabulate_dof_coordinates()[:, :2]
    cells = V.dofmap.list.array.reshape(-1, 3)
    tags = np.full(len(cells), -1)
    tags[dom.cell_tags.indices] = dom.cell_tags.values
    return V, X, cells, tags


def _polygon_area(P):
    x, y = P[:, 0], P[:, 1]
    return 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)


def _arc_position(P, q):
    """(arc-length position, perimeter, distance, side index) of a boundary point q along
    the CCW polygon P (independent of fem_py)."""
    best, pos, side, acc = np.inf, None, None, 0.0
    for i in range(len(P)):
        a, b = P[i], P[(i + 1) % len(P)]
        L = np.linalg.norm(b - a)
        t = np.clip(np.dot(q - a, b - a) / L**2, 0, 1)
        dist = np.linalg.norm(a + t * (b - a) - q)
        if dist < best:
            best, pos, side = dist, acc + t * L, i
        acc += L
    return pos, acc, best, side


def test_cells_in_exactly_one_subdomain(domain):
    V, X, cells, tags = _serial_mesh_data(domain)
    n = domain.coarse.n_subdomains
    assert len(np.unique(domain.cell_tags.indices)) == len(cells) == len(domain.cell_tags.indices)
    assert tags.min() == 0 and tags.max() == n - 1
    area = 0.5 * np.abs(np.cross(X[cells[:, 1]] - X[cells[:, 0]], X[cells[:, 2]] - X[cells[:, 0]]))
    sub_area = np.bincount(tags, weights=area, minlength=n)
    assert np.all(sub_area > 0)
    total = _polygon_area(domain.vertices)
    assert sub_area.sum() == pytest.approx(total, rel=1e-13)
    if domain.shape in ("square", "lshape"):
        # coarse squares are resolved exactly: every subdomain has area c^2 (round-off only)
        assert np.allclose(sub_area, domain.coarse_size**2, rtol=1e-12)
    # number of subdomains ~ area / d^2 (coarse triangles of size d: ~2.3 per d^2)
    ratio = n / (total / D**2)
    assert 0.7 <= ratio <= 5.0


def test_skeleton_is_resolved_and_counted(domain):
    """Sum of segments over coarse edges = number of skeleton facets counted on the mesh;
    every coarse edge is a straight chain of mesh edges between its two end vertices."""
    c = domain.coarse
    V, X, cells, tags = _serial_mesh_data(domain)
    msh = domain.mesh
    msh.topology.create_connectivity(1, 2)
    f2c = msh.topology.connectivity(1, 2)
    n_skel = 0
    for f in range(msh.topology.index_map(1).size_local):
        cs = f2c.links(f)
        n_skel += len(cs) == 1 or tags[cs[0]] != tags[cs[1]]
    assert c.edge_segments().sum() == n_skel == c.n_skeleton_facets
    edges = set()
    for cell in cells:
        for a, b in ((0, 1), (1, 2), (2, 0)):
            edges.add((min(cell[a], cell[b]), max(cell[a], cell[b])))
    for k, dofs in enumerate(c.edge_dofs):
        v0, v1 = c.edge_vertices[k]
        assert dofs[0] == c.vertex_dofs[v0] and dofs[-1] == c.vertex_dofs[v1]
        assert all((min(p, q), max(p, q)) in edges for p, q in zip(dofs[:-1], dofs[1:]))
        a, b = c.vertex_coords[v0], c.vertex_coords[v1]
        e = b - a
        t = (X[dofs] - a) @ e / (e @ e)
        dist = np.abs(np.cross(e, X[dofs] - a)) / np.linalg.norm(e)
        assert np.all(dist < 1e-12) and np.all(np.diff(t) > 0)
        assert np.allclose(c.edge_coords[k], X[dofs], atol=1e-15)
    assert np.allclose(X[c.vertex_dofs], c.vertex_coords, atol=1e-15)
    # Euler: coarse vertices - coarse edges + subdomains = 1 for a simply connected Omega
    assert c.n_vertices - c.n_edges + c.n_subdomains == 1


def test_dof_partition(domain):
    c = domain.coarse
    V, X, cells, tags = _serial_mesh_data(domain)
    N = V.dofmap.index_map.size_global
    assert c.n_dofs == N
    assert np.array_equal(np.sort(np.concatenate([c.skeleton_dofs, c.interior_dofs])), np.arange(N))
    assert np.all(np.diff(c.skeleton_dofs) > 0) and np.all(np.diff(c.interior_dofs) > 0)
    on_edges = np.unique(np.concatenate(c.edge_dofs))
    assert np.array_equal(on_edges, c.skeleton_dofs)
    sub = np.full(N, -1)
    sub[c.interior_dofs] = c.subdomain_of_interior_dof
    for cell, t in zip(cells, tags):
        inner = cell[sub[cell] >= 0]
        assert np.all(sub[inner] == t)


def test_arcs_and_boundary_edges(domain):
    c = domain.coarse
    P = domain.vertices
    assert np.array_equal(c.edge_on_boundary, c.edge_subdomains[:, 1] == -1)
    for arc in domain.arcs:
        if arc.whole:
            continue
        for q in (arc.start, arc.end):
            assert np.linalg.norm(c.vertex_coords - np.asarray(q), axis=1).min() < 1e-12
    for k in np.flatnonzero(c.edge_on_boundary):
        assert c.vertex_on_boundary[c.edge_vertices[k]].all()
        pts = c.edge_coords[k]
        for p, q in zip(pts[:-1], pts[1:]):
            s, L, dist, side = _arc_position(P, 0.5 * (p + q))
            assert dist < 1e-12
            # counter-clockwise along Gamma: same direction as the side of the CCW polygon
            assert np.dot(q - p, P[(side + 1) % len(P)] - P[side]) > 0
            # every segment midpoint lies in the arc the edge is tagged with (and no other)
            inside = [
                j for j, a in enumerate(domain.arcs) if a.whole or 0 < (s - a.s0) % L < a.length
            ]
            assert inside == ([] if c.edge_arc[k] < 0 else [c.edge_arc[k]])
    assert np.all(c.edge_arc[~c.edge_on_boundary] == -1)
    expected_tags = {
        GAMMA_T_TAG if a < 0 else SIGNORINI_TAG0 + a for a in c.edge_arc[c.edge_on_boundary]
    }
    assert set(np.unique(domain.facet_tags.values)) == expected_tags


def test_input_node_numbers_are_the_mesh_s_read_once(domain):
    """fem_py.dofs.input_node_numbers is the mesh's input_global_indices, read once per
    mesh (the same read-only array on every call, so that no caller can change it)."""
    from fem_py.dofs import input_node_numbers

    numbers = input_node_numbers(domain.mesh)
    assert np.array_equal(numbers, domain.mesh.geometry.input_global_indices)
    assert input_node_numbers(domain.mesh) is numbers and not numbers.flags.writeable


def test_structured_is_uniform():
    dom = build_domain(
        COMM, GeometrySpec("square", h=1 / 16, subdomain_size=1 / 4, structured=True)
    )
    seg = dom.coarse.edge_segments()
    assert np.all(seg == 4)  # n = d/h per coarse edge
    assert dom.coarse.n_dofs == 9 * 9 and dom.coarse.n_subdomains == 4
    assert dom.h_max == pytest.approx(np.sqrt(2) * 0.5 / 8, rel=1e-14)  # diagonal of the h-square
    X = p1_space(dom.mesh).tabulate_dof_coordinates()[:, :2]
    grid = np.round((X + 0.25) * 16, 9)
    assert np.allclose(grid, np.round(grid))  # all nodes on the h-grid


@pytest.mark.parametrize("shape", ["square", "lshape"])
def test_structured_grid_knows_its_longest_facet(shape):
    # written down from the grid (no pass over the cells), equal to the one measured
    spec = GeometrySpec(shape, h=0.03, subdomain_size=0.11, structured=True)
    dom = build_domain(COMM, spec)
    assert dom.h_max == pytest.approx(max_facet_length(dom.mesh), rel=1e-14)


def test_whole_boundary_flag():
    dom = build_domain(
        COMM,
        GeometrySpec("square", h=1 / 16, subdomain_size=1 / 4, structured=True, signorini="all"),
    )
    assert dom.signorini_is_whole_boundary and dom.arcs[0].whole
    assert np.all(dom.coarse.edge_arc[dom.coarse.edge_on_boundary] == 0)
    assert not build_domain(
        COMM,
        GeometrySpec(
            "square", h=1 / 16, subdomain_size=1 / 4, signorini=["bottom"], structured=False
        ),
    ).signorini_is_whole_boundary


def test_allow_large():
    dom = build_domain(
        COMM,
        GeometrySpec(
            "square", h=1 / 4, subdomain_size=1 / 2, width=1.0, structured=True, allow_large=True
        ),
    )
    assert dom.diameter == pytest.approx(np.sqrt(2), rel=1e-15)


ERRORS = [
    (("square",), dict(h=0.0, subdomain_size=0.1), "h must be a positive number"),
    (("square",), dict(h=-0.1, subdomain_size=0.1), "h must be a positive number"),
    (("square",), dict(h=0.1, subdomain_size=0.15), "smaller than 2h"),
    (("disc",), dict(h=0.1, subdomain_size=0.2), "shape must be one of"),
    (("square",), dict(h=0.05, subdomain_size=0.1, width=1.0), "diam(Omega)"),
    (
        ("square",),
        dict(h=0.05, subdomain_size=0.1, signorini=[((0.0, 0.0), (0.25, 0.0))]),
        "not on the boundary",
    ),
    (
        ("square",),
        dict(h=0.05, subdomain_size=0.1, signorini=[((0.0, -0.25), (0.0, -0.25))]),
        "end equals its start",
    ),
    (("square",), dict(h=0.05, subdomain_size=0.1, signorini=["north"]), "unknown side 'north'"),
    (
        ("square",),
        dict(h=0.05, subdomain_size=0.1, signorini=["bottom", ((0.0, -0.25), (0.25, 0.0))]),
        "overlap",
    ),
    (("square",), dict(h=0.05, subdomain_size=0.1, signorini=["all", "top"]), "cannot be combined"),
    (
        ("square",),
        dict(
            h=1 / 32, subdomain_size=1 / 8, structured=True, signorini=[((0.1, -0.25), (0.25, 0.0))]
        ),
        "not a coarse grid vertex",
    ),
    (
        ("polygon",),
        dict(h=0.05, subdomain_size=0.1, vertices=[(0, 0), (0.4, 0)]),
        "at least 3 vertices",
    ),
    (
        ("polygon",),
        dict(h=0.05, subdomain_size=0.1, vertices=[(0, 0), (0, 0.4), (0.4, 0)]),
        "clockwise",
    ),
    (
        ("polygon",),
        dict(h=0.05, subdomain_size=0.1, vertices=[(0, 0), (0.4, 0.4), (0.4, 0), (0, 0.4)]),
        "intersect",
    ),
    (
        ("polygon",),
        dict(h=0.05, subdomain_size=0.1, vertices=[(0, 0), (0.4, 0), (0.2, 0)]),
        "fold back",
    ),
    (("polygon",), dict(h=0.05, subdomain_size=0.1), "needs vertices"),
    (("square",), dict(h=0.05, subdomain_size=0.1, vertices=POLY), "only used by shape 'polygon'"),
]


@pytest.mark.parametrize("args, kw, match", ERRORS, ids=[e[2] for e in ERRORS])
def test_errors(args, kw, match):
    with pytest.raises(ValueError) as err:
        build_domain(COMM, GeometrySpec(*args, **{"structured": False, **kw}))
    assert match in str(err.value) and "\n" not in str(err.value)
