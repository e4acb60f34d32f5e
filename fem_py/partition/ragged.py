"""Ragged arrays: n arrays of different lengths stored as one flat array and offsets (the
coarse edges' chains of ``fem_py.partition.coarse``), not as one small array each
(measurements: docs/design/fem_py.md, "Coarse-edge chains as one flat array"). No
DOLFINx here, so the preconditioners use them without loading it."""
from __future__ import annotations

import operator
from collections.abc import Iterator, Sequence
from typing import Any

import numpy as np

__all__ = ["Ragged", "as_ragged"]


class Ragged(Sequence):
    """An immutable sequence of n arrays of different lengths, stored as one flat array.

    Row k is the read-only view ``flat[offsets[k]:offsets[k + 1]]``; rows share the
    trailing shape of ``flat`` (e.g. (m_k,) dofs or (m_k, 2) coordinates). It behaves
    as a read-only sequence of arrays (``len``, indexing, negative indices, iteration,
    ``np.concatenate``); slicing, :meth:`take` and ``+`` with another sequence of arrays
    give a new ``Ragged``. :meth:`length_groups` and :meth:`rows` give the rows of equal
    length as (B, L, ...) blocks without a Python loop over rows.

    Parameters
    ----------
    flat : (N, ...) array
        The rows one after the other.
    offsets : (n + 1,) int
        Row starts, non-decreasing, from 0 to N.

    Attributes
    ----------
    flat : (N, ...) array, read-only
    offsets : (n + 1,) int64, read-only
    lengths : (n,) int64, read-only
        ``np.diff(offsets)``.
    """

    __slots__ = ("flat", "offsets", "lengths")

    def __init__(self, flat: np.ndarray, offsets: np.ndarray) -> None:
        flat = np.asarray(flat).view()
        offsets = np.array(offsets, dtype=np.int64)  # own copy: the caller's array stays writable
        if flat.ndim < 1 or offsets.ndim != 1 or offsets.size < 1:
            raise ValueError(
                "Ragged needs a flat array with ndim >= 1 and 1-D offsets of length n + 1; "
                "build it with as_ragged from a sequence of arrays"
            )
        lengths = np.diff(offsets)
        if offsets[0] != 0 or offsets[-1] != len(flat) or np.any(lengths < 0):
            raise ValueError(
                f"Ragged offsets must rise from 0 to len(flat) = {len(flat)}; "
                f"got {offsets[0]} .. {offsets[-1]}, decreasing: {bool(np.any(lengths < 0))}"
            )
        for a in (flat, offsets, lengths):
            a.flags.writeable = False
        object.__setattr__(self, "flat", flat)
        object.__setattr__(self, "offsets", offsets)
        object.__setattr__(self, "lengths", lengths)

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError("Ragged is immutable")

    def __reduce__(self) -> tuple:
        return Ragged, (self.flat, self.offsets)

    def __len__(self) -> int:
        return len(self.offsets) - 1

    def __getitem__(self, key: Any) -> Any:
        if isinstance(key, slice):
            start, stop, step = key.indices(len(self))
            if step != 1:
                return self.take(np.arange(start, stop, step))
            stop = max(start, stop)
            a, b = self.offsets[start], self.offsets[stop]
            return Ragged(self.flat[a:b], self.offsets[start : stop + 1] - a)
        k = operator.index(key)
        n = len(self)
        if k < 0:
            k += n
        if not 0 <= k < n:
            raise IndexError(f"Ragged index {key} out of range for {n} rows")
        return self.flat[self.offsets[k] : self.offsets[k + 1]]

    def __iter__(self) -> Iterator[np.ndarray]:
        bounds = self.offsets.tolist()
        flat = self.flat
        for a, b in zip(bounds[:-1], bounds[1:]):
            yield flat[a:b]

    def __add__(self, other: Any) -> Ragged:
        if not isinstance(other, (Ragged, tuple, list)):
            return NotImplemented
        return _concat(
            self, as_ragged(other, dtype=self.flat.dtype, item_shape=self.flat.shape[1:])
        )

    def __radd__(self, other: Any) -> Ragged:
        if not isinstance(other, (Ragged, tuple, list)):
            return NotImplemented
        return _concat(
            as_ragged(other, dtype=self.flat.dtype, item_shape=self.flat.shape[1:]), self
        )

    def __repr__(self) -> str:
        return (
            f"Ragged({len(self)} rows, {len(self.flat)} entries of shape "
            f"{self.flat.shape[1:]} {self.flat.dtype})"
        )

    def take(self, indices: Any) -> Ragged:
        """The rows ``indices`` (any int array, repeats allowed) as a new ``Ragged``."""
        indices = np.asarray(indices, dtype=np.int64).ravel()
        n = len(self)
        if indices.size and (indices.min() < -n or indices.max() >= n):
            raise IndexError(
                f"Ragged.take: indices must lie in [-{n}, {n}); "
                f"got {indices.min()} .. {indices.max()}"
            )
        indices = np.where(indices < 0, indices + n, indices)
        lengths = self.lengths[indices]
        offsets = np.zeros(len(indices) + 1, dtype=np.int64)
        np.cumsum(lengths, out=offsets[1:])
        source = np.repeat(self.offsets[indices] - offsets[:-1], lengths) + np.arange(offsets[-1])
        return Ragged(self.flat.take(source, axis=0), offsets)

    def length_groups(self) -> list[tuple[int, np.ndarray]]:
        """The rows grouped by length: [(L, rows of length L in increasing order)], L increasing.

        The same groups as ``[(L, np.flatnonzero(lengths == L)) for L in np.unique(lengths)]``,
        with one sort instead of one pass per distinct length.
        """
        order = np.argsort(self.lengths, kind="stable")
        sorted_lengths = self.lengths[order]
        cut = np.flatnonzero(sorted_lengths[1:] != sorted_lengths[:-1]) + 1
        starts = np.concatenate([[0], cut]).tolist() if len(order) else []
        return [
            (int(sorted_lengths[a]), order[a:b]) for a, b in zip(starts, starts[1:] + [len(order)])
        ]

    def rows(self, group: Any) -> np.ndarray:
        """Rows ``group`` of equal length L stacked into a (B, L, ...) array (a copy).

        Equals ``np.stack([self[k] for k in group])``, by one fancy index
        ``flat[offsets[group][:, None] + arange(L)]``.
        """
        group = np.asarray(group, dtype=np.int64).ravel()
        if group.size == 0:
            return np.zeros((0, 0) + self.flat.shape[1:], dtype=self.flat.dtype)
        lengths = self.lengths[group]
        if np.any(lengths != lengths[0]):
            raise ValueError(
                "Ragged.rows needs rows of equal length; "
                f"got lengths {lengths.min()} .. {lengths.max()} (group them with length_groups)"
            )
        return self.flat.take(self.offsets[group][:, None] + np.arange(lengths[0]), axis=0)


