"""Nonlinear materials rho of docs/method.md section 1 and their energy densities (2.1).

A material is the coefficient rho in ``-div(rho(|grad u|) grad u) = f`` (1.1). From rho
we need

- ``g(t) = int_0^t s rho(s) ds``           the energy density of G(w) = int g(|grad w|) (2.1),
- ``rho'(t)``                     for the tangent rho^(x) (docs/method.md section 6, (4.1)),
- ``rho^(x) = rho(|x|) I + rho'(|x|) x x^T / |x|``, ``rho^(0) = rho(0) I``.

Every material is held as expressions in the symbol t, translated to UFL or numpy on
demand: the built-ins as closed forms written out below (rho', g and G2 derived by hand;
tests/test_fem_materials.py checks them against sympy's derivation), so that a run with
a built-in material never imports sympy (half a second of every start-up); a user's rho
as sympy expressions, which sympy integrates and differentiates. Built-ins
(``make_material``):

==============  ====================================  ==========================================
name            rho(t)                                g(t)
==============  ====================================  ==========================================
linear          1                                     t^2/2
carstensen      2 + 1/(1+t)                           t^2 + t - ln(1+t)
power           (eps^2+t^2)^((p-2)/2), p>1, eps>0     ((eps^2+t^2)^(p/2) - eps^p)/p
expression      any string in t, parsed by            sympy: int_0^t s rho(s) ds (closed form)
                fem_py.forms.expressions
==============  ====================================  ==========================================

Safety at grad u = 0 (what is done, and why). The energy is written as a function of
s = |grad u|^2, ``G2(s) = g(sqrt(s))``, so that linear and power materials involve no
square root of s at all. For a general material (carstensen: G2(s) = s + sqrt(s) -
ln(1 + sqrt(s))) the UFL derivatives of sqrt(s) are 0/0 at s = 0, so the UFL energy is

    conditional(s > S0, G2(s), rho(0) s / 2),      S0 = 1e-40 (|grad u| = 1e-20),

and the tangent is ``conditional(s > S0, rho(t), rho(0)) I + conditional(s > S0,
rho'(t)/t, 0) x x^T``. Below S0 the quadratic branch differs from g by
|rho'(0)| t^3/3, a relative 1e-20 - far below round-off - so the branch is exact in
double precision, yet its derivatives at s = 0 are the finite limits (rho(0) grad u,
rho(0) I). FFCx emits the conditional as a C ternary that selects one branch, so the
NaN of the unused branch never propagates (tests/test_fem_forms.py assembles both
Jacobians at grad u = 0 and checks every entry is finite).

Structural condition (docs/method.md section 1), checked numerically on
t in [0, 1e3] (1001 uniform points on [0, 1] and 601 log-spaced on [1, 1e3]):
rho finite and > 0 (the condition with s = 0 gives rho(t) >= alpha > 0; a material
with rho(0) = 0 would have a singular tangent at grad u = 0), and t rho(t) strictly
increasing. ``alpha`` and ``beta`` are the smallest and largest difference quotients
of t rho(t) on that grid (estimates of the constants of section 1 on bounded
gradients).
"""
from __future__ import annotations

import re

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from fem_py.forms.expressions import Expression, from_sympy

__all__ = [
    "Material",
    "make_material",
    "constant_material",
    "BUILTIN_MATERIALS",
    "S0",
    "check_grid",
]

#: Threshold on s = |grad u|^2 below which the quadratic branch is used (see module docstring).
S0 = 1e-40
BUILTIN_MATERIALS = ("linear", "carstensen", "power")


def _symbol(name: str) -> Any:
    """The positive sympy symbol ``name`` (t or s; sympy returns the same object for the
    same name and assumptions)."""
    import sympy

    return sympy.Symbol(name, positive=True)


def _evaluate(term: Any, variables: dict[str, Any], backend: str) -> Any:
    """A material's term (an :class:`Expression`: a built-in's closed form; or a sympy
    expression: derived for a user's rho) in ``backend`` ("ufl" or "numpy")."""
    if isinstance(term, Expression):
        return term.evaluate(variables, backend)
    return from_sympy(term, variables, backend)


def _as_sympy(term: Any, name: str) -> Any:
    """A material's term as a sympy expression in the positive symbol ``name``."""
    if isinstance(term, Expression):
        return term.evaluate({name: _symbol(name)}, "sympy")
    return term


def check_grid() -> np.ndarray:
    """The grid of t values on which the structural condition is checked."""
    return np.unique(np.concatenate([np.linspace(0.0, 1.0, 1001), np.logspace(0.0, 3.0, 601)]))


