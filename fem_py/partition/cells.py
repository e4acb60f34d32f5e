"""Automatic partition of a triangle mesh into compact, connected subdomains of size d
(docs/method.md section 6), pure numpy/scipy, on one rank.

:func:`partition_cells` seeds one subdomain per point of a hexagonal lattice (one point
per area d^2) that lies in Omega (near a cell centroid), runs a few Lloyd (k-means)
iterations on the area-weighted cell centroids, smooths the part boundaries, and makes
every part connected and free of enclosed islands by merging fragments into the
neighbour they share most facets with. The result depends
on Omega and d only, not on how finely the boundary is drawn: a polygon of 480 vertices
gets as many subdomains as the disk it approximates.

:func:`cell_adjacency` is the dual graph (cells sharing a facet) the merging walks.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

__all__ = ["partition_cells", "cell_adjacency", "part_diameters"]

_LLOYD_STEPS = 12
_SMOOTH_SWEEPS = 4


def cell_adjacency(cells: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Facet neighbours of a triangle mesh ``cells`` (n, 3).

    Returns (a, b, boundary): the pairs of cells a[i], b[i] sharing a facet, and the
    cells with at least one boundary facet (bool (n,)).
    """
    cells = np.asarray(cells, dtype=np.int64)
    n = len(cells)
    facets = np.sort(cells[:, [[1, 2], [2, 0], [0, 1]]].reshape(-1, 2), axis=1)
    code = facets[:, 0] * (int(cells.max(initial=0)) + 1) + facets[:, 1]
    order = np.argsort(code, kind="stable")
    sc = code[order]
    same = np.flatnonzero(sc[1:] == sc[:-1])
    a, b = order[same] // 3, order[same + 1] // 3
    count = np.ones(len(code), dtype=np.int64)
    count[order[same]] = 2
    count[order[same + 1]] = 2
    boundary = np.zeros(n, dtype=bool)
    boundary[np.flatnonzero(count == 1) // 3] = True
    return a, b, boundary


def _areas(x: np.ndarray, cells: np.ndarray) -> np.ndarray:
    p = x[cells]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    return 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])


def _renumber(label: np.ndarray) -> np.ndarray:
    _, inverse = np.unique(label, return_inverse=True)
    return inverse.astype(np.int32)


def _merge_fragments(
    label: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    boundary: np.ndarray,
    area: np.ndarray,
    min_area: float,
) -> np.ndarray:
    """Make every part connected, not enclosed by one other part, and not tiny.

    A fragment (a connected piece of a part that is not its largest piece), a part
    touching one other part only and not Gamma (an island: its boundary would be a
    closed coarse edge without coarse vertices), and a part smaller than ``min_area``
    are merged into the neighbour they share most facets with; repeated until none is
    left.
    """
    n = len(label)
    for _ in range(100):
        same = label[a] == label[b]
        graph = sp.csr_matrix((np.ones(int(same.sum())), (a[same], b[same])), shape=(n, n))
        _, comp = connected_components(graph, directed=False)
        comp_area = np.bincount(comp, area)
        best = np.zeros(label.max() + 1)
        np.maximum.at(best, label, comp_area[comp])
        # the largest component of every part keeps the part's label
        keeper = comp_area[comp] >= best[label]
        # ties: keep the component holding the part's first such cell
        first_keep = np.full(label.max() + 1, -1)
        idx = np.flatnonzero(keeper)[::-1]
        first_keep[label[idx]] = comp[idx]
        frag = comp != first_keep[label]
        # parts as merge units: fragments are their own unit
        unit = np.where(frag, label.max() + 1 + comp, label)
        unit = _renumber(unit)
        m = int(unit.max()) + 1
        cut = unit[a] != unit[b]
        ua, ub = unit[a][cut], unit[b][cut]
        shared = sp.coo_matrix(
            (np.ones(2 * len(ua)), (np.concatenate([ua, ub]), np.concatenate([ub, ua]))),
            shape=(m, m),
        ).tocsr()
        shared.sum_duplicates()
        n_neighbours = np.diff(shared.indptr)
        unit_area = np.bincount(unit, area, minlength=m)
        on_gamma = np.bincount(unit, boundary, minlength=m) > 0
        unit_is_frag = np.zeros(m, dtype=bool)
        unit_is_frag[unit[frag]] = True
        bad = (unit_is_frag | ((n_neighbours == 1) & ~on_gamma) | (unit_area < min_area)) & (
            n_neighbours > 0
        )
        if not bad.any():
            return _renumber(label)
        # merge the smallest bad units first, one per neighbourhood in this round
        target = np.full(m, -1)
        taken = np.zeros(m, dtype=bool)
        for u in np.flatnonzero(bad)[np.argsort(unit_area[bad])]:
            row = slice(shared.indptr[u], shared.indptr[u + 1])
            nbrs, w = shared.indices[row], shared.data[row]
            if taken[u] or taken[nbrs].all():
                continue
            v = nbrs[np.lexsort((nbrs, -w))][0]
            target[u] = v
            taken[u] = taken[v] = True
        # the label of the neighbour unit: that of any of its cells
        label_of_unit = np.zeros(m, dtype=np.int64)
        label_of_unit[unit] = label
        move = target[unit] >= 0
        new_label = label.copy()
        new_label[move] = label_of_unit[target[unit[move]]]
        label = new_label
    raise RuntimeError("partition: merging the fragments of the subdomains did not finish")


