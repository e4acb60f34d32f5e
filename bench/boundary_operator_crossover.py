"""Dense against H-matrix S_h on this machine, in one run: the set-up time of
``bem_cpp.steklov_poincare`` (``compression="none"`` and ``"hmatrix"``, tol
``coupling.options.HMATRIX_TOL``) and the time of one product against the boundary size
n, on the boundary of the square [-1/4, 1/4]^2 (n/4 equal panels per side) with the P1
flux, and the cost of S_h in a solve, set-up + PRODUCTS products (the S_h products of
an ssn solve of the manufactured square; pgpm needs about twice as many). The smallest
n from which the H-matrix is cheaper in a solve is the crossover of
``[solver] boundary_operator = "auto"`` (``coupling.options.HMATRIX_CROSSOVER``; the
tables are in docs/design/hmatrix.md, "The solver's S_h").

    .venv/bin/python bench/boundary_operator_crossover.py [n ...]
"""
from __future__ import annotations

import sys
import time

import numpy as np

import bem_cpp
from coupling.options import HMATRIX_TOL

#: S_h products of one ssn solve (tol 1e-8) of the manufactured square, 32 ... 256 cells
#: per side: 92 ... 121, counted (docs/design/hmatrix.md); pgpm about 205, apgpm 130.
PRODUCTS = 120


def square(n: int, width: float = 0.5) -> np.ndarray:
    """n nodes, counter-clockwise, n/4 equal panels per side."""
    k = n // 4
    t = np.arange(k) / k
    h = width / 2
    sides = [
        np.c_[-h + width * t, -h + 0 * t],
        np.c_[h + 0 * t, -h + width * t],
        np.c_[h - width * t, h + 0 * t],
        np.c_[-h + 0 * t, h - width * t],
    ]
    return np.concatenate(sides)


def best(f, repeat: int) -> tuple[float, object]:
    times, out = [], None
    for _ in range(repeat):
        tic = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - tic)
    return min(times), out


def main(sizes: list[int]) -> None:
    print(
        "| n | dense set-up [s] | H set-up [s] | H / dense | dense product [ms] "
        f"| H product [ms] | in a solve ({PRODUCTS} products): H / dense | H MB | dense MB "
        "| rel. error |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    rng = np.random.default_rng(0)
    for n in sizes:
        X = square(n)
        repeat = 3 if n <= 2000 else 1
        t_dense, S = best(lambda: bem_cpp.steklov_poincare(X, "p1"), repeat)
        t_h, H = best(
            lambda: bem_cpp.steklov_poincare(X, "p1", compression="hmatrix", tol=HMATRIX_TOL),
            repeat,
        )
        x = rng.standard_normal(n)
        p_dense, y = best(lambda: S @ x, 5)
        p_h, yh = best(lambda: H @ x, 5)
        err = np.linalg.norm(yh - y) / np.linalg.norm(y)
        solve_ratio = (t_h + PRODUCTS * p_h) / (t_dense + PRODUCTS * p_dense)
        print(
            f"| {n} | {t_dense:.3f} | {t_h:.3f} | {t_h / t_dense:.2f} | {1e3 * p_dense:.2f} "
            f"| {1e3 * p_h:.2f} | {solve_ratio:.2f} | {H.nbytes / 1e6:.1f} "
            f"| {S.nbytes / 1e6:.1f} | {err:.1e} |",
            flush=True,
        )


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [256, 512, 1024, 2048, 3072, 4096, 6144, 8192])