def _is_ufl(x: Any) -> bool:
    import ufl

    return isinstance(x, ufl.core.expr.Expr)


@dataclass(frozen=True)
class Material:
    """A material rho with its energy density g and derivative rho' (docs/method.md 1, 2.1, 4.1).

    Attributes
    ----------
    name
        ``"linear"``, ``"carstensen"``, ``"power(p=..,eps=..)"`` or the user expression.
    rho_term, g_term, drho_term
        rho(t), g(t) and rho'(t): closed forms (:class:`Expression` in ``t``) for the
        built-ins, sympy expressions in the positive symbol ``t`` for a user's rho
        (:attr:`rho_sym` and the others give sympy expressions in both cases).
    rho0
        rho(0) (the tangent at grad u = 0 is rho(0) I).
    alpha, beta
        smallest and largest difference quotient of t rho(t) on :func:`check_grid`.
    """

    name: str
    rho_term: Any = field(compare=False)
    g_term: Any = field(repr=False, compare=False)
    drho_term: Any = field(repr=False, compare=False)
    rho0: float
    alpha: float
    beta: float
    #: G2(s) = g(sqrt(s)), in the symbol ``s``
    _g2_term: Any = field(repr=False, compare=False, default=None)

    @property
    def rho_sym(self) -> Any:
        """rho(t) as a sympy expression (imports sympy)."""
        return _as_sympy(self.rho_term, "t")

    @property
    def g_sym(self) -> Any:
        """g(t) as a sympy expression (imports sympy)."""
        return _as_sympy(self.g_term, "t")

    @property
    def drho_sym(self) -> Any:
        """rho'(t) as a sympy expression (imports sympy)."""
        return _as_sympy(self.drho_term, "t")

    # ------------------------------------------------------ dispatching API
    def rho(self, t: Any) -> Any:
        """rho(t) for a UFL expression t (UFL result) or an array/float t (numpy)."""
        return self._eval(self.rho_term, t)

    def drho(self, t: Any) -> Any:
        """rho'(t), UFL or numpy like :meth:`rho`."""
        return self._eval(self.drho_term, t)

    def energy_density(self, t: Any) -> Any:
        """g(t) = int_0^t s rho(s) ds (2.1), UFL or numpy like :meth:`rho`.

        For UFL use on |grad u| prefer :meth:`energy_density_sq`, which is safe at 0.
        """
        return self._eval(self.g_term, t)

    def rho_np(self, t: Any) -> np.ndarray:
        """numpy rho(t)."""
        return self._eval(self.rho_term, np.asarray(t, dtype=float))

    def drho_np(self, t: Any) -> np.ndarray:
        """numpy rho'(t)."""
        return self._eval(self.drho_term, np.asarray(t, dtype=float))

    def g_np(self, t: Any) -> np.ndarray:
        """numpy g(t)."""
        return self._eval(self.g_term, np.asarray(t, dtype=float))

    def _eval(self, term: Any, t: Any) -> Any:
        if _is_ufl(t):
            return _evaluate(term, {"t": t}, "ufl")
        t = np.asarray(t, dtype=float)
        with np.errstate(all="ignore"):
            v = _evaluate(term, {"t": t}, "numpy")
        return np.broadcast_to(np.asarray(v, dtype=float), t.shape).copy() if t.shape else float(v)

    # ------------------------------------------------------ UFL building blocks
    def energy_density_sq(self, s: Any) -> Any:
        """UFL ``G2(s) = g(sqrt(s))`` for s = |grad u|^2, safe at s = 0 (module docstring)."""
        import ufl

        g2 = _evaluate(self._g2_term, {"s": s}, "ufl")
        return ufl.conditional(ufl.gt(s, S0), g2, 0.5 * self.rho0 * s)

    def tangent_coefficients(self, s: Any) -> tuple[Any, Any]:
        """UFL (c1, c2) = (rho(t), rho'(t)/t) at t = sqrt(s), s = |x|^2, and (rho(0), 0) at
        s = 0: the tangent of x -> rho(|x|) x is c1 I + c2 x x^T, for a vector x or (the
        deviator of an elastic strain, :mod:`fem_py.forms.elasticity`) a tensor."""
        import ufl

        t = ufl.sqrt(s)
        c1 = ufl.conditional(ufl.gt(s, S0), self.rho(t), self.rho0)
        c2 = ufl.conditional(ufl.gt(s, S0), self.drho(t) / t, 0.0)
        return c1, c2

    def tangent(self, x: Any) -> Any:
        """UFL 2x2 tangent rho^(x) = rho(|x|) I + rho'(|x|) x x^T / |x| (4.1); rho(0) I at x = 0."""
        import ufl

        c1, c2 = self.tangent_coefficients(ufl.inner(x, x))
        return c1 * ufl.Identity(ufl.shape(x)[0]) + c2 * ufl.outer(x, x)

    def flux(self, x: Any) -> Any:
        """UFL rho(|x|) x (the flux of (1.1)), safe at x = 0."""
        import ufl

        s = ufl.inner(x, x)
        return ufl.conditional(ufl.gt(s, S0), self.rho(ufl.sqrt(s)), self.rho0) * x

    # ------------------------------------------------------ the scalar equation's forms
    #: unknowns per node: u is a scalar
    components = 1

    def energy_integrand(self, u: Any) -> Any:
        """UFL g(|grad u|) (2.1), the integrand of G(u)."""
        import ufl

        grad_u = ufl.grad(u)
        return self.energy_density_sq(ufl.inner(grad_u, grad_u))

    def jacobian_integrand(self, u: Any, w: Any, v: Any) -> Any:
        """UFL (rho^(grad u) grad w) . grad v, the hand-written D^2 G(u)(w, v) (4.1)."""
        import ufl

        return ufl.inner(ufl.dot(self.tangent(ufl.grad(u)), ufl.grad(w)), ufl.grad(v))

    @staticmethod
    def stiffness_integrand(w: Any, v: Any) -> Any:
        """UFL grad w . grad v: the Laplace stiffness A_lap of the preconditioners (4.2)."""
        import ufl

        return ufl.inner(ufl.grad(w), ufl.grad(v))


