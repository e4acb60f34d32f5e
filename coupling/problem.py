"""The discrete problem (2.3), assembled once: interior forms, boundary map, S_h, loads, J_h.

The pipeline, in the order of docs/method.md: interior forms (fem_py) -> boundary map ->
S_h (bem_cpp) -> J_h (:mod:`coupling.functional`). A :class:`SignoriniProblem` holds what
is assembled and is not changed after construction; preconditioners
(:mod:`coupling.preconditioners`) and solves (:func:`coupling.solvers.solve`) read it.

Example
-------
>>> from mpi4py import MPI
>>> from fem_py.forms import make_material
>>> from fem_py.mesh import GeometrySpec, build_domain
>>> from coupling.options import SolverOptions
>>> from coupling.solvers import solve
>>> spec = GeometrySpec("square", h=1/32, subdomain_size=1/8, signorini=["bottom"])
>>> domain = build_domain(MPI.COMM_WORLD, spec)
>>> problem = SignoriniProblem(domain, make_material("carstensen"), f="1", t0="-1")
>>> solution = solve(problem, SolverOptions())
"""
from __future__ import annotations

import time
from types import MappingProxyType
from typing import Any, Mapping

import numpy as np
from petsc4py import PETSc

import bem_cpp
from fem_py.forms.elasticity import lame_parameters
from coupling.distributed import boundary_operator_kind, steklov_poincare
from coupling.functional import CoupledFunctional
from coupling.options import DEFAULT_TANGENTIAL, DEFAULTS, hmatrix_tol
from fem_py.boundary.blocked import (
    BlockedBoundary,
    elastic_gap_map,
    free_rigid_motion,
    scalar_gap_map,
)
from fem_py.parallel import array_from_root

__all__ = ["SignoriniProblem"]


