"""Consistency check of the two Jacobians of the interior energy (docs/method.md 4.1).

For several smooth random states u (random combinations of sin/cos modes, interpolated
into V_h) this compares

- the UFL Jacobian (``ufl.derivative`` of the residual) with the hand-written tangent
  rho^(grad u) of docs/method.md section 6 (for elasticity D sigma(eps(u)) of
  :mod:`fem_py.forms.elasticity`): relative Frobenius norm
  ||A_ufl - A_hand||_F / ||A_ufl||_F;
- a Taylor test of the residual F(u) = DG(u, .) in a smooth random direction du:
  r1(eps) = ||F(u + eps du) - F(u)||              ~ eps^1
  r2(eps) = ||F(u + eps du) - F(u) - eps J du||   ~ eps^2   (J = UFL Jacobian)
  with slopes fitted by least squares on log r against log eps over
  eps = 1e-2 * 2^-k, k = 0..5 (Euclidean norms of the assembled vectors).

Verdict: pass when the matrices agree to 1e-10 relative and the r2 slope is within 0.1
of 2. A material whose residual is linear in u (rho constant) has r2 at round-off for
every eps; then the slope is meaningless and the Taylor part passes when
max r2 / max r1 < 1e-10 (reported as ``"taylor_exact": True``).
"""
from __future__ import annotations

from typing import Any

import numpy as np
from petsc4py import PETSc

from fem_py.dofs.p1 import p1_space
from fem_py.forms.interior import InteriorForms
from fem_py.forms.materials import Material

__all__ = ["check_jacobian", "MATRIX_TOL", "SLOPE_TOL"]

MATRIX_TOL = 1e-10
SLOPE_TOL = 0.1
_EPS = 1e-2 * 2.0 ** -np.arange(6)
_EXACT_RATIO = 1e-10


def _random_mode_function(V: Any, rng: np.random.Generator, n_modes: int = 4) -> Any:
    """A smooth random function sum a_k sin(w_k . x + c_k) of unit-size gradients (x in
    R^2 or R^3, the mesh's dimension); on a vector space (elasticity) one such function per
    component."""
    from dolfinx import fem

    dim = V.mesh.geometry.dim
    components = V.dofmap.index_map_bs
    a = rng.normal(size=(components, n_modes))
    w = rng.normal(scale=4.0, size=(components, n_modes, dim))
    c = rng.uniform(0.0, 2 * np.pi, size=(components, n_modes))

    def modes(x: np.ndarray, i: int) -> np.ndarray:
        return sum(
            a[i, k] * np.sin(sum(w[i, k, d] * x[d] for d in range(dim)) + c[i, k])
            for k in range(n_modes)
        )

    f = fem.Function(V)
    if components == 1:
        f.interpolate(lambda x: modes(x, 0))
    else:
        f.interpolate(lambda x: np.stack([modes(x, i) for i in range(components)]))
    return f


def _slope(eps: np.ndarray, r: np.ndarray) -> float:
    return float(np.polyfit(np.log(eps), np.log(r), 1)[0])


def check_jacobian(domain: Any, material: Material, *, n_states: int = 3, seed: int = 0) -> dict:
    """Compare the UFL and hand-written Jacobians and Taylor-test the residual.

    Parameters
    ----------
    domain
        A :class:`fem_py.mesh.Domain` or :class:`fem_py.mesh.SolidDomain` (anything with
        a ``mesh``, of triangles or tetrahedra).
    material
        The material to check: a scalar ``Material`` or, for elasticity, an
        ``ElasticMaterial`` (its hand-written tangent D sigma, vector P1).
    n_states
        Number of random smooth states.
    seed
        Seed of the random states (same on every rank, so the check is collective-safe).

    Returns
    -------
    dict with keys
        ``matrix_rel_diff`` (max over states of ||A_ufl - A_hand||_F / ||A_ufl||_F),
        ``slope1``, ``slope2`` (lists, one per state), ``taylor_exact`` (residual linear
        in u), ``eps`` (list), ``r1``, ``r2`` (lists of lists), ``passed`` (bool),
        ``material``, ``n_dofs``, ``norm`` (``"frobenius"``), ``tolerances``.
    """
    if n_states < 1:
        raise ValueError(f"n_states must be >= 1, got {n_states}")
    V = p1_space(domain.mesh, material.components)
    forms = InteriorForms(V, material, None, jacobian="ufl")
    rng = np.random.default_rng(seed)
    A1, A2 = forms.create_matrix(), forms.create_matrix()
    F0, F1, Jdu = forms.create_vector(), forms.create_vector(), forms.create_vector()
    rel, s1, s2, r1s, r2s = [], [], [], [], []
    exact = True
    for _ in range(n_states):
        u = _random_mode_function(V, rng)
        du = _random_mode_function(V, rng)
        forms.assemble_jacobian(u, A1, "ufl")
        forms.assemble_jacobian(u, A2, "handwritten")
        ref = A1.norm(PETSc.NormType.FROBENIUS)
        A2.axpy(-1.0, A1)
        rel.append(A2.norm(PETSc.NormType.FROBENIUS) / ref)
        forms.assemble_residual(u, F0)
        A1.mult(du.vector, Jdu)
        w = u.copy()
        r1, r2 = [], []
        for eps in _EPS:
            w.x.array[:] = u.x.array + eps * du.x.array
            forms.assemble_residual(w, F1)
            F1.axpy(-1.0, F0)
            r1.append(F1.norm())
            F1.axpy(-eps, Jdu)
            r2.append(F1.norm())
        r1, r2 = np.array(r1), np.array(r2)
        lin = r2.max() / r1.max() < _EXACT_RATIO
        exact = exact and lin
        s1.append(_slope(_EPS, r1))
        s2.append(float("nan") if lin else _slope(_EPS, r2))
        r1s.append(r1.tolist())
        r2s.append(r2.tolist())
    for obj in (A1, A2, F0, F1, Jdu):
        obj.destroy()
    matrix_ok = max(rel) <= MATRIX_TOL
    taylor_ok = exact or all(abs(s - 2.0) <= SLOPE_TOL for s in s2)
    return {
        "material": material.name,
        "n_dofs": V.dofmap.index_map.size_global * material.components,
        "norm": "frobenius",
        "matrix_rel_diff": float(max(rel)),
        "slope1": s1,
        "slope2": s2,
        "taylor_exact": bool(exact),
        "eps": _EPS.tolist(),
        "r1": r1s,
        "r2": r2s,
        "tolerances": {"matrix": MATRIX_TOL, "slope": SLOPE_TOL},
        "passed": bool(matrix_ok and taylor_ok),
    }
