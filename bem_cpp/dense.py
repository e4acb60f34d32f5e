"""A dense matrix held in single precision and applied in double (:class:`SingleMatrix`):
the Signorini block M_s = E^T W_h E read from an H-matrix of W_h whose blocks are held in
single precision (docs/design/bem3d.md, "Single-precision storage"), at half the memory of
a double array (1.04 GB instead of 2.08 at n_s = 16,129)."""
from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse.linalg
from numpy.typing import NDArray

import bem_cpp._bem as _bem

__all__ = ["SingleMatrix", "release_free_heap"]

#: Rows of A[np.ix_(rows, cols)] gathered at a time (a band of 256 x n_s floats).
_ROWS_PER_BAND = 256


def _is_open_mesh(key: Any) -> bool:
    """Whether ``key`` is ``np.ix_(rows, cols)`` of two integer index arrays."""
    return (
        isinstance(key, tuple)
        and len(key) == 2
        and all(isinstance(k, np.ndarray) and k.dtype.kind in "iu" for k in key)
        and key[0].shape == (key[0].size, 1)
        and key[1].shape == (1, key[1].size)
    )


class SingleMatrix(scipy.sparse.linalg.LinearOperator):
    """The square matrix A whose entries are those of ``entries`` (float32, C order), as a
    double matrix: products are computed in double from the stored entries
    (``bem_cpp``'s ``single_matvec``: each entry exactly representable in double, so A is
    one fixed matrix whatever is done with it), and ``A[rows, cols]`` and
    :meth:`to_dense` give its entries as float64 arrays.

    So it can stand for a dense float64 matrix in ``A @ x``, ``A[np.ix_(I, J)]``,
    ``A.diagonal()``, ``np.asarray(A)`` (a float64 copy) and ARPACK's ``eigsh``.
    """

    def __init__(self, entries: NDArray[np.float32]):
        entries = np.ascontiguousarray(entries, dtype=np.float32)
        if entries.ndim != 2 or entries.shape[0] != entries.shape[1]:
            raise ValueError(f"SingleMatrix needs a square matrix, got shape {entries.shape}")
        super().__init__(np.float64, entries.shape)
        self.entries = entries

    @property
    def nbytes(self) -> int:
        return int(self.entries.nbytes)

    def _matvec(self, x: NDArray[np.float64]) -> NDArray[np.float64]:
        return _bem.single_matvec(self.entries, np.ascontiguousarray(np.ravel(x), dtype=float))

    def _matmat(self, X: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.column_stack([self._matvec(x) for x in np.asarray(X, dtype=float).T])

    def _adjoint(self) -> "SingleMatrix":
        return SingleMatrix(np.ascontiguousarray(self.entries.T))

    def __matmul__(self, x: Any) -> NDArray[np.float64]:
        x = np.asarray(x, dtype=float)
        return self._matvec(x) if x.ndim == 1 else self._matmat(x)

    def __getitem__(self, key: Any) -> NDArray[np.float64]:
        if _is_open_mesh(key):  # A[np.ix_(rows, cols)]: filled a band of rows at a time,
            # without the whole block in single precision next to it
            rows, cols = np.ravel(key[0]), np.ravel(key[1])
            block = np.empty((rows.size, cols.size))
            for start in range(0, rows.size, _ROWS_PER_BAND):
                band = rows[start : start + _ROWS_PER_BAND]
                block[start : start + band.size] = self.entries[band][:, cols]
            return block
        return self.entries[key].astype(np.float64)

    def diagonal(self) -> NDArray[np.float64]:
        return np.diagonal(self.entries).astype(np.float64)

    def to_dense(self) -> NDArray[np.float64]:
        """A as a float64 array (twice the memory: for a factorisation of the whole)."""
        return self.entries.astype(np.float64)

    def __array__(self, dtype: Any = None) -> NDArray:
        return self.to_dense() if dtype is None else self.to_dense().astype(dtype, copy=False)


def release_free_heap() -> bool:
    """Return the memory the C library's heaps keep after large temporaries are freed to
    the system (glibc's ``malloc_trim``; bem/heap.hpp); True if some was returned.

    An H-matrix set-up's near fields, or a dense block's products taken a block of rows at
    a time, leave many freed allocations in the heaps, which the later large arrays
    (mapped anew) cannot reuse: 0.21 of the 0.55 GB resident after the Lame S_h's set-up
    on the 24^3 box's surface, 0.44 GB when M_s^{-1} replaces its factor in the 48^3 box's
    run (docs/design/elasticity.md, "The 48^3 peak"). Cheap (milliseconds); call it after
    such a stage."""
    return bool(_bem.release_free_heap())
