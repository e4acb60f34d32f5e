"""Closed triangulated test surfaces in 3D (vertices (n, 3), triangles (m, 3), counter-
clockwise seen from outside): the icosphere projected to a sphere and the boundaries of
voxel sets (a cube, a Fichera-type L-shaped polyhedron: the cube without one octant)."""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Surface = tuple[NDArray[np.float64], NDArray[np.int64]]

_T = (1.0 + np.sqrt(5.0)) / 2.0
_ICOSAHEDRON_VERTICES = [
    (-1, _T, 0), (1, _T, 0), (-1, -_T, 0), (1, -_T, 0), (0, -1, _T), (0, 1, _T),
    (0, -1, -_T), (0, 1, -_T), (_T, 0, -1), (_T, 0, 1), (-_T, 0, -1), (-_T, 0, 1),
]  # fmt: skip
_ICOSAHEDRON_TRIANGLES = [
    (0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
    (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
    (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1),
]  # fmt: skip


def icosphere(level: int, radius: float = 1.0, center=(0.0, 0.0, 0.0)) -> Surface:
    """The icosahedron refined ``level`` times (each triangle into 4 by its edge midpoints),
    every vertex projected to the sphere: 10 4^level + 2 vertices, 20 4^level triangles,
    mesh size about 1.1 radius / 2^level."""
    X = [np.array(p, dtype=float) / np.linalg.norm(p) for p in _ICOSAHEDRON_VERTICES]
    T = list(_ICOSAHEDRON_TRIANGLES)
    for _ in range(level):
        mid: dict[tuple[int, int], int] = {}

        def midpoint(a: int, b: int) -> int:
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = X[a] + X[b]
                X.append(p / np.linalg.norm(p))
                mid[key] = len(X) - 1
            return mid[key]

        refined = []
        for i, j, k in T:
            a, b, c = midpoint(i, j), midpoint(j, k), midpoint(k, i)
            refined += [(i, a, c), (j, b, a), (k, c, b), (a, b, c)]
        T = refined
    return radius * np.array(X) + np.asarray(center, dtype=float), np.array(T, dtype=np.int64)


def voxel_surface(inside: NDArray[np.bool_], h: float) -> Surface:
    """The boundary of the union of the voxels ``inside[i, j, k]`` (side h, the box of the
    array centred at the origin): two triangles per exposed voxel face, outward."""
    N = np.array(inside.shape)
    padded = np.pad(inside, 1)
    index: dict[tuple[int, int, int], int] = {}
    triangles = []

    def vertex(p: tuple[int, int, int]) -> int:
        return index.setdefault(p, len(index))

    for i, j, k in zip(*np.nonzero(inside)):
        for axis in range(3):
            u, v = (axis + 1) % 3, (axis + 2) % 3
            for side in (0, 1):
                nb = [i + 1, j + 1, k + 1]
                nb[axis] += 1 if side else -1
                if padded[tuple(nb)]:
                    continue
                corner = [int(i), int(j), int(k)]
                corner[axis] += side
                q = []
                for du, dv in ((0, 0), (1, 0), (1, 1), (0, 1)):
                    p = list(corner)
                    p[u] += du
                    p[v] += dv
                    q.append(vertex(tuple(p)))
                if side:
                    triangles += [(q[0], q[1], q[2]), (q[0], q[2], q[3])]
                else:
                    triangles += [(q[0], q[2], q[1]), (q[0], q[3], q[2])]
    X = np.array(list(index), dtype=float)  # insertion order = vertex numbers
    return h * (X - 0.5 * N), np.array(triangles, dtype=np.int64)


def cube(n: int, side: float = 1.0) -> Surface:
    """The cube [-side/2, side/2]^3 with n x n squares (2 n^2 triangles) per face."""
    return voxel_surface(np.ones((n, n, n), dtype=bool), side / n)


def fichera(n: int, side: float = 1.0) -> Surface:
    """Fichera's corner: the cube of :func:`cube` without the octant x, y, z > 0 (n even)."""
    if n % 2:
        raise ValueError(f"fichera needs an even n, got {n}")
    inside = np.ones((n, n, n), dtype=bool)
    inside[n // 2 :, n // 2 :, n // 2 :] = False
    return voxel_surface(inside, side / n)
