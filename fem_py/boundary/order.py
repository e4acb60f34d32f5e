"""The ordered boundary nodes of docs/method.md section 4: the walk of the gathered exterior
facets (oriented with Omega on the left) into the counter-clockwise cycle of boundary
nodes, and the arrays of ``fem_py.boundary.map.BoundaryMap`` derived from it (run on
rank 0)."""
from __future__ import annotations

from typing import Any

import numpy as np

from fem_py.polyline import arc_length, segment_lengths
from fem_py.tags import SIGNORINI_TAG0

__all__ = ["walk_boundary", "closed_polygon"]


def walk_boundary(fd: Any, n_dofs: int, start: Any) -> dict:
    """Rank 0: order the gathered exterior facets (oriented, Omega on the left) into the
    counter-clockwise cycle of boundary nodes and derive the boundary-map arrays."""
    a, b = fd.dofs[:, 0], fd.dofs[:, 1]
    nf = len(a)
    if nf < 3:
        raise RuntimeError(f"only {nf} boundary facets")
    order = np.argsort(a)
    a_sorted = a[order]
    if np.any(np.diff(a_sorted) == 0) or not np.array_equal(a_sorted, np.sort(b)):
        raise RuntimeError("the boundary is not a closed curve with consistently oriented facets")
    if start is None:
        xy = fd.coords[:, 0]
        f0 = int(np.lexsort((xy[:, 0], xy[:, 1]))[0])
    else:
        f0 = int(
            np.argmin(np.linalg.norm(fd.coords[:, 0] - np.asarray(start, float)[None, :2], axis=1))
        )
    facets = np.empty(nf, dtype=np.int64)
    f = f0
    for i in range(nf):
        facets[i] = f
        f = int(order[np.searchsorted(a_sorted, b[f])])  # the facet leaving the end node
        if f == f0 and i != nf - 1:
            raise RuntimeError(
                f"the boundary has several components ({i + 1} of {nf} facets in the first); "
                "Omega must be simply connected"
            )
    nodes = fd.coords[facets, 0].astype(float)
    x, y = nodes[:, 0], nodes[:, 1]
    area = 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))
    if area <= 0:
        raise RuntimeError(
            f"boundary walk has shoelace area {area:g} <= 0 (expected counter-clockwise)"
        )
    tags = fd.tag[facets].astype(np.int64)
    polygon = closed_polygon(nodes)
    seg = np.diff(polygon, axis=0)
    plen = segment_lengths(polygon)
    pn = np.stack([seg[:, 1], -seg[:, 0]], axis=1) / plen[:, None]
    nn = pn + np.roll(pn, 1, axis=0)
    nn /= np.linalg.norm(nn, axis=1)[:, None]
    sig = np.flatnonzero((tags >= SIGNORINI_TAG0) & (tags == np.roll(tags, 1)))
    return dict(
        nodes=nodes,
        dofs=a[facets].astype(np.int64),
        s=arc_length(polygon)[:-1],
        length=float(plen.sum()),
        panel_tags=tags,
        panel_normals=pn,
        node_normals=nn,
        signorini=sig.astype(np.int64),
        arc_of_signorini=(tags[sig] - SIGNORINI_TAG0).astype(np.int64),
        n_dofs=int(n_dofs),
    )


def closed_polygon(nodes: np.ndarray) -> np.ndarray:
    """The closed polygon of the boundary nodes: (n, 2) -> (n + 1, 2), first node last."""
    return np.concatenate([nodes, nodes[:1]])
