"""The iterate of one level as the start of the next (nested iteration).

The refined mesh keeps the old nodes and adds edge midpoints, so both transfers are
exact interpolations: u_h by P1 interpolation (:func:`fem_py.mesh.refinement.transfer_p1`:
old values, averages at midpoints), the gap phi_h along Gamma likewise (the old gap as
a piecewise linear function on the old boundary polygon, 0 on Gamma_t, read at the new
Signorini nodes). In 3D the gap is read the same way through the volume: the P1 function
on the old mesh with the gap at the boundary nodes (0 inside) is interpolated at the new
nodes; a new boundary node lies on an old boundary triangle, where that function is the
gap's P1 interpolant on the surface. The step is clipped at 0 so the start lies in D_h.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from dolfinx import fem

from fem_py.mesh import boundary_transfer, transfer_p1

__all__ = ["transfer_iterate"]


def transfer_iterate(old_problem: Any, solution: Any, new_problem: Any) -> tuple:
    """(u, phi) for ``solve(new_problem, ..., initial=(u, phi))``: u the owned entries on
    new_problem.V, phi (n_s,) at its Signorini nodes (every rank the same)."""
    n_owned = new_problem.V.dofmap.index_map.size_local
    u = transfer_p1(solution.u, new_problem.V)[:n_owned]
    old_b, new_b = old_problem.boundary, new_problem.boundary
    gap = np.zeros(old_b.n_gamma)
    gap[old_b.signorini] = solution.phi
    if new_problem.V.mesh.topology.dim == 2:
        phi = boundary_transfer(old_b.nodes, gap, new_b.nodes[new_b.signorini])
        return u, np.maximum(phi, 0.0)
    old_gap = fem.Function(old_problem.V)
    old_b.scatter_add(gap, old_gap.vector)
    old_gap.x.scatter_forward()
    new_gap = fem.Function(new_problem.V)
    new_gap.x.array[:] = transfer_p1(old_gap, new_problem.V)
    phi = new_b.gather(new_gap.vector)[new_b.signorini]
    return u, np.maximum(phi, 0.0)