class SignoriniProblem:
    """The discrete problem (2.3): minimise J_h over u free, phi >= 0 on Gamma_s.

    Parameters
    ----------
    domain
        ``fem_py.mesh.Domain``: mesh, tags, coarse partition, Signorini arcs; or a
        ``fem_py.mesh.SolidDomain`` (3D: the boundary map is the ``SurfaceMap``, S_h the
        3D operator of bem_cpp on its triangles, docs/method.md section 11).
    material
        ``fem_py.forms.materials.Material`` (rho), or for elasticity an
        ``fem_py.forms.elasticity.ElasticMaterial`` (docs/method.md section 12): u is then
        the displacement (d components per node) and the problem's ``equation``
        ``"elasticity"``.
    f, u0, t0
        Data as expression strings (fem_py parser, in x, y (z); u0 and t0 may use nx,
        ny (nz)), UFL
        expressions, or (u0) a callable of boundary coordinates; for elasticity lists of
        d of them (the components). None (the default): zero.
    a
        The constant of (1.3); for elasticity the translation at infinity (d numbers).
    exterior
        Elasticity: (E, nu) of the exterior medium (Kelvin's kernel of the boundary
        operators); None for the scalar equation.
    tangential
        Elasticity: ``"slip"`` (frictionless) or ``"stick"`` on Gamma_s
        (``fem_py.boundary.blocked``).
    flux_space
        The space of the exterior normal derivative: ``"p1"`` or ``"p0"`` (bem_cpp).
    jacobian
        D^2 G from ``"ufl"`` (derived) or ``"handwritten"`` forms (fem_py.forms).
    boundary_operator
        S_h ``"dense"``, as the ``"hmatrix"`` operator of bem_cpp (applied, never
        formed), or ``"auto"`` (by the boundary size,
        :func:`coupling.distributed.boundary_operator_kind`).

    Attributes
    ----------
    V, forms, boundary
        The P1 space, the interior forms and the boundary map T, E.
    S
        S_h (:func:`coupling.distributed.steklov_poincare`): dense, an array in serial and
        :class:`coupling.distributed.RowBlocks` under MPI; or the H-matrix operator
        (``bem_cpp.SteklovPoincareOperator``, under MPI distributed by rows and applied
        collectively). Only ``S @ z`` and ``S.shape`` are common to all.
    boundary_operator
        The S_h chosen: ``"dense"`` or ``"hmatrix"``.
    u0
        u0 at the boundary nodes (boundary order; node-major, d n, for elasticity).
    equation, kernel
        ``"scalar"`` or ``"elasticity"``; the boundary operators' kernel (``"laplace"`` or
        ``("lame", E, nu)``).
    gap
        E of the gap unknowns (``fem_py.boundary.blocked.GapMap``): phi at the Signorini
        nodes, or the elastic gaps in the nodal normal frame.
    functional
        J_h (:class:`coupling.functional.CoupledFunctional`).
    timings
        Seconds per assembly stage: ``forms``, ``steklov_poincare``, ``loads``.
    """

    def __init__(
        self,
        domain: Any,
        material: Any,
        *,
        f: Any = None,
        u0: Any = None,
        t0: Any = None,
        a: Any = 0.0,
        exterior: tuple[float, float] | None = None,
        tangential: str = DEFAULT_TANGENTIAL,
        flux_space: str = DEFAULTS["solver"]["flux_space"],
        jacobian: str = DEFAULTS["solver"]["jacobian"],
        boundary_operator: str = DEFAULTS["solver"]["boundary_operator"],
    ):
        from fem_py.boundary import boundary_map
        from fem_py.dofs import p1_space
        from fem_py.forms import InteriorForms

        d = material.components
        self.equation = "scalar" if d == 1 else "elasticity"
        self.kernel = _exterior_kernel(self.equation, exterior)
        self.domain, self.material, self.tangential = domain, material, tangential
        self.a = float(a) if d == 1 else _translation(a, d)
        self.flux_space, self.jacobian = flux_space, jacobian
        self.comm = domain.mesh.comm
        timings: dict[str, float] = {}
        tic = time.perf_counter()
        self.V = p1_space(domain.mesh, d)
        self.forms = InteriorForms(self.V, material, f, jacobian=jacobian)
        # the nodes' map from the scalar space, whose dofs number the vector space's nodes
        nodal = boundary_map(self.V if d == 1 else p1_space(domain.mesh), domain)
        self.boundary = nodal if d == 1 else BlockedBoundary(nodal, d)
        self.gap = scalar_gap_map(nodal) if d == 1 else elastic_gap_map(self.boundary, tangential)
        if d > 1 and free_rigid_motion(self.boundary, tangential):
            raise ValueError(
                'tangential = "slip" on the whole boundary leaves a rigid motion of the body '
                "free to slide along it (the rotation of a disk or a ball): the solution is "
                'not unique; use "stick", or bond a part of the boundary'
            )
        load = None  # b_f, assembled here when the check needs it, else with the loads
        if d == 1 and self.gap.size == self.boundary.n_gamma:
            load = self.forms.assemble_load()
            _check_free_constant(load)
        timings["forms"] = time.perf_counter() - tic

        tic = time.perf_counter()
        nodes = self.boundary.nodes
        self.boundary_operator = boundary_operator_kind(
            boundary_operator, *nodes.shape, kernel=self.kernel
        )
        self.S = steklov_poincare(
            self.comm,
            nodes,
            flux_space,
            self.boundary_operator,
            kernel=self.kernel,
            **self._surface,
        )
        timings["steklov_poincare"] = time.perf_counter() - tic

        tic = time.perf_counter()
        zero = np.zeros(self.boundary.n_gamma)
        self.u0 = zero if u0 is None else self.boundary.interpolate_boundary(u0)
        m_t = zero if t0 is None else self.forms.boundary_load(t0, self.boundary)
        s_0 = self.S @ (self.a_trace + self.u0)
        self.functional = CoupledFunctional(
            self.forms,
            self.boundary,
            self.S,
            self.forms.assemble_load() if load is None else load,
            m_t + s_0,
            gap=self.gap,
        )
        timings["loads"] = time.perf_counter() - tic
        self.timings: Mapping[str, float] = MappingProxyType(timings)
        self._sealed = True

    def __setattr__(self, name: str, value: Any) -> None:
        if getattr(self, "_sealed", False):
            raise AttributeError(
                f"SignoriniProblem.{name}: the assembled problem is not "
                "changed after construction; build a new one, or pass the "
                "option to coupling.solvers.solve"
            )
        object.__setattr__(self, name, value)

    @property
    def _surface(self) -> dict[str, Any]:
        """The boundary's triangles for bem_cpp in 3D (``triangles=``); nothing in 2D."""
        triangles = getattr(self.boundary, "triangles", None)
        return {} if triangles is None else {"triangles": triangles}

    @property
    def n_signorini(self) -> int:
        """The number of gap unknowns: n_s (phi, or the elastic normal gaps of "stick"), or
        d n_s (the elastic gaps of "slip", :mod:`fem_py.boundary.blocked`)."""
        return self.gap.size

    @property
    def n_dofs(self) -> int:
        """The global number of unknowns of u: N nodes, times d for elasticity."""
        return int(self.V.dofmap.index_map.size_global * self.components)

    @property
    def components(self) -> int:
        """Unknowns per node: 1, or d for elasticity."""
        return self.material.components

    @property
    def a_trace(self) -> float | np.ndarray:
        """a as a boundary vector: the number a, or the translation a repeated at every node
        (node-major, elasticity)."""
        if self.components == 1:
            return self.a
        return np.tile(self.a, self.boundary.n_nodes)

    def exterior_flux(self, ue: np.ndarray) -> np.ndarray:
        """Coefficients of psi_h ~ du_e/dn from the trace ``ue`` (boundary order,
        replicated): V_h psi_h = (K_h - M_h)(ue - a) (docs/method.md section 2), by the dense
        Cholesky solve on rank 0 or by the H-matrix operator's CG solve (collective)."""
        if self.boundary_operator == "hmatrix":
            return self.S.flux(np.asarray(ue, dtype=float) - self.a_trace)
        nodes, d = self.boundary.nodes, self.components
        trace = ue if d == 1 else np.reshape(ue, (-1, d))
        flux = array_from_root(
            self.comm,
            lambda: bem_cpp.exterior_flux(
                nodes, trace, a=self.a, flux=self.flux_space, kernel=self.kernel, **self._surface
            ),
            all_cores=True,
        )
        return flux.ravel()

    def exterior(self, solution: Any, points: np.ndarray) -> np.ndarray:
        """u_e at exterior points (m, 2) ((m, 3) in 3D) by the representation formula
        (docs/method.md section 2), by direct panel sums or, above the measured crossover
        (``bem_cpp``'s ``HMATRIX_POTENTIAL_CROSSOVER_*``), by the rectangular H-matrices of the
        potentials (``compression="auto"``, tol ``coupling.options.hmatrix_tol``). For
        elasticity the displacement of the medium, (m, d), with Kelvin's kernel
        (Somigliana's identity, docs/method.md section 12), by direct sums."""
        d = self.components
        trace, flux = solution.ue, solution.flux
        if d > 1:
            trace, flux = np.reshape(trace, (-1, d)), np.reshape(flux, (-1, d))
        return bem_cpp.exterior_potential(
            self.boundary.nodes,
            trace,
            flux,
            np.asarray(points, dtype=float),
            a=self.a,
            flux=self.flux_space,
            compression="auto",
            tol=hmatrix_tol(self.boundary.nodes),
            **self._surface,
            **({} if d == 1 else {"kernel": self.kernel}),
        )


