"""Quantities derived from a solution for the user: the flux rho du_h/dn on Gamma (the
contact pressure on Gamma_s), the complementarity of the contact conditions (1.5), and
the coefficient b of log|x| in u_e (1.3).
"""
from __future__ import annotations

from typing import Any

import numpy as np

from coupling.adapt.estimator import contact_pressure

__all__ = [
    "boundary_flux",
    "complementarity",
    "log_coefficient",
    "far_field_coefficient",
    "net_force",
    "elastic_boundary_fields",
]


def boundary_flux(problem: Any, solution: Any) -> np.ndarray:
    """sigma_h = rho(|grad u_h|) du_h/dn at the boundary nodes (boundary order; collective).

    The discrete Neumann trace of the interior equation (1.1): tested with the hat
    function v_i of a boundary node i, (rho grad u_h, grad v_i) - (f, v_i) =
    <sigma, v_i>_Gamma, with the boundary mass lumped, so

        sigma_i = (A(u_h) - b_f)_i / m_i,   m_i = (|x_i - x_{i-1}| + |x_{i+1} - x_i|) / 2

    (3D: m_i a third of the area of the triangles at node i).

    At the discrete solution grad_u J_h = 0 makes A(u_h) - b_f = -T^T (S_h z - m_t - s_0),
    so on Gamma_s sigma_i = -lambda_i / m_i with lambda = grad_phi J_h >= 0 the discrete
    multiplier of phi >= 0 ((2.5)): sigma <= 0 and phi sigma = 0 hold node by node, to
    the solver's tolerance. At a corner of Gamma (no normal) the value is that of the
    lumped form, not a point value. The same quantity as the estimator's contact pressure
    (:func:`coupling.adapt.estimator.contact_pressure`), which computes it.
    """
    return contact_pressure(problem, solution.u)


def complementarity(
    phi: np.ndarray, sigma_s: np.ndarray, sigma_scale: float | None = None
) -> float:
    """The largest violation of phi >= 0, sigma <= 0 and phi sigma = 0 on Gamma_s (1.5),
    scale-free: max(-phi) / |phi|_inf, max(sigma) / s and max |phi sigma| / (|phi|_inf s)
    with s = max(|sigma_s|_inf, ``sigma_scale``) (a zero scale counts as 1); 0 without
    Signorini nodes. ``sigma_scale``: the flux's (traction's) scale on all of Gamma, so
    that on a Gamma_s wholly open, where sigma_s is round-off, the round-off is measured
    against the flux's size and not against itself."""
    if phi.size == 0:
        return 0.0
    p_scale = float(np.abs(phi).max()) or 1.0
    s_scale = max(float(np.abs(sigma_s).max()), sigma_scale or 0.0) or 1.0
    worst = max(
        np.max(-phi, initial=0.0) / p_scale,
        np.max(sigma_s, initial=0.0) / s_scale,
        np.max(np.abs(phi * sigma_s)) / (p_scale * s_scale),
    )
    return float(worst) + 0.0  # (+ 0.0: no -0.0 in summary.json)


def far_field_coefficient(problem: Any, solution: Any) -> tuple[str, float]:
    """The leading term of u_e - a at infinity: ``("b", b)`` of b log|x| in 2D
    (:func:`log_coefficient`), ``("c", c)`` of c / |x| in 3D, c = -(1/(4 pi)) int_Gamma
    du_e/dn ds (the flux through a large sphere is -4 pi c; docs/method.md section 11), the
    flux coefficients integrated exactly in their space (P1: the lumped mass, P0: areas)."""
    boundary = problem.boundary
    if problem.domain.dim == 2:
        return "b", log_coefficient(problem, solution)
    flux = np.asarray(solution.flux, dtype=float)
    weights = boundary.triangle_areas if problem.flux_space == "p0" else boundary.lumped_mass
    return "c", float(-(flux @ weights) / (4.0 * np.pi))


def _flux_weights(problem: Any) -> np.ndarray:
    """The integrals of the flux space's basis functions over Gamma: the lumped P1 mass, or
    the panels' lengths (2D) and the triangles' areas (3D) of P0."""
    boundary = problem.boundary
    if problem.flux_space == "p1":
        return boundary.lumped_mass
    return boundary.panel_lengths if problem.domain.dim == 2 else boundary.triangle_areas


def net_force(problem: Any, solution: Any) -> list[float]:
    """F = -int_Gamma sigma_e(u_e) n ds (n out of Omega; elasticity): the net force the body
    exerts on the medium through Gamma, the force of the far field u_e = a + U(x) F + ...
    (docs/method.md section 12), from the traction's coefficients integrated exactly in
    their space."""
    d = problem.components
    flux = np.asarray(solution.flux, dtype=float).reshape(-1, d)
    return [float(-v) + 0.0 for v in flux.T @ _flux_weights(problem)]


def elastic_boundary_fields(problem: Any, solution: Any, traction: np.ndarray) -> dict:
    """The boundary arrays of an elastic run (boundary order; n nodes, d components):
    ``traction`` sigma(u_h) n (n, d) from :func:`boundary_flux`, ``pressure`` its normal
    component n.sigma n (n,), the jump ``jump`` = u_e + u0 - u (n, d) and its normal
    component ``phi`` (n,), ``ue`` (n, d), ``active`` (Signorini nodes in contact) and
    ``signorini`` (nodes with a gap unknown), with the nodal normals of the gap map."""
    boundary, d = problem.boundary, problem.components
    n = boundary.n_nodes
    normals = boundary.node_normals
    traction = np.asarray(traction, dtype=float).reshape(n, d)
    jump = problem.gap.extend(np.zeros(n * d), solution.phi).reshape(n, d)
    active, signorini = np.zeros(n, bool), np.zeros(n, bool)
    active[boundary.signorini] = solution.contact
    signorini[boundary.signorini] = True
    return dict(
        boundary_u=solution.boundary_u.reshape(n, d),
        traction=traction,
        pressure=np.einsum("ij,ij->i", traction, normals),
        jump=jump,
        phi=np.einsum("ij,ij->i", jump, normals),
        ue=np.asarray(solution.ue).reshape(n, d),
        active=active,
        signorini=signorini,
    )


def log_coefficient(problem: Any, solution: Any) -> float:
    """b of u_e = a + b log|x| + O(1/|x|) (1.3): b = (1/(2 pi)) int_Gamma du_e/dn ds, the
    flux coefficients integrated exactly in their space (P1: trapezoidal, P0: midpoint)."""
    lengths = problem.boundary.panel_lengths
    flux = np.asarray(solution.flux, dtype=float)
    if problem.flux_space == "p0":
        total = flux @ lengths
    else:
        total = 0.5 * (flux + np.roll(flux, -1)) @ lengths
    return float(total / (2.0 * np.pi))
