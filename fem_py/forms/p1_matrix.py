"""A P1 bilinear form's matrix in DOLFINx's own compressed-row storage, applied by scipy.

DOLFINx 0.5 assembles into a PETSc Mat through ``MatSetValuesLocal``, whose insertion costs
more than the element kernels of the P1 forms here, and reading the rows back costs a copy
(measured: docs/design/speed.md, "The P1 matrices without PETSc"). :class:`P1Matrix`
holds one sparsity pattern in a ``MatrixCSR`` and offers the two things the solvers do
with a P1 matrix:

- **products** y = A x, with A assembled from each rank's own cells
  (:meth:`assemble_local`): every rank multiplies its rows (owned and ghost) by its local
  x, and the ghost rows' sums go to their owners (a reverse scatter-add, as an assembled
  vector's do). No rank needs the values of dofs outside its cells;
- **the owned rows** of the assembled matrix with global column numbers
  (:meth:`assemble_owned`), as PETSc's ``getValuesCSR`` gives them, for the
  preconditioners that factor blocks of it;
- **this rank's share** of it in local numbering (:attr:`local_rows`), for a
  preconditioner distributed by subdomains: a row whose cells are all local is complete
  there, with no communication and no global numbers.
"""
from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp
from dolfinx import fem, la
from petsc4py import PETSc

__all__ = ["P1Matrix"]