def _check_structure(
    name: str, rho_np: Callable[[np.ndarray], np.ndarray]
) -> tuple[float, float, float]:
    """(rho(0), alpha, beta) of ``rho_np`` on :func:`check_grid` (whose first point is t =
    0), or the ValueError of the structural condition it violates (module docstring)."""
    t = check_grid()
    with np.errstate(all="ignore"):
        r = np.asarray(rho_np(t), dtype=float) * np.ones_like(t)
    bad = ~np.isfinite(r)
    if bad.any():
        raise ValueError(
            f"material {name!r}: rho is not finite at t = {t[bad][0]:.6g}; "
            "rho must be finite on [0, inf)"
        )
    if (r <= 0).any():
        i = int(np.argmax(r <= 0))
        raise ValueError(
            f"material {name!r}: rho({t[i]:.6g}) = {r[i]:.6g} <= 0; docs/method.md section 1 "
            "implies rho(t) >= alpha > 0, make rho positive"
        )
    q = np.diff(t * r) / np.diff(t)
    if not (q > 0).all():
        i = int(np.argmax(q <= 0))
        raise ValueError(
            f"material {name!r}: t*rho(t) is not strictly increasing near t = {t[i]:.6g}; "
            "docs/method.md section 1 needs alpha (t-s) <= t rho(t) - s rho(s)"
        )
    return float(r[0]), float(q.min()), float(q.max())


def _builtin(name: str, rho: str, g: str, drho: str, g2: str) -> Material:
    """A built-in material from its closed forms in t (rho, g, rho') and s (G2(s) =
    g(sqrt(s))), without sympy."""
    terms = [Expression(text, (var,)) for text, var in ((rho, "t"), (g, "t"), (drho, "t"))]
    rho_np = lambda tt: terms[0].evaluate({"t": tt}, "numpy")  # noqa: E731
    rho0, alpha, beta = _check_structure(name, rho_np)
    return Material(
        name=name,
        rho_term=terms[0],
        g_term=terms[1],
        drho_term=terms[2],
        rho0=rho0,
        alpha=alpha,
        beta=beta,
        _g2_term=Expression(g2, ("s",)),
    )


