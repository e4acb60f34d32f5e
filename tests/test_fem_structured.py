"""The structured refinement written down piece by piece (fem_py.mesh.structured): every
piece agrees with the whole, the triangles tile the coarse cells, the ghosts and
boundary segments it reports agree with a brute-force facet search, and the coarse
structure written down from it (fem_py.mesh.structured_coarse) is the one recovered from
the mesh (serially here, under mpirun -n 3 in tests/mpi/structured_tags_check.py)."""
import numpy as np
import pytest

from fem_py.mesh.shapes import grid_partition as _grid_partition
from fem_py.mesh.structured import lattice, refine


def _areas(x, tris):
    a, b, c = x[tris[:, 0]], x[tris[:, 1]], x[tris[:, 2]]
    return 0.5 * ((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])


def _facets(tris):
    """(sorted node pair, triangle) for every facet of every triangle."""
    f = np.sort(tris[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2), axis=1)
    return f, np.repeat(np.arange(len(tris)), 3)


@pytest.fixture(params=["quads", "triangles"])
def coarse(request):
    if request.param == "quads":
        _, V, cells, _ = _grid_partition("lshape", (0.5, 0.5), 0.5, 0.125)
        return V, np.array(cells)
    V = np.array([[0.0, 0.0], [1.0, 0.0], [0.2, 0.9], [1.1, 1.0], [0.5, -0.7]])
    return V, np.array([[0, 1, 2], [1, 3, 2], [0, 4, 1]])


