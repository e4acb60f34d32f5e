"""Benchmark of the discrete Steklov-Poincare operator S_h (P1 flux) on the circle of
radius 0.4 (METHOD.md section 4).

For each n the table gives the wall time of ``bem_cpp.steklov_poincare`` (best of
--repeat runs), its stages (assembly of V_h, K_h, W_h in one pass over the panel pairs;
Cholesky V_h = L L^T; Y = L^{-1}(K_h - M_h); S_h = 1/2 (W_h + Y^T Y)), and the ratio to
one dense Cholesky factorisation of a matrix of the same size (scipy.linalg.cholesky,
i.e. LAPACK dpotrf, best of --repeat) measured in the same run. The dense linear algebra
costs n^3/3 + n^3 + n^3 flops, i.e. seven Cholesky factorisations' worth, so the ratio
cannot go below about 7. A last line times V_h, K_h and W_h alone for the largest n.

Run: .venv/bin/python bench/bem_assembly.py [--sizes 512 1024 2048 4096] [--repeat 2]
"""
from __future__ import annotations

import argparse
import os
import time

import numpy as np
import scipy.linalg

import bem_cpp


def circle(n: int, radius: float = 0.4) -> np.ndarray:
    theta = 2 * np.pi * np.arange(n) / n
    return np.c_[radius * np.cos(theta), radius * np.sin(theta)]


def best_of(repeat: int, f):
    best, result = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        result = f()
        best = min(best, time.perf_counter() - t0)
    return best, result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[512, 1024, 2048, 4096])
    parser.add_argument("--repeat", type=int, default=2)
    args = parser.parse_args()

    load = os.getloadavg()[0]
    print(f"bem_cpp {bem_cpp.version()}, {os.cpu_count()} cores, load average {load:.2f}")
    header = (
        f"{'n':>6} {'S_h [s]':>9} {'assembly':>9} {'cholesky':>9} {'trsm':>9} {'syrk':>9}"
        f" {'dpotrf [s]':>11} {'S/chol':>7}"
    )
    print(header)
    print("-" * len(header))
    for n in args.sizes:
        X = circle(n)
        stages = []

        def run():
            t: dict[str, float] = {}
            S = bem_cpp.steklov_poincare(X, "p1", timings=t)
            stages.append(t)
            return S

        t_s, _ = best_of(args.repeat, run)
        best = min(stages, key=lambda t: sum(t.values()))
        V = bem_cpp.single_layer(X, "p1")
        t_chol, _ = best_of(
            args.repeat,
            lambda: scipy.linalg.cholesky(V, lower=True, overwrite_a=False, check_finite=False),
        )
        print(
            f"{n:>6} {t_s:>9.3f} {best['assembly']:>9.3f} {best['cholesky']:>9.3f}"
            f" {best['triangular_solve']:>9.3f} {best['rank_update']:>9.3f} {t_chol:>11.3f}"
            f" {t_s / t_chol:>7.1f}"
        )

    # Where the assembly time goes: each operator alone (S_h assembles them in one pass).
    n = args.sizes[-1]
    X = circle(n)
    parts = {
        "V_h (p1)": lambda: bem_cpp.single_layer(X, "p1"),
        "K_h (p1)": lambda: bem_cpp.double_layer(X, "p1"),
        "W_h": lambda: bem_cpp.hypersingular(X),
    }
    print(
        f"\noperators alone, n = {n}: "
        + ", ".join(f"{k} {best_of(args.repeat, f)[0]:.3f} s" for k, f in parts.items())
    )


if __name__ == "__main__":
    main()
