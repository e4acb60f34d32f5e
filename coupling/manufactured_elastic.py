"""Manufactured elastic contact problems with a known contact set (docs/method.md section 12).

The body is the square [-1/4, 1/4]^2 or the box [-1/4, 1/4]^3, its bottom face x_d = c
(c = -1/4, outward normal n = -e_d) the Signorini face. With s = x_d - c,

    u = r + s^2 v + s w(x) e_d,      w(x) = -K max(0, -x)^3,

r a rigid motion and v smooth: on the face eps(u) = w e_d e_d, so sigma(u) is diagonal
there (the tangential traction vanishes) and the normal traction n.sigma(u)n = kappa w +
2 mu(|dev|) w (1 - 1/d) is < 0 exactly where x < 0 and 0 elsewhere. The gap is normal,
j = phi n with

    phi = G max(0, x)^3 (1/4 - x)            (2D),
    phi = G max(0, x)^3 (1/4 - x) 16 (1/16 - y^2)   (3D),

which vanishes on the face's boundary and is > 0 exactly where x > 0: the contact set is
{x < 0} for "stick" and, since the exact tangential slip is 0 and the tangential traction
vanishes, for "slip" too. The exterior is a translation and a Kelvin point force from
inside, u_e = a + U(x - x0) F, and

    f = -div sigma(u),   t0 = sigma(u) n - sigma_e(u_e) n,   u0 = u - u_e + j   on Gamma.

f and t0 are UFL expressions (exact at the quadrature points); u0 is evaluated at the
boundary nodes.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import ufl

from bem_cpp.kelvin import kelvin_field
from fem_py.forms.elasticity import ElasticMaterial, lame_parameters

__all__ = ["ElasticContact", "elastic_contact", "kelvin_ufl"]

#: The Signorini face x_d = FACE, the width of the contact term K and the gap's size G.
FACE, K, G = -0.25, 20.0, 100.0
#: The exterior medium, the point force from inside and the translation at infinity.
EXTERIOR = (1.5, 0.3)
SOURCE = {2: (0.03, -0.02), 3: (0.03, -0.02, 0.01)}
FORCE = {2: (0.4, -0.7), 3: (0.4, -0.7, 0.3)}
TRANSLATION = {2: (0.1, -0.2), 3: (0.1, -0.2, 0.05)}


def kelvin_ufl(X: Any, source: Any, force: Any, E: float, nu: float) -> Any:
    """UFL U(X - x0) F, Kelvin's displacement of a point force (plane strain in 2D; the
    formula of ``bem_cpp.kelvin.kelvin_field``)."""
    d = len(source)
    _, mu = lame_parameters(E, nu)
    r = X - ufl.as_vector(source)
    rr = ufl.inner(r, r)
    F = ufl.as_vector(force)
    if d == 2:
        c = 1.0 / (8.0 * np.pi * mu * (1.0 - nu))
        return c * (-(3.0 - 4.0 * nu) * 0.5 * ufl.ln(rr) * F + ufl.inner(r, F) * r / rr)
    c = 1.0 / (16.0 * np.pi * mu * (1.0 - nu))
    return c / ufl.sqrt(rr) * ((3.0 - 4.0 * nu) * F + ufl.inner(r, F) * r / rr)


def _interior(x: tuple, lib: Any) -> list:
    """The components of u (module docstring) at coordinates ``x``, numpy or UFL."""
    d = len(x)
    ramp = (lambda a: np.maximum(a, 0.0)) if lib is np else (lambda a: ufl.max_value(a, 0.0))
    s = x[-1] - FACE
    w = -K * ramp(-x[0]) ** 3
    rigid = [0.05 - 0.1 * x[1], -0.02 + 0.1 * x[0]] + ([0.03] if d == 3 else [])
    v = [0.3 * x[0], 0.2 - 0.4 * x[0]] if d == 2 else [0.3 * x[0], 0.2 * x[1], 0.2 - 0.4 * x[0]]
    u = [rigid[k] + s**2 * v[k] for k in range(d)]
    u[-1] = u[-1] + s * w
    return u


def _gap(x: np.ndarray) -> np.ndarray:
    """phi (module docstring) at the points x (k, d) of the face."""
    phi = G * np.maximum(x[:, 0], 0.0) ** 3 * (0.25 - x[:, 0])
    return phi if x.shape[1] == 2 else phi * 16.0 * (0.0625 - x[:, 1] ** 2)


@dataclass(frozen=True)
class ElasticContact:
    """A manufactured case: the data of :class:`coupling.problem.SignoriniProblem` and the
    exact solution."""

    dim: int
    f: Any
    t0: Any
    u0: list
    a: np.ndarray
    exterior: tuple[float, float]

    @property
    def data(self) -> dict[str, Any]:
        """The data keywords of :class:`coupling.problem.SignoriniProblem`: f, u0, t0, a and
        the exterior medium."""
        return dict(f=self.f, u0=self.u0, t0=self.t0, a=self.a, exterior=self.exterior)

    def u(self, points: np.ndarray) -> np.ndarray:
        """The exact u at points (k, d): (k, d)."""
        return np.stack(_interior(tuple(np.asarray(points, float).T), np), axis=1)

    def gap(self, points: np.ndarray) -> np.ndarray:
        """The exact normal gap phi at points (k, d) of the Signorini face."""
        return _gap(np.asarray(points, dtype=float))

    def exterior_field(self, points: np.ndarray) -> np.ndarray:
        """The exact u_e at points (k, d) outside."""
        u, _ = kelvin_field(points, SOURCE[self.dim], FORCE[self.dim], *self.exterior)
        return u + self.a


def elastic_contact(mesh: Any, material: ElasticMaterial) -> ElasticContact:
    """The manufactured case of the module docstring on ``mesh`` (the square or the box of
    width 1/2 centred at 0, ``signorini=["bottom"]``) for ``material``."""
    d = mesh.geometry.dim
    E, nu = EXTERIOR
    lam, mu = lame_parameters(E, nu)
    X = ufl.SpatialCoordinate(mesh)
    n = ufl.FacetNormal(mesh)
    a = np.asarray(TRANSLATION[d], dtype=float)
    u = ufl.as_vector(_interior(tuple(X[k] for k in range(d)), ufl))
    ue = kelvin_ufl(X, SOURCE[d], FORCE[d], E, nu) + ufl.as_vector(a)
    eps = ufl.sym(ufl.grad(ue))
    sigma_e = lam * ufl.tr(eps) * ufl.Identity(d) + 2.0 * mu * eps
    sigma = material.stress(u)
    case = ElasticContact(d, -ufl.div(sigma), ufl.dot(sigma - sigma_e, n), [], a, EXTERIOR)

    def component(k: int):
        def u0(*xn: np.ndarray) -> np.ndarray:
            x, normal = np.stack(xn[:d], axis=1), xn[d:]
            on_face = np.abs(x[:, -1] - FACE) < 1e-12
            j = np.where(on_face, _gap(x), 0.0) * normal[k]
            return case.u(x)[:, k] - case.exterior_field(x)[:, k] + j

        return u0

    case.u0.extend(component(k) for k in range(d))
    return case