def partition_cells(x: np.ndarray, cells: np.ndarray, d: float) -> np.ndarray:
    """Subdomain id of every cell: connected, compact parts of diameter about ``d``.

    Parameters
    ----------
    x : (n_nodes, 2) float
        Node coordinates.
    cells : (n_cells, 3) int
        Triangles.
    d : float
        Subdomain size: parts are the Voronoi cells (after Lloyd iterations) of about
        area(Omega) / d^2 seeds, so their diameter is about d (1 to 2 d).

    Returns
    -------
    (n_cells,) int32
        Subdomain ids 0 .. L-1, every id used, each part connected (through facets),
        none enclosed by a single other part.
    """
    x = np.asarray(x, dtype=float)[:, :2]
    cells = np.asarray(cells, dtype=np.int64)
    area = _areas(x, cells)
    centroid = x[cells].mean(axis=1)
    lo, hi = centroid.min(0), centroid.max(0)
    # seeds: a hexagonal lattice of one point per area d^2 (centred on the bounding box),
    # the points near a centroid; hexagonal, so that parts meet three at a time (four
    # parts meeting at one point make two triple points and a tiny coarse edge)
    s = d * np.sqrt(2.0 / np.sqrt(3.0))
    step = np.array([s, 0.5 * np.sqrt(3.0) * s])
    counts = np.maximum(1, np.ceil((hi - lo) / step).astype(int) + 1)
    start = 0.5 * (lo + hi) - 0.5 * (counts - 1) * step
    i, j = np.meshgrid(np.arange(counts[0]), np.arange(counts[1]))
    grid = np.column_stack(
        [start[0] + step[0] * (i + 0.5 * (j % 2) - 0.25).ravel(), start[1] + step[1] * j.ravel()]
    )
    tree = cKDTree(centroid)
    dist, nearest = tree.query(grid)
    h_cell = np.sqrt(2 * area.max())
    seeds = grid[dist <= 0.5 * d + h_cell]
    if len(seeds) == 0:
        seeds = centroid[nearest[np.argmin(dist)]][None, :]
    seeds = np.unique(seeds, axis=0)
    for _ in range(_LLOYD_STEPS):
        _, label = cKDTree(seeds).query(centroid)
        w = np.bincount(label, area, minlength=len(seeds))
        keep = w > 0
        moved = np.stack(
            [np.bincount(label, area * centroid[:, i], len(seeds)) for i in range(2)], 1
        )
        seeds = moved[keep] / w[keep][:, None]
    _, label = cKDTree(seeds).query(centroid)
    a, b, boundary = cell_adjacency(cells)
    label = _smooth(label, a, b, len(cells))
    return _merge_fragments(_renumber(label), a, b, boundary, area, 0.2 * d * d)


def _smooth(label: np.ndarray, a: np.ndarray, b: np.ndarray, n: int) -> np.ndarray:
    """Straighten the part boundaries: a cell two of whose neighbours lie in one other
    part moves there (a tooth of the Voronoi boundary), a few sweeps."""
    for _ in range(_SMOOTH_SWEEPS):
        src = np.concatenate([a, b])
        nbr_label = label[np.concatenate([b, a])]
        other = nbr_label != label[src]
        key = src[other].astype(np.int64) * (int(label.max()) + 1) + nbr_label[other]
        uniq, count = np.unique(key, return_counts=True)
        win = uniq[count >= 2]
        if not win.size:
            break
        cell, new = np.divmod(win, int(label.max()) + 1)
        label = label.copy()
        label[cell] = new
    return label


def part_diameters(x: np.ndarray, cells: np.ndarray, label: np.ndarray) -> np.ndarray:
    """Diameter of every part (the largest distance between two of its nodes), (L,)."""
    from fem_py.polyline import diameter

    out = np.zeros(int(label.max()) + 1)
    for k in range(len(out)):
        out[k] = diameter(x[np.unique(cells[label == k])][:, :2])
    return out
