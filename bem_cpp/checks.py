"""Input checks of bem_cpp: each returns the validated array or value, or raises a
one-line ``ValueError`` naming the argument and what is wrong with it."""
from __future__ import annotations

from typing import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

import bem_cpp._bem as _bem

SPACES = {"p0": _bem.Space.P0, "p1": _bem.Space.P1}
KERNEL_HINT = "'laplace' or ('lame', E, nu)"


def kernel(value: str | tuple) -> _bem.Lame | None:
    """The kernel of the boundary operators: None for Laplace's (``"laplace"``), the
    compiled :class:`bem_cpp._bem.Lame` (shear modulus mu, Poisson ratio nu) for Kelvin's
    (``("lame", E, nu)``: Young's modulus E > 0 and -1 < nu < 1/2)."""
    if isinstance(value, str) and value == "laplace":
        return None
    if isinstance(value, (tuple, list)) and len(value) == 3 and value[0] == "lame":
        return _bem.lame_from_young(scalar(value[1], "E"), scalar(value[2], "nu"))
    raise ValueError(f"kernel must be {KERNEL_HINT}, got {value!r}")


def components(lame: _bem.Lame | None, geometry: tuple) -> int:
    """Components per node of the traces: 1 (Laplace) or the dimension d (Lame: d
    components per node, node-major dofs d * node + component)."""
    return 1 if lame is None else (2 if len(geometry) == 1 else 3)


def space(value: str, name: str) -> _bem.Space:
    try:
        return SPACES[value]
    except (KeyError, TypeError):
        raise ValueError(f"{name} must be 'p0' or 'p1', got {value!r}") from None


def points(value: ArrayLike, name: str, rows: str = "m", dim: int = 2) -> NDArray[np.float64]:
    """``value`` as a C-contiguous (rows, dim) float64 array of points; else a one-line
    ``ValueError`` naming ``name`` (finiteness is the caller's check)."""
    try:
        arr = np.ascontiguousarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real ({rows}, {dim}) array") from None
    if arr.ndim != 2 or arr.shape[1] != dim:
        raise ValueError(f"{name} must have shape ({rows}, {dim}), got {arr.shape}")
    return arr


def nodes(value: ArrayLike) -> NDArray[np.float64]:
    arr = np.asarray(value)
    if arr.ndim == 2 and arr.shape[1] == 3:
        raise ValueError(
            f"nodes must have shape (n, 2), got {arr.shape} (the vertices of a surface need"
            " triangles=(m, 3) too)"
        )
    return points(value, "nodes", "n")


def surface(
    vertices: ArrayLike, triangles: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The (n, 3) float64 vertices and (m, 3) int64 triangles of a surface, as the compiled
    code reads them (its Surface checks closedness, orientation and the rest)."""
    X = points(vertices, "vertices", "n", dim=3)
    T = np.asarray(triangles)
    if T.ndim != 2 or T.shape[1] != 3:
        raise ValueError(f"triangles must have shape (m, 3), got {T.shape}")
    if T.size and not np.issubdtype(T.dtype, np.integer):
        raise ValueError(f"triangles must hold integer vertex indices, got dtype {T.dtype}")
    return X, np.ascontiguousarray(T, dtype=np.int64)


def boundary(
    value: ArrayLike, triangles: ArrayLike | None
) -> tuple[NDArray[np.float64]] | tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The arguments of the compiled functions for Gamma: ``(nodes,)`` of a polygon (2D,
    ``triangles`` None) or ``(vertices, triangles)`` of a surface (3D)."""
    return (nodes(value),) if triangles is None else surface(value, triangles)


def dofs(geometry: tuple, space: _bem.Space) -> int:
    """Number of dofs of ``space`` on the checked ``geometry`` (:func:`boundary`): the nodes
    (2D), the vertices (3D, P1) or the triangles (3D, P0)."""
    if len(geometry) == 2 and space == _bem.Space.P0:
        return geometry[1].shape[0]
    return geometry[0].shape[0]


def indices(value: ArrayLike, n: int, name: str) -> NDArray[np.int64]:
    """(k,) distinct integer indices in [0, n), as int64."""
    idx = np.asarray(value)
    if idx.ndim != 1 or (idx.size and not np.issubdtype(idx.dtype, np.integer)):
        raise ValueError(
            f"{name} must be a 1D array of integer indices, got {idx.dtype} {idx.shape}"
        )
    if idx.size and (idx.min() < 0 or idx.max() >= n):
        raise ValueError(f"{name}: indices must lie in [0, {n}), got {idx.min()}..{idx.max()}")
    if np.unique(idx).size != idx.size:
        raise ValueError(f"{name}: indices must be distinct")
    return idx.astype(np.int64)


def vector(value: ArrayLike, n: int, name: str) -> NDArray[np.float64]:
    """(n,) finite float64 values, one per node."""
    return _finite(value, (n,), name, "one value per node")


def field(value: ArrayLike, n: int, d: int, name: str) -> NDArray[np.float64]:
    """(n, d) finite float64 values, d components per node (a vector field's nodal values)."""
    return _finite(value, (n, d), name, f"{d} components per node")


def _finite(
    value: ArrayLike, shape: tuple[int, ...], name: str, meaning: str
) -> NDArray[np.float64]:
    """``value`` as a C-contiguous finite float64 array of ``shape``; else a one-line
    ``ValueError`` naming ``name`` and what the shape means."""
    text = f"({', '.join(map(str, shape))}{',' if len(shape) == 1 else ''})"
    try:
        arr = np.ascontiguousarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real array of shape {text}") from None
    if arr.shape != shape:
        raise ValueError(f"{name} must have shape {text} ({meaning}), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains non-finite values")
    return arr


def translation(value: ArrayLike, d: int) -> NDArray[np.float64]:
    """The translation a at infinity of a vector field: d finite values (the scalar 0, the
    default of the scalar problem, as the zero vector)."""
    if np.ndim(value) == 0 and scalar(value, "a") == 0.0:
        return np.zeros(d)
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"a must be {d} real numbers, got {value!r}") from None
    if arr.shape != (d,):
        raise ValueError(f"a must have {d} components (a translation), got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError("a contains non-finite values")
    return arr


def tolerance(value: float, name: str = "tol") -> float:
    """A relative accuracy (``tol`` of H-matrix blocks, a solver's tolerance): a real
    number in (0, 1)."""
    tol = scalar(value, name)
    if not 0 < tol < 1:
        raise ValueError(f"{name} must lie in (0, 1), got {tol!r}")
    return tol


def scalar(value: float, name: str) -> float:
    try:
        a = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real number, got {value!r}") from None
    if not np.isfinite(a):
        raise ValueError(f"{name} must be finite, got {a}")
    return a


def columnwise(
    apply: Callable[[NDArray[np.float64]], NDArray[np.float64]], x: ArrayLike, n: int
) -> NDArray[np.float64]:
    """``apply`` (of an (n, k) block) to x of shape (n,) or (n, k)."""
    arr = np.asarray(x, dtype=np.float64)
    if arr.ndim not in (1, 2) or arr.shape[0] != n:
        raise ValueError(f"x must have shape ({n},) or ({n}, k), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError("x contains non-finite values")
    y = apply(np.asfortranarray(arr.reshape(n, 1) if arr.ndim == 1 else arr))
    return y[:, 0] if arr.ndim == 1 else y