class P1Matrix:
    """The matrix of a bilinear form on one P1 space, in DOLFINx's ``MatrixCSR``.

    Parameters
    ----------
    form
        A compiled bilinear form (``fem.form``) whose cell pattern the matrix has; every
        form assembled into it must have the same pattern (the P1 cell pattern).
    """

    def __init__(self, form: Any):
        pattern = fem.create_sparsity_pattern(form)
        pattern.assemble()
        rows, columns = pattern.index_map(0), pattern.column_index_map()
        self.comm = form.mesh.comm
        self.n_owned = rows.size_local
        self.n_local = rows.size_local + rows.num_ghosts
        self._column_start = columns.local_range[0]
        self._n_owned_columns = columns.size_local
        self._row_start = rows.local_range[0]
        self._row_ghosts = np.asarray(rows.ghosts, dtype=np.int64)
        self._row_owners = np.asarray(rows.owners, dtype=np.int64)
        self._column_ghosts = np.asarray(columns.ghosts, dtype=np.int64)
        if not np.array_equal(self._column_ghosts[: len(self._row_ghosts)], self._row_ghosts):
            raise RuntimeError(  # DOLFINx 0.5.2's pattern keeps the space's ghosts first
                "the sparsity pattern's column numbering does not extend the space's"
            )
        self.n_global = columns.size_global
        self._matrix = la.matrix_csr(pattern)
        n_columns = columns.size_local + len(self._column_ghosts)
        # views of the MatrixCSR's arrays: the products read the values assembled last
        self._rows = sp.csr_matrix(
            (self._matrix.data, self._matrix.indices, self._matrix.indptr),
            shape=(self.n_local, n_columns),
            copy=False,
        )
        # the column numbering extends V's local numbering (owned, then V's ghosts) by the
        # columns that only other ranks' cells couple to an owned dof; a rank's own cells
        # never reach those, so x is 0 there in :meth:`mult`
        self._x = np.zeros(n_columns) if n_columns > self.n_local else None

    def assemble_local(self, form: Any, coefficients: Any = None) -> None:
        """Assemble ``form`` over this rank's cells, for :meth:`mult` (no communication)."""
        self._matrix.set(0.0)
        fem.assemble_matrix(self._matrix, form, coeffs=coefficients)

    @property
    def local_rows(self) -> sp.csr_matrix:
        """The matrix as last assembled by :meth:`assemble_local`: this rank's cells' sums on
        its local rows (owned, then ghost) and local columns (V's local numbering, then the
        columns that only other ranks' cells reach, zero here). A view: the next assembly
        overwrites it."""
        return self._rows

    def assemble_owned(self, form: Any, coefficients: Any = None) -> sp.csr_matrix:
        """Assemble ``form`` and return its owned rows (n_owned, n_global) with global column
        numbers: this rank's sums plus the other ranks' sums on its rows (collective; a
        copy, the matrix is assembled over again later)."""
        self.assemble_local(form, coefficients)
        rows = self._rows
        owned = sp.csr_matrix(
            (
                rows.data[: rows.indptr[self.n_owned]].copy(),
                self._global(rows.indices[: rows.indptr[self.n_owned]]),
                rows.indptr[: self.n_owned + 1].copy(),
            ),
            shape=(self.n_owned, self.n_global),
        )
        if self.comm.size == 1:
            return owned
        # the ghost rows' sums go to the rows' owners (DOLFINx 0.5.2's MatrixCSR.finalize
        # lost some of them: measured on two ranks)
        ghost = rows[self.n_owned :].tocoo()
        owner = self._row_owners[ghost.row]
        order = np.argsort(owner, kind="stable")
        counts = np.bincount(owner, minlength=self.comm.size)
        bounds = np.concatenate([[0], np.cumsum(counts)])
        outgoing = [
            (
                self._row_ghosts[ghost.row[order[a:b]]],
                self._global(ghost.col[order[a:b]]),
                ghost.data[order[a:b]],
            )
            for a, b in zip(bounds[:-1], bounds[1:])
        ]
        incoming = self.comm.alltoall(outgoing)
        row, col, value = (np.concatenate([part[k] for part in incoming]) for k in range(3))
        np.add.at(owned.data, _entries(owned, row - self._row_start, col), value)
        return owned

    def _global(self, columns: np.ndarray) -> np.ndarray:
        """Global numbers of local column numbers (a new array; int32 while they fit)."""
        if self.comm.size == 1:  # one rank: the local numbers are the global ones
            return np.array(columns)
        index_type = np.int32 if self.n_global <= np.iinfo(np.int32).max else np.int64
        out = np.add(columns, self._column_start, dtype=index_type)
        ghost = np.flatnonzero(columns >= self._n_owned_columns)
        out[ghost] = self._column_ghosts[columns[ghost] - self._n_owned_columns]
        return out

    def mult(self, x: PETSc.Vec, y: PETSc.Vec) -> None:
        """y = A x for the ghosted Vecs ``x`` and ``y`` of the space, A as last assembled by
        :meth:`assemble_local` (collective; x's ghosts are refreshed, y's ghost entries
        are left 0)."""
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        with x.localForm() as x_local, y.localForm() as y_local:
            values = x_local.array_r
            if self._x is not None:
                self._x[: self.n_local] = values
                values = self._x
            y_local.array[:] = self._rows @ values
        if self.comm.size > 1:
            y.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
            with y.localForm() as y_local:
                y_local.array[self.n_owned :] = 0.0

    def destroy(self) -> None:
        """Nothing to free beyond Python's references (the interface of a PETSc Mat)."""


def _entries(matrix: sp.csr_matrix, rows: np.ndarray, columns: np.ndarray) -> np.ndarray:
    """The positions in ``matrix.data`` of the entries (rows, columns), all in its pattern,
    found among the rows they name only (a sum of sparse matrices would pass every row)."""
    if len(rows) == 0:
        return np.zeros(0, dtype=np.int64)
    n_columns = np.int64(matrix.shape[1])
    touched = np.unique(rows)
    starts, stops = matrix.indptr[touched], matrix.indptr[touched + 1]
    lengths = stops - starts
    positions = np.repeat(starts - np.cumsum(lengths) + lengths, lengths) + np.arange(lengths.sum())
    keys = np.repeat(touched.astype(np.int64), lengths) * n_columns + matrix.indices[positions]
    order = np.argsort(keys)
    wanted = rows.astype(np.int64) * n_columns + columns
    at = np.minimum(np.searchsorted(keys[order], wanted), len(keys) - 1)
    if not np.array_equal(keys[order[at]], wanted):
        raise RuntimeError(  # the pattern is assembled with every rank's rows: a bug
            "an entry received for an owned row is not in the sparsity pattern"
        )
    return positions[order[at]]
