"""The discrete problem (2.3), assembled once: interior forms, boundary map, S_h, loads, J_h.

The pipeline, in the order of METHOD.md: interior forms (fem_py) -> boundary map ->
S_h (bem_cpp) -> J_h (:mod:`coupling.functional`). A :class:`SignoriniProblem` holds what
is assembled and is not changed after construction; preconditioners
(:mod:`coupling.preconditioners`) and solves (:func:`coupling.solvers.solve`) read it.

Example
-------
>>> from mpi4py import MPI
>>> from fem_py.geometry import build_domain
>>> from fem_py.materials import make_material
>>> from coupling.options import SolverOptions
>>> from coupling.solvers import solve
>>> domain = build_domain(MPI.COMM_WORLD, "square", h=1/32, subdomain_size=1/8,
...                       signorini=["bottom"])
>>> problem = SignoriniProblem(domain, make_material("carstensen"), f="1", t0="-1")
>>> solution = solve(problem, SolverOptions())
"""
from __future__ import annotations

import time
from types import MappingProxyType
from typing import Any, Mapping

import numpy as np

import bem_cpp
from coupling.distributed import RowBlocks
from coupling.functional import CoupledFunctional
from coupling.options import DEFAULTS

__all__ = ["SignoriniProblem"]


class SignoriniProblem:
    """The discrete problem (2.3): minimise J_h over u free, phi >= 0 on Gamma_s.

    Parameters
    ----------
    domain
        ``fem_py.geometry.Domain``: mesh, tags, coarse partition, Signorini arcs.
    material
        ``fem_py.materials.Material`` (rho).
    f, u0, t0
        Data as expression strings (fem_py parser; u0 and t0 may use nx, ny), UFL
        expressions, or (u0) a callable of boundary coordinates.
    a
        The constant of (1.3).
    flux_space
        The space of the exterior normal derivative: ``"p1"`` or ``"p0"`` (bem_cpp).
    jacobian
        D^2 G from ``"ufl"`` (derived) or ``"handwritten"`` forms (fem_py.forms).

    Attributes
    ----------
    V, forms, boundary
        The P1 space, the interior forms and the boundary map T, E.
    S
        S_h, dense: an array in serial, :class:`coupling.distributed.RowBlocks` under MPI.
    u0
        u0 at the boundary nodes (boundary order).
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
        f: Any = "0",
        u0: Any = "0",
        t0: Any = "0",
        a: float = 0.0,
        flux_space: str = DEFAULTS["solver"]["flux_space"],
        jacobian: str = DEFAULTS["solver"]["jacobian"],
    ):
        from fem_py.boundary import BoundaryMap
        from fem_py.forms import InteriorForms, p1_space

        self.domain, self.material, self.a = domain, material, float(a)
        self.flux_space, self.jacobian = flux_space, jacobian
        self.comm = domain.mesh.comm
        timings: dict[str, float] = {}
        tic = time.perf_counter()
        self.V = p1_space(domain.mesh)
        self.forms = InteriorForms(self.V, material, f, jacobian=jacobian)
        self.boundary = BoundaryMap(self.V, domain)
        timings["forms"] = time.perf_counter() - tic

        tic = time.perf_counter()
        # S_h: dense, replicated in serial; under MPI computed on rank 0 and kept by rows
        nodes = self.boundary.nodes

        def steklov() -> np.ndarray:
            return bem_cpp.steklov_poincare(nodes, flux=flux_space)

        self.S = steklov() if self.comm.size == 1 else RowBlocks.from_root(self.comm, steklov)
        timings["steklov_poincare"] = time.perf_counter() - tic

        tic = time.perf_counter()
        self.u0 = self.boundary.interpolate_boundary(u0)
        m_t = self.forms.boundary_load(t0, self.boundary)
        s_0 = self.S @ (self.a + self.u0)
        self.functional = CoupledFunctional(
            self.forms, self.boundary, self.S, self.forms.assemble_load(), m_t + s_0
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
    def n_signorini(self) -> int:
        """n_s, the number of phi unknowns."""
        return int(self.boundary.signorini.size)

    def exterior(self, solution: Any, points: np.ndarray) -> np.ndarray:
        """u_e at exterior points (m, 2) by the representation formula (METHOD.md section 2)."""
        return bem_cpp.exterior_potential(
            self.boundary.nodes,
            solution.ue,
            solution.flux,
            np.asarray(points, dtype=float),
            a=self.a,
            flux=self.flux_space,
        )
