"""T, E and the exchange of boundary values with distributed PETSc vectors, for any
boundary map that lists its nodes by global P1 dof (docs/method.md section 4).

A boundary map holds, identically on every rank, ``dofs`` (n_gamma,): the global P1 dof of
each boundary node in the map's order, ``signorini`` (n_s,): the positions of the phi
unknowns in that order, and ``n_dofs``: the global number of P1 dofs N. Then

    T : R^N -> R^{n_gamma},     (T u)_i = u[dofs[i]]              (trace)
    E : R^{n_s} -> R^{n_gamma}, (E phi)_{signorini[j]} = phi_j     (extension by zero)

and z = T u + E phi. :class:`BoundaryVectors` gives these to a map class that sets the
three attributes (the 3D ``fem_py.boundary.surface.SurfaceMap``; the 2D boundary map
has the same methods with the same meaning).
"""
from __future__ import annotations

import inspect
from typing import Callable

import numpy as np
import scipy.sparse as sp
from mpi4py import MPI
from petsc4py import PETSc

from fem_py.forms.expressions import Expression

__all__ = ["BoundaryVectors"]


class BoundaryVectors:
    """T, E, ``gather`` and ``scatter_add`` from ``dofs``, ``signorini`` and ``n_dofs``;
    boundary data at the nodes from ``nodes`` and ``node_normals`` (n_gamma, d)."""

    dofs: np.ndarray
    signorini: np.ndarray
    n_dofs: int
    nodes: np.ndarray
    node_normals: np.ndarray

    def interpolate_boundary(self, expr: str | Callable | float) -> np.ndarray:
        """Nodal values (in the map's order) of boundary data such as u0.

        ``expr`` is text in the coordinates and the normal's components (x, y, nx, ny; in
        3D x, y, z, nx, ny, nz; ``fem_py.forms.expressions``), a number, or a callable on
        arrays of the coordinates alone (``f(x, y)``, ``f(x, y, z)``) or of the coordinates
        and the node normal (``f(x, y, nx, ny)``, ``f(x, y, z, nx, ny, nz)``).
        """
        dim = self.nodes.shape[1]
        names = ("x", "y", "z")[:dim] + ("nx", "ny", "nz")[:dim]
        values = (*self.nodes.T, *self.node_normals.T)
        if isinstance(expr, str):
            out = Expression(expr, names).evaluate(dict(zip(names, values)), "numpy")
        elif callable(expr):
            try:
                nargs = len(inspect.signature(expr).parameters)
            except (TypeError, ValueError):
                nargs = 2 * dim
            out = expr(*values[: dim if nargs == dim else 2 * dim])
        elif isinstance(expr, (int, float, np.floating, np.integer)) and not isinstance(expr, bool):
            out = float(expr)
        else:
            raise ValueError(
                f"boundary data must be text, a number or a callable, got {type(expr).__name__}"
            )
        out = np.broadcast_to(np.asarray(out, dtype=float), (self.n_gamma,)).copy()
        if not np.all(np.isfinite(out)):
            raise ValueError(
                "boundary data is not finite at some boundary node; check the expression"
            )
        return out

    @property
    def n_gamma(self) -> int:
        """The number of boundary nodes."""
        return len(self.dofs)

    @property
    def n_signorini(self) -> int:
        """The number of phi unknowns."""
        return len(self.signorini)

    def trace_matrix(self) -> sp.csr_matrix:
        """T (n_gamma x N): T[i, dofs[i]] = 1 (global dof columns)."""
        n = self.n_gamma
        return sp.csr_matrix((np.ones(n), (np.arange(n), self.dofs)), shape=(n, self.n_dofs))

    def extension_matrix(self) -> sp.csr_matrix:
        """E (n_gamma x n_s): E[signorini[j], j] = 1."""
        m = self.n_signorini
        return sp.csr_matrix((np.ones(m), (self.signorini, np.arange(m))), shape=(self.n_gamma, m))

    def owned(self, local_range: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
        """(boundary positions, local indices) of the boundary dofs a rank owns whose
        owned dofs are the global ``local_range`` [start, stop) (computed once per range)."""
        key = tuple(int(i) for i in local_range)
        cached = self.__dict__.setdefault("_owned_cache", {})
        if key not in cached:
            mine = np.flatnonzero((self.dofs >= key[0]) & (self.dofs < key[1]))
            cached[key] = (mine, (self.dofs[mine] - key[0]).astype(np.int32))
        return cached[key]

    def _owned(self, vec: PETSc.Vec) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`owned` in the layout of ``vec``."""
        return self.owned(vec.getOwnershipRange())

    def gather(self, vec: PETSc.Vec) -> np.ndarray:
        """T u for a distributed PETSc Vec u: the values in the map's order on every rank
        (collective)."""
        positions, local = self._owned(vec)
        out = np.zeros(self.n_gamma)
        out[positions] = vec.array_r[local]
        comm = vec.comm.tompi4py()
        if comm.size > 1:
            comm.Allreduce(MPI.IN_PLACE, out, op=MPI.SUM)
        return out

    def scatter_add(
        self, values: np.ndarray, vec: PETSc.Vec, *, refresh_ghosts: bool = True
    ) -> PETSc.Vec:
        """vec += T^T values (each rank adds to the entries it owns; ``values`` must be
        the same on every rank). With ``refresh_ghosts`` the ghost entries of a ghosted
        ``vec`` are refreshed (collective); without, only owned entries are valid."""
        values = np.asarray(values, dtype=float)
        if values.shape != (self.n_gamma,):
            raise ValueError(f"values must have shape ({self.n_gamma},), got {values.shape}")
        positions, local = self._owned(vec)
        owned = vec.getArray()
        owned[local] += values[positions]
        if refresh_ghosts:
            try:
                vec.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
            except PETSc.Error:  # not a ghosted Vec: nothing to refresh
                pass
        return vec