def _build(name: str, rho: Any) -> Material:
    """A material from a user's rho (a sympy expression in t): g and rho' by sympy."""
    import sympy

    t, s = _symbol("t"), _symbol("s")
    rho = sympy.sympify(rho)
    rho_np = lambda tt: from_sympy(rho, {"t": tt}, "numpy")  # noqa: E731
    rho0, alpha, beta = _check_structure(name, rho_np)
    anti = sympy.integrate(t * rho, t)
    if anti.has(sympy.Integral) or anti.has(sympy.Piecewise):
        raise ValueError(
            f"material {name!r}: sympy cannot integrate t*rho(t) in closed form; "
            "give a rho with an elementary antiderivative"
        )
    at0 = anti.subs(t, 0)
    if not at0.is_finite:
        at0 = sympy.limit(anti, t, 0, "+")
    if not at0.is_finite:
        raise ValueError(
            f"material {name!r}: int_0^t s rho(s) ds diverges at 0; rho must be finite at 0"
        )
    g = anti - at0
    drho = sympy.diff(rho, t)
    g2 = g.subs(t, sympy.sqrt(s))
    for e, what in ((g, "g(t)"), (drho, "rho'(t)")):  # fail here, not at form compilation
        try:
            from_sympy(e, {"t": np.ones(1), "s": np.ones(1)}, "numpy")
        except ValueError as err:
            raise ValueError(
                f"material {name!r}: {what} = {e} cannot be evaluated ({err})"
            ) from None
    return Material(
        name=name,
        rho_term=rho,
        g_term=g,
        drho_term=drho,
        rho0=rho0,
        alpha=alpha,
        beta=beta,
        _g2_term=g2,
    )


def constant_material(value: float) -> Material:
    """The linear material rho = ``value`` > 0 (g = value t^2 / 2), without sympy."""
    c = repr(float(value))
    return _builtin(f"constant({c})", c, f"{c}*t^2/2", "0", f"{c}*s/2")


def make_material(
    name_or_expression: str, *, p: float | None = None, eps: float | None = None
) -> Material:
    """Build a material by name (``linear``, ``carstensen``, ``power``) or from rho(t) as text.

    Parameters
    ----------
    name_or_expression
        A built-in name, or an expression in ``t`` for rho(t) (fem_py.forms.expressions
        grammar), e.g. ``"2 + 1/(1+t)"``; sympy derives g and rho'.
    p, eps
        Exponent (> 1) and regularisation (> 0) of ``power``: rho = (eps^2+t^2)^((p-2)/2).
        Required for ``power`` and ignored by the other materials (so that a
        configuration may always carry them).

    Raises
    ------
    ValueError
        Missing or invalid p/eps, a bad expression, a rho violating docs/method.md section 1
        (rho < 0 or t rho(t) not strictly increasing on [0, 1e3]) or a rho whose energy
        has no closed form.
    """
    if not isinstance(name_or_expression, str) or not name_or_expression.strip():
        raise ValueError(
            "material must be a non-empty string: linear, carstensen, power or an expression in t"
        )
    key = name_or_expression.strip()
    if key == "linear":
        return _builtin("linear", "1", "t^2/2", "0", "s/2")
    if key == "carstensen":
        return _builtin(
            "carstensen",
            "2 + 1/(1 + t)",
            "t^2 + t - log(1 + t)",
            "-1/(1 + t)^2",
            "s + sqrt(s) - log(1 + sqrt(s))",
        )
    if key == "power":
        if p is None or eps is None:
            raise ValueError("material 'power' needs both p > 1 and eps > 0, e.g. p=1.5, eps=0.1")
        try:
            p, eps = float(p), float(eps)
        except (TypeError, ValueError):
            raise ValueError(
                f"material 'power' needs numbers p and eps, got p={p!r}, eps={eps!r}"
            ) from None
        if not (np.isfinite(p) and p > 1):
            raise ValueError(f"material 'power' needs p > 1, got p={p}")
        if not (np.isfinite(eps) and eps > 0):
            raise ValueError(f"material 'power' needs eps > 0, got eps={eps}")
        q, e = repr(p), repr(eps)  # exact: repr round-trips a float
        return _builtin(
            f"power(p={p:g},eps={eps:g})",
            f"({e}^2 + t^2)^(({q} - 2)/2)",
            f"(({e}^2 + t^2)^({q}/2) - {e}^{q})/{q}",
            f"({q} - 2)*t*({e}^2 + t^2)^(({q} - 4)/2)",
            f"(({e}^2 + s)^({q}/2) - {e}^{q})/{q}",
        )
    if re.fullmatch(r"[A-Za-z_]\w*", key) and key != "t":
        raise ValueError(
            f"unknown material {key!r}; the named materials are {', '.join(BUILTIN_MATERIALS)} "
            '(lower case), or give rho(t) as an expression in t, e.g. "2 + 1/(1+t)"'
        )
    rho = Expression(key, ("t",)).evaluate({"t": _symbol("t")}, "sympy")
    return _build(key, rho)
