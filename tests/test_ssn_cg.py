"""The preconditioned CG of ssn's Newton steps with inexact products (coupling.solvers.ssn).

Each product may be less accurate than the first by the factor the residual has fallen
(relaxed inexact Krylov products); the CG must still reach its rtol in the exact residual.
The tolerances below: the residual gap of CG with product errors eps_k is at most about
sum_k eps_k ||p_k|| ||A^-1||, i.e. a few times the 1e-2 rtol the products are relaxed from.
"""
from __future__ import annotations

import numpy as np
from mpi4py import MPI

from coupling.solvers.ssn import _pcg


def _spd(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    Q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    return (Q * np.logspace(0, 3, n)) @ Q.T


def test_products_are_given_the_factor_the_residual_has_fallen_and_cg_still_meets_rtol():
    n, m, rtol, eps = 60, 20, 1e-6, 1e-2
    A = _spd(n + m, 0)
    rng = np.random.default_rng(1)
    rhs = rng.standard_normal(n + m)
    diag = np.diag(A)
    slacks = []

    def apply_h(p, slack):
        slacks.append(slack)
        y = A @ np.concatenate(p)
        # an error of relative size eps rtol slack, as ssn's V solves allow
        y += eps * rtol * slack * np.linalg.norm(y) * rng.standard_normal(y.size) / np.sqrt(y.size)
        return y[:n], y[n:]

    def apply_b_inv(r):
        return r[0] / diag[:n], r[1] / diag[n:]

    (x_u, x_phi), its = _pcg(
        apply_h,
        apply_b_inv,
        (rhs[:n].copy(), rhs[n:].copy()),
        MPI.COMM_SELF,
        rtol=rtol,
        max_iterations=500,
    )
    x = np.concatenate([x_u, x_phi])
    r = rhs - A @ x
    # the residual in the norm CG stops on (B^-1: the diagonal here), against its start
    assert np.sqrt(r @ (r / diag)) <= 5 * rtol * np.sqrt(rhs @ (rhs / diag))
    assert slacks[0] == 1.0 and len(slacks) == its
    # the factor grows with the falling residual, up to about 1 / rtol
    assert max(slacks) > 1e-2 / rtol and max(slacks) <= 1.0 / rtol