def _concat(a: Ragged, b: Ragged) -> Ragged:
    return Ragged(
        np.concatenate([a.flat, b.flat]), np.concatenate([a.offsets, b.offsets[1:] + a.offsets[-1]])
    )


def as_ragged(seq: Any, dtype: Any = None, item_shape: tuple = ()) -> Ragged:
    """``seq`` (a :class:`Ragged` or any sequence of arrays) as a ``Ragged``.

    Parameters
    ----------
    seq
        A ``Ragged`` (returned as is unless ``dtype`` asks for a cast) or a sequence of
        arrays sharing their trailing shape.
    dtype
        Cast the entries to this dtype (no copy if they have it already).
    item_shape
        Trailing shape of the rows, used only when ``seq`` is empty (e.g. (2,) for
        coordinates).
    """
    if isinstance(seq, Ragged):
        if dtype is None or seq.flat.dtype == np.dtype(dtype):
            return seq
        return Ragged(seq.flat.astype(dtype), seq.offsets)
    arrays = [np.asarray(a, dtype=dtype) for a in seq]
    if not arrays:
        return Ragged(
            np.zeros((0,) + tuple(item_shape), dtype=dtype or np.float64),
            np.zeros(1, dtype=np.int64),
        )
    if any(a.ndim < 1 or a.shape[1:] != arrays[0].shape[1:] for a in arrays):
        raise ValueError(
            "as_ragged needs arrays with ndim >= 1 and equal trailing shapes; "
            f"got shapes {sorted({a.shape[1:] for a in arrays})} (ndim 0 items are not rows)"
        )
    offsets = np.zeros(len(arrays) + 1, dtype=np.int64)
    np.cumsum([len(a) for a in arrays], out=offsets[1:])
    return Ragged(np.concatenate(arrays), offsets)
