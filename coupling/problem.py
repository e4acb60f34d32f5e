"""The coupled Signorini problem: from a domain, a material and data to a solution.

The pipeline, in the order of METHOD.md: interior forms (fem_py) -> boundary map ->
S_h (bem_cpp) -> J_h (:mod:`coupling.functional`) -> preconditioner B
(:mod:`coupling.preconditioner`) -> solver (:mod:`coupling.newton`, :mod:`coupling.pgpm`) -> result.

Example
-------
>>> from mpi4py import MPI
>>> from fem_py.geometry import build_domain
>>> from fem_py.materials import make_material
>>> domain = build_domain(MPI.COMM_WORLD, "square", h=1/32, subdomain_size=1/8,
...                       signorini=["bottom"])
>>> problem = SignoriniProblem(domain, make_material("carstensen"), f="1", t0="-1")
>>> result = problem.solve()
"""
from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from mpi4py import MPI

import bem_cpp
from coupling.config import DEFAULTS, as_dataclass_kwargs
from coupling.functional import CoupledFunctional
from coupling.newton import semismooth_newton
from coupling.pgpm import IterationRecord, RunResult, estimate_extremes, projection_gradient
from coupling.distributed import (RootPreconditioner, RowBlocks, computed_on_root, gather_matrix,
                                  gather_rows)
from coupling.distributed_substructuring import (DistributedSubstructuringPreconditioner,
                                                 subdomain_ranks)
from coupling.exact_preconditioner import ExactPreconditioner
from coupling.preconditioner import (IdentityPreconditioner, SignoriniArc,
                                     SubstructuringPreconditioner)
from coupling.projection import SignoriniProjection
from fem_py.geometry import GAMMA_T_TAG

__all__ = ["SolverOptions", "SignoriniProblem", "Solution", "problem_from_config",
           "domain_from_config", "material_from_config"]


def _solver_default(key: str) -> Any:
    return field(default=DEFAULTS["solver"][key])


@dataclass(frozen=True)
class SolverOptions:
    """The ``[solver]`` section (defaults in :data:`coupling.config.DEFAULTS`)."""

    method: str = _solver_default("method")
    preconditioner: str = _solver_default("preconditioner")
    tol: float = _solver_default("tol")
    max_iterations: int = _solver_default("max_iterations")
    step: Any = _solver_default("step")
    projection: str = _solver_default("projection")
    projection_tol: float = _solver_default("projection_tol")
    projection_max_iterations: int = _solver_default("projection_max_iterations")
    edge_form: str = _solver_default("edge_form")
    flux_space: str = _solver_default("flux_space")
    jacobian: str = _solver_default("jacobian")
    signorini_weight: float = _solver_default("signorini_weight")


@dataclass
class Solution:
    """What :meth:`SignoriniProblem.solve` returns.

    Attributes
    ----------
    u
        u_h (dolfinx Function on the P1 space).
    phi
        phi_h at the Signorini nodes (n_s,), the gap u_e + u0 - u there.
    contact
        (n_s,) bool, phi_h == 0: the discrete contact set.
    boundary_u, ue, flux
        u_h on Gamma, u_e = u + phi - u0 on Gamma (boundary order), and the
        coefficients of the exterior normal derivative psi_h (flux space).
    """

    u: Any
    phi: np.ndarray
    contact: np.ndarray
    boundary_u: np.ndarray
    ue: np.ndarray
    flux: np.ndarray
    converged: bool
    reason: str
    iterations: int
    energy: float
    tau: float
    C0: float
    history: list[IterationRecord]
    energy_increases: int
    timings: dict[str, float]


