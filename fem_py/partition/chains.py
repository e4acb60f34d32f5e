"""Curved coarse edges (``fem_py.partition.coarse`` with ``corner_angle``): walks along the chains
of skeleton facets between coarse vertices.

The skeleton is given as in ``fem_py.partition.coarse``: ``inv`` (n_f, 2) the node numbers of the
facets (exterior facets counter-clockwise), ``incident``/``first`` the facets at every
node (those of node i are ``incident[first[i]:]``, two for a chain node), ``is_vertex``
the coarse vertex flags.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

__all__ = ["walk_chain", "mark_closed_chains", "walk_chains"]


def walk_chain(inv, incident, first, is_vertex, facet, node) -> list:
    """The nodes of a skeleton chain from ``node`` along ``facet`` to the next coarse
    vertex (or back to ``node``), both ends included."""
    out = [int(node)]
    while True:
        a, b = inv[facet]
        node = b if a == node else a
        out.append(int(node))
        if is_vertex[node] or node == out[0]:
            return out
        k = first[node]
        f0, f1 = incident[k], incident[k + 1]
        facet = f1 if f0 == facet else f0


def mark_closed_chains(inv, incident, first, i2, f, g, is_vertex) -> None:
    """Make two coarse vertices on every closed skeleton chain without one (a subdomain
    enclosed by a single other one, or Gamma of a single subdomain with no corner)."""
    nf = len(inv)
    join = ~is_vertex[i2]
    graph = sp.csr_matrix((np.ones(int(join.sum())), (f[join], g[join])), shape=(nf, nf))
    n_comp, comp = connected_components(graph, directed=False)
    has_vertex = np.zeros(n_comp, dtype=bool)
    has_vertex[np.repeat(comp, 2)[is_vertex[inv].ravel()]] = True
    for c in np.flatnonzero(~has_vertex):
        facet = int(np.flatnonzero(comp == c)[0])
        node = int(inv[facet, 0])
        loop = walk_chain(inv, incident, first, is_vertex, facet, node)
        is_vertex[node] = True
        is_vertex[loop[len(loop) // 2]] = True


def walk_chains(inv, incident, first, is_vertex, comp, exterior, start, stop, vnum):
    """(start, stop, chains) of curved coarse edges: each chain walked from its start,
    counter-clockwise along Gamma (the exterior facets are oriented so), from the lower
    to the higher coarse vertex number inside Omega."""
    n_edges = len(start)
    starts, stops, rows = start.copy(), stop.copy(), []
    facets_of = np.argsort(comp, kind="stable")
    bounds = np.concatenate([[0], np.cumsum(np.bincount(comp, minlength=n_edges))])
    for e in range(n_edges):
        fs = facets_of[bounds[e] : bounds[e + 1]]
        ends = [(int(ff), int(inv[ff, k])) for ff in fs for k in (0, 1) if is_vertex[inv[ff, k]]]
        if exterior[fs[0]]:  # leave along the facet that starts at the vertex
            facet, node = next((ff, nd) for ff, nd in ends if inv[ff, 0] == nd)
        else:
            facet, node = min(ends, key=lambda fn: vnum[fn[1]])
        walk = walk_chain(inv, incident, first, is_vertex, facet, node)
        starts[e], stops[e] = walk[0], walk[-1]
        rows.append(np.asarray(walk, dtype=np.int64))
    return starts, stops, rows
