"""fem_py.boundary: the counter-clockwise boundary order, T, E, boundary data and the
distributed gather/scatter (docs/method.md section 4)."""
from __future__ import annotations

import numpy as np
import pytest
from dolfinx import fem
from dolfinx import mesh as dmesh
from mpi4py import MPI

from fem_py.boundary import BoundaryMap
from fem_py.dofs import p1_space
from fem_py.forms import InteriorForms, make_material
from fem_py.mesh import GeometrySpec, build_domain
from fem_py.tags import SIGNORINI_TAG0

COMM = MPI.COMM_WORLD
POLY = [(0.0, 0.0), (0.5, 0.0), (0.6, 0.35), (0.3, 0.55), (-0.05, 0.4)]
CASES = {
    "square": dict(shape="square", signorini=["bottom", ((0.25, 0.1), (0.0, 0.25))]),
    "lshape": dict(
        shape="lshape", structured=True, signorini=["notch_bottom", "notch_left", "left"]
    ),
    "polygon": dict(shape="polygon", vertices=POLY, signorini=[((0.2, 0.0), (0.55, 0.175))]),
    "all": dict(shape="square", structured=True, signorini="all"),
}


@pytest.fixture(scope="module", params=list(CASES))
def case(request):
    kw = {"structured": False, **CASES[request.param]}
    dom = build_domain(COMM, GeometrySpec(kw.pop("shape"), h=1 / 16, subdomain_size=1 / 8, **kw))
    V = p1_space(dom.mesh)
    return dom, V, BoundaryMap(V, dom)


def _area(P):
    x, y = P[:, 0], P[:, 1]
    return 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)


def test_closed_ccw_and_mesh_nodes(case):
    dom, V, bm = case
    assert bm.nodes.shape == (bm.n_gamma, 2) and len(np.unique(bm.dofs)) == bm.n_gamma
    # Gamma_h is the polygon itself: its shoelace area is |Omega| (positive: CCW)
    assert _area(bm.nodes) == pytest.approx(_area(dom.vertices), rel=1e-13)
    assert bm.length == pytest.approx(
        np.sum(np.linalg.norm(np.roll(dom.vertices, -1, 0) - dom.vertices, axis=1)), rel=1e-13
    )
    assert np.allclose(bm.nodes[0], dom.vertices[0], atol=1e-15)
    # consecutive nodes (and last -> first) are joined by a boundary facet
    fdim = 1
    dom.mesh.topology.create_connectivity(fdim, 2)
    bf = dmesh.exterior_facet_indices(dom.mesh.topology)
    assert len(bf) == bm.n_gamma
    bdofs = fem.locate_dofs_topological(V, fdim, bf)
    assert np.array_equal(np.sort(bdofs), np.sort(bm.dofs))  # serial: local = global
    X = V.tabulate_dof_coordinates()[:, :2]
    assert np.allclose(X[bm.dofs], bm.nodes, atol=1e-15)
    f2v = dom.mesh.topology.connectivity(fdim, 0)
    dom.mesh.topology.create_connectivity(2, 0)
    c2v = dom.mesh.topology.connectivity(2, 0).array.reshape(-1, 3)
    v2dof = np.empty(c2v.max() + 1, dtype=np.int64)
    v2dof[c2v.ravel()] = V.dofmap.list.array
    pairs = {tuple(sorted(v2dof[f2v.links(f)])) for f in bf}
    cyc = {tuple(sorted((a, b))) for a, b in zip(bm.dofs, np.roll(bm.dofs, -1))}
    assert pairs == cyc
    assert np.allclose(np.diff(bm.s), bm.panel_lengths[:-1], rtol=1e-14)
    assert bm.s[0] == 0.0


def test_signorini_nodes(case):
    """phi unknowns: exactly the nodes strictly inside an arc (ends excluded unless
    Gamma_s = Gamma)."""
    dom, V, bm = case
    if dom.signorini_is_whole_boundary:
        assert np.array_equal(bm.signorini, np.arange(bm.n_gamma))
        return
    L = bm.length
    expected, arc_of = [], []
    for i in range(bm.n_gamma):
        for k, arc in enumerate(dom.arcs):
            # s measured from the first polygon vertex = nodes[0]
            r = (bm.s[i] - arc.s0) % L
            if 1e-12 < r < arc.length - 1e-12:
                expected.append(i)
                arc_of.append(k)
    assert np.array_equal(bm.signorini, expected)
    assert np.array_equal(bm.arc_of_signorini, arc_of)
    # panels tagged with the arc of their end nodes
    for i, k in zip(bm.signorini, bm.arc_of_signorini):
        assert bm.panel_tags[i] == bm.panel_tags[i - 1] == SIGNORINI_TAG0 + k
    # boundary coarse edges appear as contiguous runs in boundary order
    pos = {d: i for i, d in enumerate(bm.dofs)}
    c = dom.coarse
    for k in np.flatnonzero(c.edge_on_boundary):
        idx = np.array([pos[d] for d in c.edge_dofs[k]])
        assert np.all((np.diff(idx) % bm.n_gamma) == 1)