class SignoriniProblem:
    """The discrete problem (2.3): minimise J_h over u free, phi >= 0 on Gamma_s.

    Parameters
    ----------
    domain
        ``fem_py.geometry.Domain``: mesh, tags, coarse partition, Signorini arcs.
    material
        ``fem_py.materials.Material`` (rho).
    f, u0, t0
        Data as expression strings (fem_py parser; u0 and t0 may use nx, ny).
    a
        The constant of (1.3).
    options
        Solver options.
    """

    def __init__(self, domain, material, *, f: str = "0", u0: str = "0", t0: str = "0",
                 a: float = 0.0, options: SolverOptions = SolverOptions()):
        from fem_py.boundary import BoundaryMap
        from fem_py.forms import InteriorForms, p1_space

        self.domain, self.material, self.options, self.a = domain, material, options, float(a)
        self.comm = domain.mesh.comm
        timings: dict[str, float] = {}
        tic = time.perf_counter()
        self.V = p1_space(domain.mesh)
        self.forms = InteriorForms(self.V, material, f, jacobian=options.jacobian)
        self.boundary = BoundaryMap(self.V, domain)
        timings["forms"] = time.perf_counter() - tic

        tic = time.perf_counter()
        # S_h: dense, replicated in serial; under MPI computed on rank 0 and kept by rows
        steklov = lambda: bem_cpp.steklov_poincare(self.boundary.nodes, flux=options.flux_space)  # noqa: E731
        self.S = steklov() if self.comm.size == 1 else RowBlocks.from_root(self.comm, steklov)
        timings["steklov_poincare"] = time.perf_counter() - tic

        tic = time.perf_counter()
        self.u0 = self.boundary.interpolate_boundary(u0)
        m_t = self.forms.boundary_load(t0, self.boundary)
        s_0 = self.S @ (self.a + self.u0)
        self.functional = CoupledFunctional(self.forms, self.boundary, self.S,
                                            self.forms.assemble_load(), m_t + s_0)
        timings["loads"] = time.perf_counter() - tic

        tic = time.perf_counter()
        self.preconditioner = self._make_preconditioner()
        self.projection = SignoriniProjection(
            self.preconditioner.signorini_metric, options.projection,
            rho_in=options.projection_tol, max_iterations=options.projection_max_iterations,
            lambda_max=lambda: self.preconditioner.lambda_max_signorini)
        timings["preconditioner"] = time.perf_counter() - tic
        self.timings = timings

    def _signorini_arcs(self) -> list[SignoriniArc]:
        """The Signorini arcs in the form of the preconditioner: nodes along each arc
        (counter-clockwise, ends included), coarse-vertex flags and phi indices."""
        b = self.boundary
        n = b.n_gamma
        phi_index = np.full(n, -1)
        phi_index[b.signorini] = np.arange(b.signorini.size)
        is_vertex = np.isin(b.dofs, self.domain.coarse.vertex_dofs)
        arcs = []
        for tag in np.unique(b.panel_tags[b.panel_tags != GAMMA_T_TAG]):
            panels = b.panel_tags == tag
            if panels.all():
                arcs.append(SignoriniArc(b.nodes, is_vertex, phi_index, closed=True))
                continue
            # the arc starts at the panel whose predecessor is not on it
            first = np.flatnonzero(panels & ~np.roll(panels, 1))
            if first.size != 1:
                raise ValueError(f"Signorini arc with facet tag {tag} is not one connected "
                                 "arc of the boundary; give each arc separately")
            length = int(panels.sum())
            nodes = (first[0] + np.arange(length + 1)) % n
            arcs.append(SignoriniArc(b.nodes[nodes], is_vertex[nodes],
                                     phi_index[nodes[1:-1]]))
        return arcs

    def _make_preconditioner(self):
        """B of the ``preconditioner`` option (METHOD.md sections 5-6), factored once.

        Under MPI the substructuring preconditioner is distributed by subdomains
        (:mod:`coupling.distributed_substructuring`) when every subdomain lies on one
        rank (``build_domain`` partitions so whenever there are at least as many
        subdomains as ranks); otherwise, and for the exact preconditioner, B is built
        from the gathered stiffness matrix and runs on rank 0 (:mod:`coupling.distributed`).
        """
        kind, comm = self.options.preconditioner, self.comm
        n_owned = self.V.dofmap.index_map.size_local
        if kind == "identity":
            return IdentityPreconditioner(n_owned, self.n_signorini)
        stiffness = self.forms.assemble_stiffness()
        arcs = self._signorini_arcs()
        if kind == "substructuring" and comm.size > 1:
            domain = self.domain
            ranks = subdomain_ranks(comm, domain.cell_tags,
                                    domain.mesh.topology.index_map(2).size_local,
                                    domain.coarse.n_subdomains)
            if ranks is not None:  # whole subdomains per rank: no gathering
                try:
                    return DistributedSubstructuringPreconditioner(
                        comm, stiffness, self.V.dofmap.index_map, domain.coarse, ranks,
                        domain.subdomain_size, arcs, edge_form=self.options.edge_form,
                        signorini_weight=self.options.signorini_weight)
                finally:
                    stiffness.destroy()
        csr = gather_matrix(stiffness)
        stiffness.destroy()
        x = gather_rows(comm, self.V.tabulate_dof_coordinates()[:n_owned, :2])

        S = self.S if self.comm.size == 1 or kind != "exact" else self.S.full()

        def build():
            if kind == "exact":
                return ExactPreconditioner(csr, self.boundary.dofs, self.boundary.signorini, S)
            return SubstructuringPreconditioner(
                csr, self.domain.coarse, x, self.domain.subdomain_size, arcs,
                edge_form=self.options.edge_form,
                signorini_weight=self.options.signorini_weight)

        return build() if comm.size == 1 else RootPreconditioner(comm, n_owned, build)

    @property
    def n_signorini(self) -> int:
        return int(self.boundary.signorini.size)

    def solve(self, *, progress: bool = False, every: int = 25) -> Solution:
        """Solve from xi_0 = (0, 0) with ``options.method``: ``ssn`` (default,
        :func:`coupling.newton.semismooth_newton`), ``pgpm`` or ``apgpm``
        (:func:`coupling.pgpm.projection_gradient`)."""
        from dolfinx import fem

        opts, comm = self.options, self.comm
        u = fem.Function(self.V, name="u")
        phi0 = np.zeros(self.n_signorini)
        timings = dict(self.timings)
        tic = time.perf_counter()
        lambda_min = None  # the momentum of apgpm, from the same Lanczos run as C0
        if opts.step == "auto":
            jacobian = self.forms.create_matrix()
            self.forms.assemble_jacobian(u, jacobian)
            lambda_min, C0 = estimate_extremes(self.functional, self.preconditioner, jacobian,
                                               phi0.size)
            jacobian.destroy()
            tau = 1.0 / C0
        else:
            tau = float(opts.step)
            C0 = 1.0 / tau
        timings["step_estimate"] = time.perf_counter() - tic

        def monitor(record: IterationRecord) -> None:
            if progress and comm.rank == 0 and (record.iteration % every == 0
                                                or record.iteration == 1):
                print(f"  it {record.iteration:5d}  J_h = {record.energy:.12e}  "
                      f"step = {record.step_norm:.3e}  contact = {record.contact}  "
                      f"inner = {record.inner}", file=sys.stdout, flush=True)

        if opts.method == "ssn":
            run: RunResult = semismooth_newton(
                self.functional, self.preconditioner, self.projection, self.forms, u, phi0,
                tau=tau, tol=opts.tol, max_iterations=opts.max_iterations, monitor=monitor)
        else:
            run = projection_gradient(
                self.functional, self.preconditioner, self.projection, u, phi0, tau=tau,
                tol=opts.tol, max_iterations=opts.max_iterations,
                accelerated=opts.method == "apgpm",
                strong_convexity=lambda_min if opts.method == "apgpm" else None, monitor=monitor)
        timings["solve"] = run.solve_time
        if run.energy_increases and progress and comm.rank == 0:
            print(f"  note: J_h increased {run.energy_increases} times; tau was halved "
                  f"to {run.tau:.3e}", flush=True)

        boundary_u = self.boundary.gather(u.vector)
        gap = np.zeros_like(boundary_u)
        gap[self.boundary.signorini] = run.phi
        ue = boundary_u + gap - self.u0
        tic = time.perf_counter()
        flux = computed_on_root(comm, lambda: bem_cpp.exterior_flux(
            self.boundary.nodes, ue, a=self.a, flux=opts.flux_space))
        timings["exterior_flux"] = time.perf_counter() - tic
        return Solution(u=u, phi=run.phi, contact=run.phi <= 0.0, boundary_u=boundary_u,
                        ue=ue, flux=flux, converged=run.converged, reason=run.reason,
                        iterations=run.iterations, energy=run.energy, tau=run.tau, C0=C0,
                        history=run.history, energy_increases=run.energy_increases,
                        timings=timings)

    def exterior(self, solution: Solution, points: np.ndarray) -> np.ndarray:
        """u_e at exterior points (m, 2) by the representation formula (METHOD.md section 2)."""
        return bem_cpp.exterior_potential(self.boundary.nodes, solution.ue, solution.flux,
                                          np.asarray(points, dtype=float), a=self.a,
                                          flux=self.options.flux_space)