def _exterior_kernel(equation: str, exterior: tuple[float, float] | None) -> str | tuple:
    """The kernel of the boundary operators: Laplace's for the scalar equation, Kelvin's of
    the medium ``exterior`` = (E, nu) for elasticity; a one-line ``ValueError`` when one is
    given without the other."""
    if equation == "scalar":
        if exterior is not None:
            raise ValueError(
                "exterior (E, nu) is for elasticity; the scalar equation's exterior is Laplace's"
            )
        return "laplace"
    if exterior is None:
        raise ValueError("elasticity needs the exterior medium: exterior=(E, nu)")
    E, nu = exterior
    lame_parameters(E, nu)  # the one-line refusal of a bad medium
    return ("lame", float(E), float(nu))


def _translation(a: Any, d: int) -> np.ndarray:
    """The translation at infinity as a (d,) array: d numbers, or one number for every
    component."""
    values = np.atleast_1d(np.asarray(a, dtype=float))
    if values.shape == (1,):
        values = np.repeat(values, d)
    if values.shape != (d,) or not np.all(np.isfinite(values)):
        raise ValueError(f"a, the translation at infinity, needs {d} finite components, got {a!r}")
    return values


def _check_free_constant(load: PETSc.Vec) -> None:
    """Refuse a scalar problem whose gap lives at every boundary node (Gamma_s = Gamma, no
    arc end pins it) unless int f dx > 0, the sum of the assembled body load ``load`` (b_f,
    which the functional then takes; collective: the same on every rank).

    Then (u + c, phi - c) leaves z = T u + E phi unchanged, and with it G(u) and every term
    of J_h (2.4) but the body load's, which changes by -c int f dx; phi - c >= 0 bounds c
    from above only. So J_h is unbounded below for int f < 0 (no solution), constant along
    c <= min phi for int f = 0 (no unique one), and for int f > 0 its minimiser has
    min phi = 0.
    """
    total, size = load.sum(), load.norm(PETSc.NormType.NORM_1)
    if total <= 1e-12 * size:
        effect = (
            "lowers the energy without bound (no solution)"
            if total < 0
            else "leaves the energy unchanged (no unique solution)"
        )
        raise ValueError(
            f"the Signorini part is the whole boundary and the body load int f dx = {total:.3g}"
            f" is not positive: adding a constant to the gap and subtracting it from u {effect}"
            "; give a load f with a positive integral, or keep a part of the boundary out of "
            "[geometry] signorini"
        )
