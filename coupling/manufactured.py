"""Manufactured solutions with a known contact set (docs/method.md section 8).

Recipe: pick a smooth u in Omega and u_e = a + b log|x - x0| + c.(x - x0)/|x - x0|^2.
On each Signorini arc (a straight side with arc coordinate xi in [-L/2, L/2] measured
counter-clockwise from its midpoint, and inward distance eta) take

    gap    g*(xi) = G max(0, xi)^3 (L/2 - xi)       (zero at both ends, > 0 for xi > 0)
    flux   du/dn  = -K max(0, -xi)^3                 (< 0 exactly where g* = 0)

so that rho(|grad u|) du/dn <= 0 on the arc and vanishes where the gap is open:
u contains the term K eta max(0, -xi)^3 (times a factor with zero normal derivative
on the other arcs). Then

    f  = -div(rho(|grad u|) grad u)                    (UFL, exact at quadrature points)
    t0 = rho(|grad u|) du/dn - du_e/dn                  on all of Gamma (UFL, FacetNormal)
    u0 = u - u_e + g*                                   (g* = 0 on Gamma_t)

The exact solution has gap g*, contact set {xi < 0} on every arc, exterior field u_e.
Cases: the square [-1/4, 1/4]^2 with the bottom side as Signorini arc; the L-shape
[-1/4, 1/4]^2 minus [0, 1/4]^2 with the bottom side and the inner horizontal side y = 0,
0 <= x <= 1/4, as arcs; the disk and the ellipse with their lower quarter; the L-shape's
corner singularity without contact and with the bottom side in contact
(:func:`lshape_corner_contact`, the case on which adaptivity gains, docs/design/adapt.md).

In 3D (docs/method.md section 11) the same recipe with u_e = a + c/|x - x0| + d.(x - x0)/
|x - x0|^3 and a Signorini face instead of an arc: :func:`box_contact` (the bottom face of
the box, contact for x < 0) and :func:`ball_contact` (the lower half of the sphere, contact
for x < 0); the gap vanishes on the face's boundary curve.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
import ufl

from fem_py.forms import numpy_function, parse_expression

__all__ = [
    "ManufacturedSolution",
    "square_contact",
    "lshape_contact",
    "disk_contact",
    "ellipse_contact",
    "lshape_corner",
    "lshape_corner_contact",
    "box_contact",
    "ball_contact",
    "MANUFACTURED",
    "manufactured_problem",
    "energy_error",
    "solution_errors",
]

_A, _B, _C = 0.5, 0.2, (0.05, -0.03)
_K, _G = 20.0, 100.0


def exterior_field(x0: tuple[float, float]) -> str:
    """u_e = a + b log|x - x0| + c.(x - x0)/|x - x0|^2 (x0 inside Omega, well away from
    Gamma: u_e varies on the length scale |x - x0| along Gamma)."""
    rx, ry = f"(x - ({x0[0]}))", f"(y - ({x0[1]}))"
    return (
        f"{_A} + {_B}*0.5*log({rx}**2 + {ry}**2)"
        f" + ({_C[0]}*{rx} + ({_C[1]})*{ry})/({rx}**2 + {ry}**2)"
    )


def exterior_field_3d(x0: tuple[float, float, float]) -> str:
    """u_e = a + c/|x - x0| + d.(x - x0)/|x - x0|^3 (x0 inside Omega), harmonic outside."""
    r = [f"(x - ({x0[0]}))", f"(y - ({x0[1]}))", f"(z - ({x0[2]}))"]
    r2 = " + ".join(f"{v}**2" for v in r)
    dot = " + ".join(f"({d})*{v}" for d, v in zip(_D3, r))
    return f"{_A} + {_C3}/sqrt({r2}) + ({dot})/({r2})**1.5"


_C3, _D3 = 0.02, (0.01, -0.01, 0.015)


@dataclass(frozen=True)
class Face:
    """A Signorini face of a body (3D): its facet group name, where it lies (the boundary
    nodes at which the expression ``where`` vanishes) and its gap formula."""

    name: str
    where: str  # in x, y, z: zero exactly on the face (among boundary points)
    gap: str  # g* in x, y, z


@dataclass(frozen=True)
class Arc:
    """A straight Signorini arc: end points (counter-clockwise) and its gap formula."""

    start: tuple[float, float]
    end: tuple[float, float]
    gap: str  # g* in x, y (parser language)


@dataclass(frozen=True)
class ManufacturedSolution:
    """Exact data and solution of one manufactured contact problem.

    Attributes
    ----------
    shape, width, center
        The geometry (fem_py.mesh.build_domain arguments).
    arcs
        The Signorini arcs, counter-clockwise end points.
    u, ue
        Exact interior solution and exterior field, expressions in x, y.
    a
        The constant a of (1.3).
    """

    shape: str
    width: float
    center: tuple[float, float]
    arcs: tuple[Arc, ...]
    u: str
    ue: str
    a: float = _A
    radius: float = 0.0  # the disk's (its arcs run along the circle) and the ball's
    semi_axes: tuple[float, float] = (0.0, 0.0)  # the ellipse's (its arcs run along it)
    faces: tuple[Face, ...] = ()  # 3D: the Signorini faces (instead of arcs)

    @property
    def dim(self) -> int:
        return 3 if self.shape in ("box", "ball") or len(self.center) == 3 else 2

    @property
    def variables(self) -> tuple[str, ...]:
        return ("x", "y", "z")[: self.dim]

    @property
    def signorini(self) -> list:
        """``geometry.signorini``: the arcs' end points (2D), the faces' names (3D)."""
        if self.dim == 3:
            return [face.name for face in self.faces]
        return [(arc.start, arc.end) for arc in self.arcs]

    def exact_u(self) -> Callable[..., np.ndarray]:
        return numpy_function(self.u, self.variables)

    def exact_ue(self) -> Callable[..., np.ndarray]:
        return numpy_function(self.ue, self.variables)

    def exact_gap(self, points: np.ndarray) -> np.ndarray:
        """g* at boundary points (m, dim): the arc's (face's) formula on it, 0 elsewhere."""
        gap = np.zeros(len(points))
        if self.dim == 3:
            for face in self.faces:
                where = numpy_function(face.where, self.variables)(*points.T)
                on = np.abs(np.broadcast_to(where, (len(points),))) < 1e-12
                gap[on] = numpy_function(face.gap, self.variables)(*points[on].T)
            return gap
        for arc, on in zip(self.arcs, self._on_arcs(points)):
            gap[on] = numpy_function(arc.gap, ("x", "y"))(*points[on].T)
        return gap

    def _on_arcs(self, points: np.ndarray) -> list[np.ndarray]:
        if self.shape in ("disk", "ellipse"):
            return self._on_conic_arcs(points)
        masks = []
        for arc in self.arcs:
            p0, p1 = np.array(arc.start), np.array(arc.end)
            t = p1 - p0
            rel = points - p0
            along = rel @ t / (t @ t)
            across = np.abs(rel[:, 0] * t[1] - rel[:, 1] * t[0]) / np.linalg.norm(t)
            masks.append((across < 1e-12) & (along >= -1e-12) & (along <= 1 + 1e-12))
        return masks

    def _on_conic_arcs(self, points: np.ndarray) -> list[np.ndarray]:
        """Points of the arcs along the circle or ellipse, by parameter angle (the points
        mapped onto the unit circle)."""
        axes = self.semi_axes if self.shape == "ellipse" else (self.radius, self.radius)
        rel = (points - np.asarray(self.center)) / np.asarray(axes)
        on_circle = np.abs(np.linalg.norm(rel, axis=1) - 1.0) < 1e-9
        angle = np.arctan2(rel[:, 1], rel[:, 0])
        masks = []
        for arc in self.arcs:
            t0, t1 = (
                np.arctan2((p[1] - self.center[1]) / axes[1], (p[0] - self.center[0]) / axes[0])
                for p in (arc.start, arc.end)
            )
            span = (t1 - t0) % (2 * np.pi)
            r = (angle - t0) % (2 * np.pi)
            masks.append(on_circle & ((r <= span + 1e-12) | (r >= 2 * np.pi - 1e-12)))
        return masks

    def u0(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """u0 = u - u_e + g* at boundary points (numpy)."""
        return self._u0_at(x, y)

    def _u0_at(self, *coords: np.ndarray) -> np.ndarray:
        points = np.column_stack(coords)
        return self.exact_u()(*coords) - self.exact_ue()(*coords) + self.exact_gap(points)

    def data(self, mesh: Any, material) -> dict[str, Any]:
        """UFL f and t0 on ``mesh`` and the callable u0, for :class:`SignoriniProblem`."""
        X = ufl.SpatialCoordinate(mesh)
        n = ufl.FacetNormal(mesh)
        variables = dict(zip(self.variables, X))
        u = parse_expression(self.u, variables)
        ue = parse_expression(self.ue, variables)
        flux = material.flux(ufl.grad(u))
        return {
            "f": -ufl.div(flux),
            "t0": ufl.dot(flux - ufl.grad(ue), n),
            "u0": self.u0 if self.dim == 2 else lambda x, y, z: self._u0_at(x, y, z),
            "a": self.a,
        }


def _flux_term(eta: str, xi: str) -> str:
    """K eta max(0, -xi)^3: du/dn = -K max(0, -xi)^3 on the arc where eta = 0."""
    return f"{_K}*({eta})*max(0, -({xi}))**3"


def square_contact() -> ManufacturedSolution:
    """Square [-1/4, 1/4]^2, Signorini arc = bottom side (contact for x < 0)."""
    # The smooth part has du/dy = 0 on y = -1/4 and |du/dx| >= 0.09 > 0 in Omega.
    smooth = "0.2 + 3*x + 0.2*cos(pi*(y + 0.25))*sin(pi*x) + 0.3*(x + 0.1)**2"
    u = f"{smooth} + {_flux_term('y + 0.25', 'x')}"
    arc = Arc((-0.25, -0.25), (0.25, -0.25), f"{_G}*max(0, x)**3*(0.25 - x)")
    return ManufacturedSolution("square", 0.5, (0.0, 0.0), (arc,), u, exterior_field((0.03, -0.02)))


def lshape_contact() -> ManufacturedSolution:
    """L-shape [-1/4, 1/4]^2 minus [0, 1/4]^2 with two arcs: the bottom side (contact for
    x < 0) and the inner side y = 0 from (1/4, 0) to (0, 0) (xi = 1/8 - x; contact for
    x > 1/8). The second flux term carries (1 + 4y)^2, whose y-derivative vanishes on
    the bottom side, so each term only acts on its own arc."""
    # cos(4 pi (y + 1/4)) has zero y-derivative on both y = -1/4 and y = 0.
    smooth = "0.2 + 3*x + 0.05*cos(4*pi*(y + 0.25))*sin(pi*x) + 0.3*(x + 0.1)**2"
    bottom = _flux_term("y + 0.25", "x")
    inner = f"{_flux_term('-y', '0.125 - x')}*(1 + 4*y)**2"
    u = f"{smooth} + {bottom} + {inner}"
    arcs = (
        Arc((-0.25, -0.25), (0.25, -0.25), f"{_G}*max(0, x)**3*(0.25 - x)"),
        Arc((0.25, 0.0), (0.0, 0.0), f"{_G}*max(0, 0.125 - x)**3*x"),
    )
    return ManufacturedSolution("lshape", 0.5, (0.0, 0.0), arcs, u, exterior_field((-0.1, -0.1)))


def disk_contact(radius: float = 0.25) -> ManufacturedSolution:
    """Disk of radius R about 0, Signorini arc = the lower quarter of the circle, from angle
    -3 pi/4 to -pi/4 (x from -R/sqrt 2 to R/sqrt 2; contact for x < 0).

    The smooth part is P(m x, m y) with m = (3R^2 - r^2)/(2R^2), whose radial derivative
    vanishes on the circle; the flux term is K (R^2 - r^2)/(2R) max(0, -x)^3 (du/dn = -K
    max(0, -x)^3 on r = R), the gap G max(0, x)^3 (R/sqrt 2 - x)."""
    R = float(radius)
    m = f"((3*{R}**2 - (x**2 + y**2))/(2*{R}**2))"
    X, Y = f"({m}*x)", f"({m}*y)"
    smooth = f"0.2 + 3*{X} + 0.2*cos(pi*{Y})*sin(pi*{X}) + 0.3*({X} + 0.1)**2"
    u = f"{smooth} + {_K}*(({R}**2 - (x**2 + y**2))/(2*{R}))*max(0, -x)**3"
    c = R / np.sqrt(2.0)
    arc = Arc((-c, -c), (c, -c), f"{_G}*max(0, x)**3*({c} - x)")
    return ManufacturedSolution(
        "disk", 2 * R, (0.0, 0.0), (arc,), u, exterior_field((0.03, -0.02)), radius=R
    )


def ellipse_contact(semi_axes: tuple[float, float] = (0.3, 0.2)) -> ManufacturedSolution:
    """Ellipse x^2/a^2 + y^2/b^2 < 1, Signorini arc = its lower part from the parameter
    angle -3 pi/4 to -pi/4 ((-a, -b)/sqrt 2 to (a, -b)/sqrt 2; contact for x < 0).

    With psi = x^2/a^2 + y^2/b^2, A = diag(1/a^2, 1/b^2) (grad psi = 2 A p) and q = |A p|^2
    + (1 - psi)/(a b) (> 0 in Omega, |grad psi|^2 / 4 on Gamma), the smooth part is
    P(F(p)) with F(p) = p + (1 - psi) A p / (2 q): on Gamma DF n = n - A p (grad psi . n)
    / (2 q) = 0, so its normal derivative vanishes. The flux term is K eta max(0, -x)^3
    with eta = (1 - psi) / (2 sqrt q) (d eta/dn = -1 on Gamma), the gap G max(0, x)^3
    (a/sqrt 2 - x). For a = b = R this is :func:`disk_contact`."""
    a, b = (float(v) for v in semi_axes)
    psi = f"(x**2/{a}**2 + y**2/{b}**2)"
    q = f"(x**2/{a}**4 + y**2/{b}**4 + (1 - {psi})/({a}*{b}))"
    X = f"(x*(1 + (1 - {psi})/(2*{a}**2*{q})))"
    Y = f"(y*(1 + (1 - {psi})/(2*{b}**2*{q})))"
    smooth = f"0.2 + 3*{X} + 0.2*cos(pi*{Y})*sin(pi*{X}) + 0.3*({X} + 0.1)**2"
    u = f"{smooth} + {_K}*((1 - {psi})/(2*sqrt({q})))*max(0, -x)**3"
    ca, cb = a / np.sqrt(2.0), b / np.sqrt(2.0)
    arc = Arc((-ca, -cb), (ca, -cb), f"{_G}*max(0, x)**3*({ca} - x)")
    return ManufacturedSolution(
        "ellipse",
        2 * max(a, b),
        (0.0, 0.0),
        (arc,),
        u,
        exterior_field((0.03, -0.02)),
        semi_axes=(a, b),
    )


def lshape_corner() -> ManufacturedSolution:
    """The L-shape [-1/4, 1/4]^2 minus [0, 1/4]^2 without contact and u = r^(2/3)
    sin(2 theta/3) about the re-entrant corner (0, 0), theta from the side x = 0, y > 0:
    with beta = atan2(x - y, -(x + y)) (zero along (-1, -1), its branch cut in the removed
    quarter), theta = beta + 3 pi/4 and sin(2 theta/3) = cos(2 beta/3). u is harmonic
    (f = 0 for the linear material) with an unbounded gradient at the corner, so uniform
    P1 converges like N^(-1/3) in the energy norm (the adaptivity study)."""
    u = "(x**2 + y**2)**(1/3)*cos(2/3*atan2(x - y, -(x + y)))"
    return ManufacturedSolution("lshape", 0.5, (0.0, 0.0), (), u, exterior_field((-0.1, -0.1)))


def lshape_corner_contact() -> ManufacturedSolution:
    """The L-shape with both the corner singularity and contact: u = smooth + K eta
    max(0, -x)^3 (the bottom side as Signorini arc, contact for x < 0, as in
    :func:`lshape_contact`) + (1 + 4y)^2 r^(2/3) sin(2 theta/3) (:func:`lshape_corner`).
    The factor (1 + 4y)^2 is 1 at the corner and vanishes with its y-derivative on the
    bottom side, so the flux on the arc is that of the contact term alone; u keeps the
    r^(2/3) singularity, f = -div(rho grad u) ~ r^(-1/3) near the corner (in L^2), and
    uniform P1 converges like N^(-1/3) in the energy norm while the contact set is
    known exactly: the case on which adaptivity with contact has something to gain."""
    smooth = "0.2 + 3*x + 0.05*cos(4*pi*(y + 0.25))*sin(pi*x) + 0.3*(x + 0.1)**2"
    corner = lshape_corner().u
    u = f"{smooth} + {_flux_term('y + 0.25', 'x')} + (1 + 4*y)**2*{corner}"
    arc = Arc((-0.25, -0.25), (0.25, -0.25), f"{_G}*max(0, x)**3*(0.25 - x)")
    return ManufacturedSolution("lshape", 0.5, (0.0, 0.0), (arc,), u, exterior_field((-0.1, -0.1)))


def box_contact() -> ManufacturedSolution:
    """The box [-1/4, 1/4]^3 with its bottom face z = -1/4 as Signorini face: gap
    G max(0, x)^3 (1/4 - x)(1/4 - y)(y + 1/4) (zero on the face's four edges), flux
    du/dn = -du/dz = -K max(0, -x)^3 (contact for x < 0). The smooth part has du/dz = 0
    on z = -1/4 and |du/dx| >= 0.09 in Omega."""
    smooth = "0.2 + 3*x + 0.5*y + 0.2*cos(pi*(z + 0.25))*sin(pi*x)*cos(pi*y) + 0.3*(x + 0.1)**2"
    u = f"{smooth} + {_flux_term('z + 0.25', 'x')}"
    face = Face("bottom", "z + 0.25", f"{_G}*max(0, x)**3*(0.25 - x)*(0.25 - y)*(y + 0.25)")
    return ManufacturedSolution(
        "box", 0.5, (0.0, 0.0, 0.0), (), u, exterior_field_3d((0.03, -0.02, 0.01)), faces=(face,)
    )


def ball_contact(radius: float = 0.25) -> ManufacturedSolution:
    """The ball of radius R about 0 with its lower half (``bottom``, z <= 0) as Signorini
    face: gap G max(0, x)^2 max(0, -z) (zero on the equator), flux du/dn = -K max(0, -x)^2
    on the sphere (contact for x < 0). As in :func:`disk_contact`, the smooth part is
    P(m x, m y, m z) with m = (3R^2 - r^2)/(2R^2) (zero radial derivative on the sphere)
    and the flux term K (R^2 - r^2)/(2R) max(0, -x)^2 (u in W^{2, inf}: O(h) energy
    error). On the faceted sphere the data use the facets' normals, so the flux condition
    holds up to the facets' deviation from the sphere. Squares, not the cubes of the other
    cases: gap and multiplier grow like x^2 from the switch line, so the contact state is
    decided one mesh size from it on the meshes the tests afford (with cubes, contact
    nodes up to |x| = 0.13 = 4h were open at h = R/8, measured)."""
    R = float(radius)
    r2 = "(x**2 + y**2 + z**2)"
    m = f"((3*{R}**2 - {r2})/(2*{R}**2))"
    X, Y, Z = f"({m}*x)", f"({m}*y)", f"({m}*z)"
    smooth = f"0.2 + 3*{X} + 0.5*{Y} + 0.2*cos(pi*{Z})*sin(pi*{X}) + 0.3*({X} + 0.1)**2"
    u = f"{smooth} + {_K}*(({R}**2 - {r2})/(2*{R}))*max(0, -x)**2"
    face = Face("bottom", "max(0, z)", f"{_G}*max(0, x)**2*max(0, -z)")
    return ManufacturedSolution(
        "ball",
        2 * R,
        (0.0, 0.0, 0.0),
        (),
        u,
        exterior_field_3d((0.03, -0.02, 0.01)),
        radius=R,
        faces=(face,),
    )


MANUFACTURED = {
    "square": square_contact,
    "lshape": lshape_contact,
    "disk": disk_contact,
    "ellipse": ellipse_contact,
}


def manufactured_problem(
    comm,
    solution: ManufacturedSolution,
    material,
    *,
    cells: int,
    d_over_h: int = 4,
    structured: bool = True,
    **discretisation,
):
    """The :class:`coupling.problem.SignoriniProblem` of ``solution`` on a mesh with
    ``cells`` cells per side of the bounding square (cube) (h = width / cells) and, in 2D,
    subdomains of d = d_over_h * h; ``discretisation``: ``flux_space``, ``jacobian``,
    ``boundary_operator`` of the problem."""
    from coupling.problem import SignoriniProblem
    from fem_py.mesh import GeometrySpec, build_domain

    h = solution.width / cells
    curved = {
        "disk": {"radius": solution.radius},
        "ellipse": {"semi_axes": solution.semi_axes},
        "ball": {"radius": solution.radius},
    }
    sizes = curved.get(solution.shape, {"width": solution.width})
    if solution.dim == 2:  # subdomains, and polygons structured or not: planar keys
        sizes["subdomain_size"] = d_over_h * h
        if solution.shape not in curved:
            sizes["structured"] = structured
    domain = build_domain(
        comm,
        GeometrySpec(
            solution.shape,
            h=h,
            center=solution.center,
            **sizes,
            signorini=solution.signorini,
        ),
    )
    data = solution.data(domain.mesh, material)
    return SignoriniProblem(
        domain, material, f=data["f"], u0=data["u0"], t0=data["t0"], a=data["a"], **discretisation
    )


#: The largest quadrature degree of :func:`energy_error`. UFL's estimate grows with the
#: nesting of the exact expression (20-26 for the manufactured corner and ellipse
#: solutions), and with it the points per cell. For a smooth u degree q errs by
#: O(h^(q+1)); at a corner singularity (|grad u|^2 ~ r^(-2/3)) the corner cells carry a
#: share of |u - u_h|_1^2 of the same order, O(h^(4/3)), as their quadrature error, so the
#: reported error is off by a mesh-independent fraction and its convergence rate is
#: kept. Measurements: docs/design/speed.md, "The energy error's quadrature".
ERROR_QUADRATURE_DEGREE = 10


def energy_error(problem, u_h, exact: str) -> float:
    """|u_h - u|_1, the H^1 seminorm (energy) error of ``u_h`` against the exact solution
    ``exact`` (an expression in x, y; :mod:`fem_py.forms.expressions`) on the problem's mesh,
    integrated at UFL's estimated degree of the integrand, at most
    :data:`ERROR_QUADRATURE_DEGREE` (collective)."""
    from dolfinx import fem
    from mpi4py import MPI
    from ufl.algorithms import estimate_total_polynomial_degree
    from ufl.algorithms.apply_algebra_lowering import apply_algebra_lowering

    from fem_py.forms import compile_form

    mesh = problem.domain.mesh
    X = ufl.SpatialCoordinate(mesh)
    e = u_h - parse_expression(exact, dict(zip(("x", "y", "z"), X)))
    integrand = ufl.inner(ufl.grad(e), ufl.grad(e))
    degree = estimate_total_polynomial_degree(apply_algebra_lowering(integrand))
    dx = ufl.dx(metadata={"quadrature_degree": min(degree, ERROR_QUADRATURE_DEGREE)})
    local = fem.assemble_scalar(compile_form(integrand * dx))
    return float(np.sqrt(mesh.comm.allreduce(local, op=MPI.SUM)))


def _nearest(points: np.ndarray, p: np.ndarray) -> float:
    """The distance from ``p`` to the nearest of ``points`` (inf when there is none)."""
    return float(np.min(np.linalg.norm(points - p, axis=1), initial=np.inf))


def _directions(dim: int) -> np.ndarray:
    """Unit vectors: 8 at equal angles (2D); the 6 axes and the 8 diagonals (3D)."""
    if dim == 2:
        theta = np.linspace(0, 2 * np.pi, 9)[:-1]
        return np.column_stack([np.cos(theta), np.sin(theta)])
    axes = np.vstack([np.eye(3), -np.eye(3)])
    corners = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)])
    return np.vstack([axes, corners / np.sqrt(3.0)])


def solution_errors(
    problem, solution: ManufacturedSolution, result, exterior_points: np.ndarray | None = None
) -> dict[str, float]:
    """Errors of a computed ``result`` against the exact ``solution`` (collective).

    Returns the H^1 seminorm ("energy") error |u_h - u|_1, the largest nodal error of
    u_h, of the gap phi_h and of u_e on Gamma, the largest error of u_e at
    ``exterior_points`` (default: 8 points on the circle of radius 0.6; 3D: 14 points on
    the sphere of radius 0.6), and the number of Signorini nodes whose contact state
    differs from the exact one away from the switch points of the exact contact set.

    Near a switch point both the exact gap (G xi^3 (L/2 - xi) with G L/2 >= 12.5) and the
    exact multiplier (rho K xi^3 with rho K >= 40) vanish like |xi|^3, so within
    |xi| < (e / 12.5)^(1/3), e the measured largest gap error, the contact state is not
    decided by the discretisation; nodes there (or within one mesh size) are ignored. In
    3D the switch points are the contact nodes within 1.5 h of an open node, and an open
    node whose exact gap is at most e (next to the face's boundary curve, where the gap
    vanishes) is not decided either.
    """
    from mpi4py import MPI

    mesh = problem.domain.mesh
    energy = energy_error(problem, result.u, solution.u)
    index_map = problem.V.dofmap.index_map
    x = problem.V.tabulate_dof_coordinates()[: index_map.size_local]
    dim = solution.dim
    exact_u = solution.exact_u()(*x[:, :dim].T)
    nodal = np.abs(result.u.x.array[: index_map.size_local] - exact_u)
    nodal = mesh.comm.allreduce(float(nodal.max(initial=0.0)), op=MPI.MAX)
    b = problem.boundary
    s_nodes = b.nodes[b.signorini]
    gap = solution.exact_gap(s_nodes)
    ue = solution.exact_ue()(*b.nodes.T)
    if exterior_points is None:
        exterior_points = 0.6 * _directions(dim)
    ue_points = problem.exterior(result, exterior_points)
    # switch points of the exact contact set: where the contact state changes along an arc
    exact_contact = gap <= 0.0
    gap_error = float(np.abs(result.phi - gap).max(initial=0.0))
    h = problem.domain.h
    radius = max(1.01 * h, (gap_error / (_G * 0.125)) ** (1 / 3))
    wrong = np.flatnonzero(exact_contact != result.contact)
    if dim == 2:
        same_arc = np.diff(b.arc_of_signorini) == 0
        switches = s_nodes[np.flatnonzero((np.diff(exact_contact.astype(int)) != 0) & same_arc)]
    else:
        wrong = wrong[~((gap[wrong] > 0.0) & (gap[wrong] <= gap_error))]
        opened = s_nodes[~exact_contact]
        switches = np.array(
            [p for p in s_nodes[exact_contact] if _nearest(opened, p) <= 1.5 * h]
        ).reshape(-1, dim)
    far = [_nearest(switches, s_nodes[i]) > radius for i in wrong]
    return {
        "energy": energy,
        "nodal_u": nodal,
        "gap": gap_error,
        "ue_gamma": float(np.abs(result.ue - ue).max()),
        "ue_exterior": float(np.abs(ue_points - solution.exact_ue()(*exterior_points.T)).max()),
        "contact_mismatch": int(np.count_nonzero(far)),
    }
