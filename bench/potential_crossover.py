"""Direct against H-matrix potentials (``bem_cpp.exterior_potential`` with
``compression="none"`` and ``"hmatrix"``, tol ``coupling.options.HMATRIX_TOL``) on this
machine: the time of one evaluation of u_e at the m points of an image grid around the
domain (the whole-plane plot's use) for n boundary dofs, with the load average before
each row. The H-matrix time includes its set-up (each call builds it). The tables and
the crossover of ``compression="auto"`` (``bem_cpp.HMATRIX_POTENTIAL_CROSSOVER``) are in
docs/design/hmatrix.md, "Potentials".

3D (``--shape sphere|cube``, tol ``coupling.options.hmatrix_tol``): n is the number
of vertices (the nearest icosphere level, or cube with that many), the m points a pixel
grid on the body's mid-plane out to twice its half-width, outside it (the slice picture
of a 3D run, coupling/io/body_figure_data.py); docs/design/bem3d.md, "The exterior
potential".

    .venv/bin/python bench/potential_crossover.py [--shape circle|l_shape|sphere|cube] n:m [n:m ...]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
from matplotlib.path import Path

import bem_cpp
from bem_cpp.surfaces import cube, icosphere
from coupling.options import HMATRIX_TOL, hmatrix_tol


def circle(n: int, radius: float = 0.4) -> np.ndarray:
    t = 2 * np.pi * np.arange(n) / n
    return np.column_stack([radius * np.cos(t), radius * np.sin(t)])


def l_shape(n: int, side: float = 0.6) -> np.ndarray:
    """The square of `side` without its upper right quarter, n/8 panels per half side."""
    s = side / 2
    corners = np.array([[-s, -s], [s, -s], [s, 0.0], [0.0, 0.0], [0.0, s], [-s, s]])
    k = n // 8
    per = [2 * k, k, k, k, k, 2 * k]
    pieces = [
        corners[i] + np.outer(np.arange(p) / p, corners[(i + 1) % 6] - corners[i])
        for i, p in enumerate(per)
    ]
    return np.vstack(pieces)


def image_grid(nodes: np.ndarray, m: int) -> np.ndarray:
    """About m points of a square pixel grid on [-1, 1]^2 outside the polygon."""
    inside = abs(
        np.sum(nodes[:, 0] * np.roll(nodes[:, 1], -1) - np.roll(nodes[:, 0], -1) * nodes[:, 1])
    )
    k = int(np.ceil(np.sqrt(m / (1 - inside / 2 / 4))))
    g = np.linspace(-1, 1, k) + np.pi * 1e-5  # off the polygon's lines x, y = 0, +-0.3
    G = np.column_stack([c.ravel() for c in np.meshgrid(g, g)])
    return np.ascontiguousarray(G[~Path(nodes).contains_points(G, radius=-1e-9)])


def surface(shape: str, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The icosphere (radius 0.5) or cube (side 1) with about n vertices."""
    if shape == "sphere":
        level = int(np.clip(np.round(np.log(max(n - 2, 10) / 10) / np.log(4)), 0, 7))
        X, T = icosphere(level, 0.5)
        return X, T
    k = max(1, int(np.round(np.sqrt(max(n - 2, 6) / 6))))
    X, T = cube(k)
    return X, T


def slice_grid(shape: str, m: int) -> np.ndarray:
    """About m pixel centres of the plane z = 0 on [-1, 1]^2 (twice the body's half-width)
    outside the body (the ball of radius 0.5 or the cube of side 1 about 0, with a margin
    of 1e-4 relative), shifted by a third of a pixel as in the slice picture."""
    half = 0.5
    k = int(np.ceil(np.sqrt(m / (1 - np.pi / 16))))
    g = np.linspace(-2.0, 2.0, k) * half
    g = g + (g[1] - g[0]) / 3.0
    G = np.column_stack([c.ravel() for c in np.meshgrid(g, g)] + [np.zeros(k * k)])
    size = np.linalg.norm(G, axis=1) if shape == "sphere" else np.abs(G).max(axis=1)
    return np.ascontiguousarray(G[size > half * 1.0001])


def cases(shape: str, sizes: list[str]):
    """(boundary nodes, evaluation points, the keywords of ``exterior_potential``) of every
    n:m size."""
    for size in sizes:
        n, m = (int(x) for x in size.split(":"))
        if shape in ("sphere", "cube"):
            X, T = surface(shape, n)
            yield X, slice_grid(shape, m), {"triangles": T, "tol": hmatrix_tol(X)}
        else:
            X = circle(n) if shape == "circle" else l_shape(n)
            yield X, image_grid(X, m), {"tol": HMATRIX_TOL}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--shape", choices=("circle", "l_shape", "sphere", "cube"), default="circle"
    )
    parser.add_argument("sizes", nargs="+", help="n:m pairs")
    args = parser.parse_args()
    print("| n | m | direct [s] | H-matrix [s] | H / direct | max error / max abs u | load |")
    print("|---|---|---|---|---|---|---|")
    for X, Z, keywords in cases(args.shape, args.sizes):
        rng = np.random.default_rng(0)
        v, psi = rng.standard_normal(len(X)), rng.standard_normal(len(X))
        load = os.getloadavg()[0]
        t = time.perf_counter()
        direct = bem_cpp.exterior_potential(X, v, psi, Z, a=0.1, compression="none", **keywords)
        t_direct = time.perf_counter() - t
        t = time.perf_counter()
        h = bem_cpp.exterior_potential(X, v, psi, Z, a=0.1, compression="hmatrix", **keywords)
        t_h = time.perf_counter() - t
        err = np.abs(h - direct).max() / np.abs(direct).max()
        print(
            f"| {len(X):,} | {len(Z):,} | {t_direct:.3f} | {t_h:.3f} | {t_h / t_direct:.2f} "
            f"| {err:.1e} | {load:.2f}-{os.getloadavg()[0]:.2f} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
