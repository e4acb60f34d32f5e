"""Elastic materials of docs/method.md section 12: Hencky's law and linear elasticity.

With eps(u) = (grad u + grad u^T)/2, dev e = e - (tr e / d) I (the d-dimensional deviator)
and |e| the Frobenius norm,

    sigma(u) = kappa tr(eps) I + 2 mu(|dev eps|) dev eps,   -div sigma(u) = f in Omega,
    psi(e)   = kappa/2 (tr e)^2 + g(|dev e|),             g(t) = int_0^t 2 s mu(s) ds,

so that sigma = d psi / d e and G(u) = int psi(eps(u)) dx. The deviatoric part is a scalar
material of :mod:`fem_py.forms.materials` with rho(t) = 2 mu(t): its g is the g above, its
structure condition (t rho(t) strictly increasing, rho > 0) is section 12's
alpha (t - s) <= 2 (t mu(t) - s mu(s)) <= beta (t - s), and its safe branches at 0 carry
over. The hand-written tangent is

    D sigma(e)[h] = kappa tr(h) I + rho(t) dev h + rho'(t)/t (dev e : dev h) dev e,  t = |dev e|,

(rho(0) dev h at dev e = 0). Linear isotropic elasticity is mu constant with
kappa = lambda + 2 mu / d; in 2D this is plane strain (sigma = lambda tr eps I + 2 mu eps).
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

import numpy as np

from fem_py.forms.materials import Material, constant_material, make_material

__all__ = ["ElasticMaterial", "linear_elastic", "hencky", "lame_parameters", "rigid_body_modes"]


def lame_parameters(E: float, nu: float) -> tuple[float, float]:
    """(lambda, mu) of Young's modulus E > 0 and Poisson's ratio -1 < nu < 1/2, or a one-line
    ``ValueError`` naming the bad value."""
    E, nu = float(E), float(nu)
    if not E > 0.0:
        raise ValueError(f"E = {E:g}: Young's modulus must be positive")
    if not -1.0 < nu < 0.5:
        raise ValueError(f"nu = {nu:g}: Poisson's ratio must lie in (-1, 1/2)")
    return E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), E / (2.0 * (1.0 + nu))


@dataclass(frozen=True)
class ElasticMaterial:
    """A Hencky (or linear elastic) material in d dimensions (module docstring).

    Attributes
    ----------
    name
        ``"linear-elastic"`` or ``"hencky"``.
    bulk
        kappa > 0.
    deviatoric
        The scalar material with rho(t) = 2 mu(t) (:class:`fem_py.forms.materials.Material`).
    dim
        d = 2 (plane strain) or 3: the number of components of u.
    """

    name: str
    bulk: float
    deviatoric: Material
    dim: int

    @property
    def components(self) -> int:
        """Unknowns per node: the d components of the displacement."""
        return self.dim

    @property
    def alpha(self) -> float:
        """The structure constant alpha of the shear law: the smallest difference quotient
        of 2 t mu(t) (:attr:`Material.alpha` of the deviatoric part)."""
        return self.deviatoric.alpha

    @property
    def beta(self) -> float:
        """The largest difference quotient of 2 t mu(t)."""
        return self.deviatoric.beta

    @property
    def shear0(self) -> float:
        """mu(0), the shear modulus of the tangent at eps = 0."""
        return 0.5 * self.deviatoric.rho0

    # ------------------------------------------------------------ UFL building blocks
    def _parts(self, u: Any) -> tuple[Any, Any]:
        """(tr eps(u), dev eps(u))."""
        import ufl

        eps = ufl.sym(ufl.grad(u))
        trace = ufl.tr(eps)
        return trace, eps - trace / self.dim * ufl.Identity(self.dim)

    def energy_integrand(self, u: Any) -> Any:
        """UFL psi(eps(u)) = kappa/2 (tr eps)^2 + g(|dev eps|)."""
        import ufl

        trace, dev = self._parts(u)
        return 0.5 * self.bulk * trace**2 + self.deviatoric.energy_density_sq(ufl.inner(dev, dev))

    def stress(self, u: Any) -> Any:
        """UFL sigma(u) = kappa tr(eps) I + 2 mu(|dev eps|) dev eps."""
        import ufl

        trace, dev = self._parts(u)
        return self.bulk * trace * ufl.Identity(self.dim) + self.deviatoric.flux(dev)

    def jacobian_integrand(self, u: Any, w: Any, v: Any) -> Any:
        """UFL D sigma(eps(u))[eps(w)] : eps(v), the hand-written D^2 G(u)(w, v)."""
        import ufl

        _, dev = self._parts(u)
        trace_w, dev_w = self._parts(w)
        trace_v, dev_v = self._parts(v)
        c1, c2 = self.deviatoric.tangent_coefficients(ufl.inner(dev, dev))
        return (
            self.bulk * trace_w * trace_v
            + c1 * ufl.inner(dev_w, dev_v)
            + c2 * ufl.inner(dev, dev_w) * ufl.inner(dev, dev_v)
        )

    def stiffness_integrand(self, w: Any, v: Any) -> Any:
        """UFL kappa tr eps(w) tr eps(v) + 2 mu(0) dev eps(w) : dev eps(v): the linear
        elastic stiffness of the tangent at u = 0 (the preconditioner's interior block)."""
        import ufl

        trace_w, dev_w = self._parts(w)
        trace_v, dev_v = self._parts(v)
        return self.bulk * trace_w * trace_v + self.deviatoric.rho0 * ufl.inner(dev_w, dev_v)


def linear_elastic(E: float, nu: float, dim: int) -> ElasticMaterial:
    """Linear isotropic elasticity of Young's modulus E and Poisson's ratio nu (plane strain
    in 2D): mu = E / (2 (1 + nu)), kappa = lambda + 2 mu / d."""
    lam, mu = lame_parameters(E, nu)
    return ElasticMaterial("linear-elastic", lam + 2.0 * mu / dim, constant_material(2.0 * mu), dim)


def hencky(bulk: float, shear: float | str, dim: int) -> ElasticMaterial:
    """Hencky's material: bulk modulus ``bulk`` > 0 and shear modulus mu(s), a positive number
    or an expression in s = |dev eps| (``fem_py.forms.expressions`` grammar), e.g.
    ``"1 + 1/(1 + s)"``; sympy derives g and mu'. A law that breaks the structure condition
    (2 s mu(s) strictly increasing, mu > 0) is refused in one line."""
    bulk = float(bulk)
    if not bulk > 0.0:
        raise ValueError(f"bulk = {bulk:g}: the bulk modulus kappa must be positive")
    if isinstance(shear, (int, float)) and not isinstance(shear, bool):
        if not shear > 0.0:
            raise ValueError(f"shear = {shear:g}: the shear modulus must be positive")
        return ElasticMaterial("hencky", bulk, constant_material(2.0 * float(shear)), dim)
    if not isinstance(shear, str) or not shear.strip():
        raise ValueError(
            "shear must be a positive number or an expression in s, e.g. 1 + 1/(1 + s)"
        )
    if re.search(r"\bt\b", shear):
        raise ValueError(f"shear = {shear!r}: the shear law is written in s = |dev eps|, not t")
    try:
        deviatoric = make_material("2*(" + re.sub(r"\bs\b", "t", shear) + ")")
    except ValueError as err:
        raise ValueError(f"shear = {shear!r} (rho(t) = 2 mu(t) below, t = s): {err}") from None
    return ElasticMaterial("hencky", bulk, deviatoric, dim)


def rigid_body_modes(V: Any) -> list:
    """The rigid motions of R^d on the vector P1 space ``V`` as orthonormal ghosted PETSc
    vectors (collective; the caller destroys them): the d translations e_k and the rotations,
    in 2D (-y, x), in 3D (-y, x, 0), (0, -z, y), (z, 0, -x) - the near-nullspace of the
    elastic stiffness that algebraic multigrid needs (``Mat.setNearNullSpace``)."""
    from dolfinx import la

    d = V.dofmap.index_map_bs
    index_map = V.dofmap.index_map
    n = index_map.size_local
    x = V.tabulate_dof_coordinates()[:n, :d]
    fields = [np.eye(d)[k][None, :] * np.ones((n, 1)) for k in range(d)]
    pairs = [(0, 1)] if d == 2 else [(0, 1), (1, 2), (2, 0)]
    for i, j in pairs:  # the rotation in the (x_i, x_j) plane: -x_j e_i + x_i e_j
        mode = np.zeros((n, d))
        mode[:, i], mode[:, j] = -x[:, j], x[:, i]
        fields.append(mode)
    modes = []
    for field in fields:
        vec = la.create_petsc_vector(index_map, d)
        vec.array[:] = field.ravel()
        modes.append(vec)
    la.orthonormalize(modes)
    return modes
