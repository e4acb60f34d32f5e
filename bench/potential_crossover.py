"""Direct against H-matrix potentials (``bem_cpp.exterior_potential`` with
``compression="none"`` and ``"hmatrix"``, tol ``coupling.options.HMATRIX_TOL``) on this
machine: the time of one evaluation of u_e at the m points of an image grid around the
domain (the whole-plane plot's use) for n boundary dofs, with the load average before
each row. The H-matrix time includes its set-up (each call builds it). The tables and
the crossover of ``compression="auto"`` (``bem_cpp.HMATRIX_POTENTIAL_CROSSOVER``) are in
docs/design/hmatrix.md, "Potentials".

    .venv/bin/python bench/potential_crossover.py [--shape circle|l_shape] n:m [n:m ...]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
from matplotlib.path import Path

import bem_cpp
from coupling.options import HMATRIX_TOL


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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shape", choices=("circle", "l_shape"), default="circle")
    parser.add_argument("sizes", nargs="+", help="n:m pairs")
    args = parser.parse_args()
    make = circle if args.shape == "circle" else l_shape
    print("| n | m | direct [s] | H-matrix [s] | H / direct | max error / max abs u | load |")
    print("|---|---|---|---|---|---|---|")
    for size in args.sizes:
        n, m = (int(x) for x in size.split(":"))
        X = make(n)
        Z = image_grid(X, m)
        rng = np.random.default_rng(0)
        v, psi = rng.standard_normal(len(X)), rng.standard_normal(len(X))
        load = os.getloadavg()[0]
        t = time.perf_counter()
        direct = bem_cpp.exterior_potential(X, v, psi, Z, a=0.1, compression="none")
        t_direct = time.perf_counter() - t
        t = time.perf_counter()
        h = bem_cpp.exterior_potential(X, v, psi, Z, a=0.1, compression="hmatrix", tol=HMATRIX_TOL)
        t_h = time.perf_counter() - t
        err = np.abs(h - direct).max() / np.abs(direct).max()
        print(
            f"| {len(X):,} | {len(Z):,} | {t_direct:.3f} | {t_h:.3f} | {t_h / t_direct:.2f} "
            f"| {err:.1e} | {load:.2f}-{os.getloadavg()[0]:.2f} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