@pytest.mark.parametrize("corners", [3, 4])
@pytest.mark.parametrize("n", [2, 3, 5])
def test_lattice_tiles_the_reference_cell(corners, n):
    lat = lattice(corners, n)
    assert len(lat.triangles) == (2 if corners == 4 else 1) * n * n
    # every facet on side s is found, and the sides hold n segments each
    for s, tris in enumerate(lat.side_triangles):
        assert len(tris) == n
        assert np.all(np.isin(lat.triangles[tris], lat.sides[s]).sum(1) == 2)
    assert len(lat.interior) == ((n - 1) ** 2 if corners == 4 else (n - 1) * (n - 2) // 2)


def test_pieces_agree_with_the_whole(coarse):
    V, cells = coarse
    ref = refine(V, cells, 4)
    N = ref.n_nodes
    x = ref.coordinates(0, N)
    for P in (2, 3, 7):  # node blocks and coarse-cell subsets as P ranks make them
        cuts = [r * N // P for r in range(P + 1)]
        np.testing.assert_array_equal(
            np.concatenate([ref.coordinates(a, b) for a, b in zip(cuts, cuts[1:])]), x
        )
    whole = ref.triangles(np.arange(len(cells)))
    T = ref.triangles_per_cell
    for ids in (np.array([1]), np.arange(0, len(cells), 2)):
        np.testing.assert_array_equal(
            ref.triangles(ids), whole.reshape(len(cells), T, 3)[ids].reshape(-1, 3)
        )
    # the triangles tile the coarse cells: all nodes used once at least, positive areas
    # summing to each coarse cell's area (round-off)
    assert np.array_equal(np.unique(whole), np.arange(N))
    area = _areas(x, whole).reshape(len(cells), T)
    assert area.min() > 0
    q = V[cells]
    coarse_area = 0.5 * np.sum(
        q[:, :, 0] * np.roll(q[:, :, 1], -1, 1) - np.roll(q[:, :, 0], -1, 1) * q[:, :, 1], 1
    )
    np.testing.assert_allclose(area.sum(1), coarse_area, rtol=1e-13)
    # conformity: every facet lies in one or two triangles
    f, _ = _facets(whole)
    _, count = np.unique(f, axis=0, return_counts=True)
    assert count.max() == 2


def test_segments_on_coarse_edges_and_ghosts(coarse):
    V, cells = coarse
    ref = refine(V, cells, 3)
    T = ref.triangles_per_cell
    tris = ref.triangles(np.arange(len(cells)))
    x = ref.coordinates(0, ref.n_nodes)
    f, owner_tri = _facets(tris)
    edge = ref.edge_of_segments(ref.node_numbers(f[:, 0]), ref.node_numbers(f[:, 1]))
    # a facet lies on coarse edge e iff its midpoint lies on the segment between e's vertices
    mid = x[f].mean(1)
    a, b = V[ref.edges[:, 0]], V[ref.edges[:, 1]]
    t, r = b - a, mid[:, None, :] - a[None]
    cross = np.abs(t[None, :, 0] * r[:, :, 1] - t[None, :, 1] * r[:, :, 0])
    s = (r * t[None]).sum(2) / (t * t).sum(1)[None]
    on = (cross < 1e-12) & (s > 0) & (s < 1)
    assert np.all(on.sum(1) <= 1)
    np.testing.assert_array_equal(edge, np.where(on.any(1), on.argmax(1), -1))
    # ghosts against a brute-force facet search, for a few rank assignments
    rng = np.random.default_rng(3)
    for _ in range(3):
        rank_of_cell = rng.integers(0, 3, size=len(cells))
        owner = np.repeat(rank_of_cell, T)
        code = f[:, 0] * ref.n_nodes + f[:, 1]
        order = np.argsort(code, kind="stable")
        same = np.flatnonzero(code[order][1:] == code[order][:-1])
        p, q = owner_tri[order[same]], owner_tri[order[same + 1]]
        for rank in range(3):
            ids = np.flatnonzero(rank_of_cell == rank)
            local = np.full(len(tris), -1)
            local[(ids[:, None] * T + np.arange(T)).ravel()] = np.arange(len(ids) * T)
            expect = set()
            for u, w in ((p, q), (q, p)):
                cut = (owner[u] == rank) & (owner[w] != rank)
                expect |= set(zip(local[u[cut]].tolist(), owner[w[cut]].tolist()))
            got = ref.ghost_ranks(ids, rank_of_cell, rank)
            assert set(map(tuple, got.tolist())) == expect


def test_refine_rejects_bad_input():
    V = np.zeros((5, 2))
    with pytest.raises(ValueError, match="n >= 2"):
        refine(V, np.array([[0, 1, 2]]), 1)
    with pytest.raises(ValueError, match="triangles or all quadrilaterals"):
        refine(V, np.array([[0, 1, 2, 3, 4]]), 2)


@pytest.mark.mpi
def test_parallel_tags_match_geometry(tmp_path):
    """Under mpirun -n 3 every rank's cells and facets, ghosts included, carry the tags
    their position implies (tests/mpi/structured_tags_check.py)."""
    import json

    from conftest import ROOT, run_mpi

    out = tmp_path / "tags"
    run_mpi(3, str(ROOT / "tests" / "mpi" / "structured_tags_check.py"), str(out), timeout=240)
    for rank in range(3):
        result = json.loads((tmp_path / f"tags.{rank}").read_text())
        for name, r in result.items():
            assert r["cells_ok"] and r["facets_ok"] and not r["coarse_differs"], (rank, name, r)
            assert r["ghost_cells"] > 0, (rank, name)  # the ghost layer was exercised


@pytest.mark.parametrize(
    "case",
    [
        dict(shape="square", h=1 / 64, subdomain_size=1 / 8, signorini=["bottom"]),
        dict(shape="square", h=1 / 40, subdomain_size=1 / 10, signorini=["all"]),
        dict(shape="lshape", h=1 / 48, subdomain_size=1 / 12, signorini=["notch_bottom", "left"]),
        dict(  # coarse triangles from gmsh, refined
            shape="polygon",
            vertices=[[0, 0], [0.5, 0], [0.6, 0.4], [0.15, 0.5]],
            h=1 / 30,
            subdomain_size=0.25,
            signorini=["side0"],
        ),
    ],
    ids=["square", "square-all", "lshape", "polygon"],
)
def test_the_generators_coarse_structure_is_the_recovered_one(case):
    """Every field equal (the coordinates to round-off): the vertices, the edges with
    their orientation, order, chains, arcs and subdomains, the skeleton and the interior
    dofs with their subdomains."""
    import runpy

    from mpi4py import MPI

    from conftest import ROOT
    from fem_py.mesh import GeometrySpec, build_domain
    from fem_py.partition import compute_coarse_structure

    script = runpy.run_path(str(ROOT / "tests" / "mpi" / "structured_tags_check.py"))
    d = build_domain(MPI.COMM_WORLD, GeometrySpec(structured=True, **case))
    recovered = compute_coarse_structure(d.mesh, d.cell_tags, d.facet_tags)
    assert d.coarse.n_edges > 4 and len(d.coarse.interior_dofs) > 0
    assert script["differing_fields"](d.coarse, recovered) == []


@pytest.mark.parametrize("shuffle", [False, True])
def test_partitioner_destinations(shuffle):
    """DOLFINx's partitioner output: each cell's owner, then its ghost ranks in the order
    the links give them (links unsorted or sorted); no links: the owners alone."""
    from fem_py.mesh.distribute import destinations

    owner = np.array([2, 0, 1, 1])
    links = np.array([[0, 1], [2, 0], [0, 3], [3, 2], [2, 2]])
    if shuffle:
        links = links[[4, 1, 3, 0, 2]]
    graph = destinations(owner, links)
    rows = [list(graph.links(c)) for c in range(4)]
    assert rows[1] == [0] and rows[3] == [1, 2]
    assert rows[0] == [2, 1, 3]
    assert rows[2] == ([1, 2, 0] if shuffle else [1, 0, 2])
    alone = destinations(owner, np.empty((0, 2), dtype=np.int64))
    assert [list(alone.links(c)) for c in range(4)] == [[2], [0], [1], [1]]
