"""The sizes a user checks before trusting a mesh (issue 17): the number of subdomains,
the shortest and longest fine facet, the mean subdomain diameter and the length of each
Signorini arc, from a distributed :class:`fem_py.mesh.Domain` (collective); for a body in
R^3 (:class:`fem_py.mesh.SolidDomain`) the shortest and longest edge and the area of
each Signorini face."""
from __future__ import annotations

from typing import Any

import numpy as np
from dolfinx import cpp
from dolfinx import mesh as dmesh
from mpi4py import MPI

from fem_py.partition.ragged import as_ragged
from fem_py.tags import SIGNORINI_TAG0

__all__ = ["mesh_facts", "shortest_facet", "subdomain_diameters"]

#: directions of the widths whose maximum is the diameter (within cos(pi / 16) = 0.981)
_DIRECTIONS = 8


def subdomain_diameters(domain: Any) -> np.ndarray:
    """The diameter of every subdomain, (L,) on every rank: the largest width over 8
    directions (the diameter to within 2%) of the nodes on its boundary, its coarse
    edges (``coarse.edge_coords``, replicated: no communication)."""
    coarse = domain.coarse
    edges = as_ragged(coarse.edge_coords, dtype=float, item_shape=(2,))
    sides = np.asarray(coarse.edge_subdomains, dtype=np.int64)  # (n_e, 2), -1 for Gamma
    angle = np.pi * np.arange(_DIRECTIONS) / _DIRECTIONS
    proj = edges.flat @ np.stack([np.cos(angle), np.sin(angle)])  # (points, 8)
    edge = np.repeat(np.arange(len(sides)), edges.lengths)
    n_sub = int(coarse.n_subdomains)
    hi, lo = np.full((n_sub, _DIRECTIONS), -np.inf), np.full((n_sub, _DIRECTIONS), np.inf)
    for side in (0, 1):
        part = sides[edge, side]
        keep = part >= 0
        order = np.argsort(part[keep], kind="stable")
        sorted_part, values = part[keep][order], proj[keep][order]
        if not len(sorted_part):
            continue
        starts = np.flatnonzero(np.r_[True, sorted_part[1:] != sorted_part[:-1]])
        mine = sorted_part[starts]
        hi[mine] = np.maximum(hi[mine], np.maximum.reduceat(values, starts, axis=0))
        lo[mine] = np.minimum(lo[mine], np.minimum.reduceat(values, starts, axis=0))
    return (hi - lo).max(axis=1)


def shortest_facet(domain: Any) -> float:
    """The shortest side of the owned triangles, minimised over the ranks (collective);
    the longest is ``domain.h_max``."""
    msh = domain.mesh
    x0, x1 = (np.ascontiguousarray(msh.geometry.x[:, k]) for k in (0, 1))
    cells = msh.geometry.dofmap.array.reshape(-1, 3)[: msh.topology.index_map(2).size_local]
    shortest2 = np.inf  # the squared length |x_a - x_b|^2 of side a-b, one side at a time
    for a, b in ((0, 2), (1, 0), (2, 1)):
        d0, d1 = x0[cells[:, a]] - x0[cells[:, b]], x1[cells[:, a]] - x1[cells[:, b]]
        shortest2 = min(shortest2, float((d0 * d0 + d1 * d1).min(initial=np.inf)))
    return msh.comm.allreduce(float(np.sqrt(shortest2)), op=MPI.MIN)


def _summed(comm: Any, values: np.ndarray) -> np.ndarray:
    out = np.empty_like(values)
    comm.Allreduce(values, out, op=MPI.SUM)
    return out


def solid_facts(domain: Any) -> dict:
    """``h_min``, ``h_max`` (shortest and longest edge) and ``signorini_areas`` (the area
    of each Signorini face or group, in the order of ``domain.signorini``; the whole
    surface for ``"all"``) of a :class:`fem_py.mesh.SolidDomain` (collective)."""
    msh, comm = domain.mesh, domain.mesh.comm
    tags = domain.facet_tags
    n_owned = msh.topology.index_map(2).size_local  # each triangle counted once
    owned = tags.indices < n_owned
    chosen = domain.signorini
    if chosen == "all":
        msh.topology.create_connectivity(2, 3)
        boundary = dmesh.exterior_facet_indices(msh.topology)
        groups = [boundary[boundary < n_owned]]
    else:
        groups = [tags.indices[owned & (tags.values == tag)] for tag in chosen]
    areas = np.zeros(len(groups))
    for k, facets in enumerate(groups):
        if len(facets):
            corners = cpp.mesh.entities_to_geometry(msh._mesh, 2, facets.astype(np.int32), False)
            p = msh.geometry.x[corners]
            areas[k] = (
                0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1).sum()
            )
    return {
        "h_min": float(domain.h_min),
        "h_max": float(domain.h_max),
        "signorini_areas": [float(v) for v in _summed(comm, areas)],
    }


def mesh_facts(domain: Any) -> dict:
    """``subdomains``, ``h_min``, ``h_max`` (shortest and longest fine facet),
    ``subdomain_diameter`` (the mean over the subdomains, :func:`subdomain_diameters`)
    and ``signorini_lengths`` (the length of arc k, tagged 100 + k), the same on every
    rank (collective); :func:`solid_facts` for a body in R^3."""
    if domain.dim == 3:
        return solid_facts(domain)
    msh, comm = domain.mesh, domain.mesh.comm
    x = msh.geometry.x[:, :2]
    facets, values = domain.facet_tags.indices, domain.facet_tags.values
    owned = facets < msh.topology.index_map(1).size_local  # each facet counted once
    on_arc = owned & (values >= SIGNORINI_TAG0)
    n_arcs = comm.allreduce(
        int(values[values >= SIGNORINI_TAG0].max(initial=SIGNORINI_TAG0 - 1)),
        op=MPI.MAX,
    )
    n_arcs -= SIGNORINI_TAG0 - 1
    lengths = np.zeros(n_arcs)
    if on_arc.any():
        ends = cpp.mesh.entities_to_geometry(msh._mesh, 1, facets[on_arc].astype(np.int32), False)
        np.add.at(
            lengths,
            values[on_arc] - SIGNORINI_TAG0,
            np.linalg.norm(x[ends[:, 0]] - x[ends[:, 1]], axis=1),
        )
    return {
        "subdomains": int(domain.coarse.n_subdomains),
        "h_min": shortest_facet(domain),
        "h_max": float(domain.h_max),  # kept by fem_py.mesh and fem_py.mesh.refinement
        "subdomain_diameter": float(subdomain_diameters(domain).mean()),
        "signorini_lengths": [float(v) for v in _summed(comm, lengths)],
    }