def domain_from_config(comm: MPI.Comm, config: dict):
    """Build the ``fem_py.geometry.Domain`` of a validated configuration."""
    from fem_py.geometry import build_domain

    g = config["geometry"]
    return build_domain(comm, g["shape"], h=g["h"], subdomain_size=g["subdomain_size"],
                        center=tuple(g["center"]), width=g["width"],
                        vertices=g["vertices"] or None, signorini=g["signorini"],
                        structured=g["structured"], allow_large=g["allow_large"])


def material_from_config(config: dict):
    """The ``fem_py.materials.Material`` of a validated configuration."""
    from fem_py.materials import make_material

    m = config["material"]
    return make_material(m["rho"], p=m["p"], eps=m["eps"])


def problem_from_config(comm: MPI.Comm, config: dict) -> SignoriniProblem:
    """A :class:`SignoriniProblem` from a validated configuration (coupling.config)."""
    data = config["data"]
    options = SolverOptions(**as_dataclass_kwargs(SolverOptions, config["solver"]))
    material = material_from_config(config)
    tic = time.perf_counter()
    domain = domain_from_config(comm, config)
    mesh_time = time.perf_counter() - tic
    problem = SignoriniProblem(domain, material, f=data["f"], u0=data["u0"], t0=data["t0"],
                               a=data["a"], options=options)
    problem.timings = {"mesh": mesh_time, **problem.timings}
    return problem