def test_trace_and_extension(case):
    dom, V, bm = case
    T, E = bm.trace_matrix(), bm.extension_matrix()
    N = V.dofmap.index_map.size_global
    assert T.shape == (bm.n_gamma, N) and E.shape == (bm.n_gamma, bm.n_signorini)
    X = V.tabulate_dof_coordinates()[:, :2]
    assert np.allclose(T @ X[:, 0], bm.nodes[:, 0], atol=0) and np.allclose(
        T @ X[:, 1], bm.nodes[:, 1], atol=0
    )
    assert abs(T @ T.T - np.eye(bm.n_gamma)).max() == 0
    assert abs(E.T @ E - np.eye(bm.n_signorini)).max() == 0
    phi = np.arange(1.0, bm.n_signorini + 1)
    z = E @ phi
    assert np.array_equal(z[bm.signorini], phi) and np.count_nonzero(z) == bm.n_signorini


def test_gather_scatter(case):
    dom, V, bm = case
    u = fem.Function(V)
    u.interpolate(lambda x: 1 + 2 * x[0] - 3 * x[1])
    assert np.allclose(bm.gather(u.vector), 1 + 2 * bm.nodes[:, 0] - 3 * bm.nodes[:, 1], atol=1e-15)
    w = u.vector.duplicate()
    w.set(0.0)
    vals = np.linspace(-1, 1, bm.n_gamma)
    bm.scatter_add(vals, w)
    bm.scatter_add(vals, w)
    T = bm.trace_matrix()
    assert np.allclose(w.array, 2 * (T.T @ vals), atol=0)
    w.destroy()


def test_boundary_data(case):
    dom, V, bm = case
    x, y = bm.nodes[:, 0], bm.nodes[:, 1]
    assert np.allclose(bm.interpolate_boundary("x^2 + y"), x**2 + y, atol=1e-15)
    assert np.allclose(bm.interpolate_boundary(lambda x, y: x * y), x * y, atol=0)
    assert np.allclose(
        bm.interpolate_boundary(lambda x, y, nx, ny: nx), bm.node_normals[:, 0], atol=0
    )
    assert np.allclose(bm.interpolate_boundary(1.5), 1.5)
    assert np.allclose(np.linalg.norm(bm.node_normals, axis=1), 1.0, atol=1e-15)
    # panel normals point out of Omega: (dy, -dx)/h for CCW panels, outward by the shoelace sign
    seg = np.roll(bm.nodes, -1, 0) - bm.nodes
    assert np.allclose(
        bm.panel_normals[:, 0] * seg[:, 0] + bm.panel_normals[:, 1] * seg[:, 1], 0, atol=1e-15
    )
    assert np.sum(
        np.sum(bm.panel_normals * (bm.nodes + 0.5 * seg), axis=1) * bm.panel_lengths
    ) == pytest.approx(
        2 * _area(bm.nodes), rel=1e-12
    )  # int x.n ds = 2|Omega|
    with pytest.raises(ValueError, match="unknown name 'z'"):
        bm.interpolate_boundary("z")


def test_square_node_normals():
    dom = build_domain(COMM, GeometrySpec("square", h=1 / 8, subdomain_size=1 / 4, structured=True))
    bm = BoundaryMap(p1_space(dom.mesh), dom)
    assert np.allclose(
        bm.node_normals[0], [-np.sqrt(0.5), -np.sqrt(0.5)], atol=1e-15
    )  # corner (-1/4, -1/4)
    assert np.allclose(bm.node_normals[1], [0.0, -1.0], atol=1e-15)  # bottom side
    forms = InteriorForms(p1_space(dom.mesh), make_material("linear"), None)
    m = forms.boundary_load("nx*x", bm)
    # int_Gamma nx x v_j ds: on the right side (x = 1/4) the hats sum to the side length
    assert m.sum() == pytest.approx(2 * 0.5 * 0.25, rel=1e-13)
