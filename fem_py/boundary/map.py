"""The boundary map of docs/method.md section 4: ordered boundary nodes, T and E.

Gamma_h is the closed polygon of the boundary nodes of the fine mesh. ``BoundaryMap``
lists them counter-clockwise (Omega on the left), which is the order of every boundary
vector of the coupling (``V_h(Gamma)``: continuous P1 on that polygon), and defines

    T : R^N -> R^{N_Gamma},   (T u)_i = u(node_i)          (trace, picks boundary dofs)
    E : R^{N_s} -> R^{N_Gamma}, (E phi)_{signorini[j]} = phi_j (extension by zero)

so that z = T u + E phi (docs/method.md section 4). The phi unknowns are the nodes interior
to the Signorini arcs: a node is one when both boundary panels at it carry the same
Signorini tag 100 + k. Arc end points (where the tag changes) are excluded, so phi
vanishes there; with Gamma_s = Gamma (one closed arc, tag 100 everywhere) every node is
a phi unknown.

Panel i joins node i to node i+1 (mod N_Gamma); its outward unit normal is
(dy, -dx)/|panel| (counter-clockwise orientation). The normal at a node, used for
``nx, ny`` in boundary data, is the normalised average of the two adjacent panel
normals (at a corner of angle theta it bisects the exterior angle; on a straight side
it is the side's normal).

DOLFINx 0.5.2 gives no facet orientation, and ``exterior_facet_indices`` returns owned
facets only: each rank orients its exterior facets with its cell on the left, rank 0
gathers them as global dof pairs, walks the cycle, checks it is one closed polygon with
positive shoelace area, and broadcasts. The map is identical on every rank.
"""
from __future__ import annotations

from typing import Any

import numpy as np
from dolfinx import fem

from fem_py.boundary.order import closed_polygon, walk_boundary
from fem_py.boundary.vectors import BoundaryVectors
from fem_py.dofs.p1 import exterior_facets, facet_data, gather_facet_data, p1_topology, tag_array
from fem_py.parallel import broadcast_from_root
from fem_py.polyline import segment_lengths
from fem_py.tags import GAMMA_T_TAG

__all__ = ["BoundaryMap"]


class BoundaryMap(BoundaryVectors):
    """Boundary nodes in counter-clockwise order and the maps T, E (docs/method.md section 4).

    ``BoundaryMap(V, domain)`` (collective) with ``V = fem_py.dofs.p1_space(mesh)`` and
    a :class:`fem_py.mesh.Domain` (the walk starts at its first polygon vertex), or
    ``BoundaryMap(V, facet_tags, start=point)`` with the facet tags alone (default
    start: the boundary node with the smallest y, then x - a corner of Omega). Every
    rank holds the same arrays.

    Attributes
    ----------
    nodes : (n_gamma, 2) float
        Boundary nodes, counter-clockwise, first node not repeated.
    dofs : (n_gamma,) int64
        Global P1 dofs of ``nodes`` (numbering of ``fem_py.dofs.p1_space``).
    s : (n_gamma,) float
        Arc length from ``nodes[0]`` counter-clockwise; ``length`` is |Gamma_h|.
    panel_tags : (n_gamma,) int
        Facet tag of panel i = [node i, node i+1]: 1 on Gamma_t, 100 + k on arc k.
    panel_normals, node_normals : (n_gamma, 2) float
        Outward unit normals of the panels and at the nodes (module docstring).
    signorini : (n_s,) int
        Indices into the boundary order of the phi unknowns.
    arc_of_signorini : (n_s,) int
        Arc index k of each phi unknown.
    n_dofs : int
        Global number of P1 dofs N (columns of T).
    """

    nodes: np.ndarray
    dofs: np.ndarray
    s: np.ndarray
    length: float
    panel_tags: np.ndarray
    panel_normals: np.ndarray
    node_normals: np.ndarray
    signorini: np.ndarray
    arc_of_signorini: np.ndarray
    n_dofs: int

    def __init__(self, V: fem.FunctionSpace, domain_or_facet_tags: Any, *, start: Any = None):
        if hasattr(domain_or_facet_tags, "facet_tags") and hasattr(
            domain_or_facet_tags, "vertices"
        ):
            facet_tags = domain_or_facet_tags.facet_tags
            if start is None:
                start = domain_or_facet_tags.vertices[0]
        else:
            facet_tags = domain_or_facet_tags
        msh = V.mesh
        comm = msh.comm
        topo = p1_topology(V)
        n_facets = msh.topology.index_map(1).size_local + msh.topology.index_map(1).num_ghosts
        n_cells = msh.topology.index_map(2).size_local + msh.topology.index_map(2).num_ghosts
        ftag = tag_array(facet_tags, n_facets, default=0)
        fd = gather_facet_data(
            comm, [facet_data(topo, exterior_facets(msh), ftag, np.zeros(n_cells, np.int32), True)]
        )
        n_dofs = V.dofmap.index_map.size_global
        arrays = broadcast_from_root(
            comm, lambda: walk_boundary(fd, n_dofs, start), error_prefix="boundary map"
        )
        for key, value in arrays.items():
            setattr(self, key, value)

    @classmethod
    def from_domain(cls, domain: Any, V: fem.FunctionSpace | None = None) -> "BoundaryMap":
        """Collective: ``BoundaryMap(p1_space(domain.mesh), domain)``."""
        from fem_py.dofs.p1 import p1_space

        return cls(p1_space(domain.mesh) if V is None else V, domain)

    # ------------------------------------------------------------ sizes
    @property
    def panel_lengths(self) -> np.ndarray:
        return segment_lengths(closed_polygon(self.nodes))

    @property
    def lumped_mass(self) -> np.ndarray:
        """The row sums of the P1 mass matrix of Gamma_h: half the length of the two
        panels at each node."""
        lengths = self.panel_lengths  # panel i = [node i, node i + 1]
        return 0.5 * (lengths + np.roll(lengths, 1))

    def on_gamma_t(self) -> np.ndarray:
        """Panel mask of Gamma_t (tag 1)."""
        return self.panel_tags == GAMMA_T_TAG
