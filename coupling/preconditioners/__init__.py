"""The block preconditioners B = B_Omega + B_s of the iterations (docs/method.md sections 5-6).

- :mod:`~coupling.preconditioners.base`: the interface, and B = identity;
- :mod:`~coupling.preconditioners.edge_forms`: the discrete H^{1/2}_00 edge forms (5.1);
- :mod:`~coupling.preconditioners.kernels`: factors, the two-level form, C and Pi;
- :mod:`~coupling.preconditioners.signorini`: the Signorini arcs and omega B_s;
- :mod:`~coupling.preconditioners.substructuring`: the serial substructuring B;
- :mod:`~coupling.preconditioners.distributed`: the same B, distributed by subdomains;
- :mod:`~coupling.preconditioners.root`: any serial B set up on rank 0 under MPI;
- :mod:`~coupling.preconditioners.exact`: the diagonal blocks of (4.2), the reference;
- :mod:`~coupling.preconditioners.multigrid`: multigrid and E^T W_h E (3D, section 11);
- :mod:`~coupling.preconditioners.lattice_multigrid`: its geometric multigrid on the box.

:func:`build_preconditioner` chooses and builds one for an assembled problem.
"""
from __future__ import annotations

from typing import Any

from petsc4py import PETSc

from coupling.distributed import dense_matrix, gather_owned_rows
from coupling.options import AMG_MAX_ITERATIONS, AMG_RTOL, AUTO_PRECONDITIONER, SolverOptions
from coupling.preconditioners.base import IdentityPreconditioner, Preconditioner
from coupling.preconditioners.distributed import (
    DistributedSubstructuringPreconditioner,
    subdomain_ranks,
)
from coupling.preconditioners.exact import ExactPreconditioner
from coupling.preconditioners.multigrid import (
    MultigridPreconditioner,
    constant_mode_weight,
    signorini_hypersingular,
)
from coupling.preconditioners.root import RootPreconditioner
from coupling.preconditioners.signorini import SignoriniArc, signorini_arcs
from coupling.preconditioners.substructuring import SubstructuringPreconditioner
from fem_py.forms.p1_matrix import P1Matrix
from fem_py.tags import GAMMA_T_TAG

__all__ = [
    "Preconditioner",
    "IdentityPreconditioner",
    "SubstructuringPreconditioner",
    "DistributedSubstructuringPreconditioner",
    "RootPreconditioner",
    "ExactPreconditioner",
    "MultigridPreconditioner",
    "SignoriniArc",
    "build_preconditioner",
    "create_matrix",
    "preconditioner_kind",
    "coarse_space",
    "problem_arcs",
]


def problem_arcs(problem: Any) -> list[SignoriniArc]:
    """The Signorini arcs of an assembled :class:`coupling.problem.SignoriniProblem`."""
    return signorini_arcs(problem.boundary, problem.domain.coarse.vertex_dofs, GAMMA_T_TAG)


def coarse_space(domain: Any, choice: str) -> str:
    """The coarse matrix C of ``[solver] coarse_space`` for ``domain``: ``"auto"`` is the
    paper's graph Laplacian on a generated coarse grid (shape-regular by construction)
    and the Galerkin C on subdomains made of a mesh's cells (the automatic partition or
    physical groups: ``domain.partition == "cells"``), whose jagged interfaces and short
    coarse edges the graph Laplacian does not see (docs/design/coarse_space.md)."""
    if choice != "auto":
        return choice
    return "galerkin" if domain.partition == "cells" else "graph"


def preconditioner_kind(choice: str, dim: int, components: int = 1) -> str:
    """The preconditioner of ``[solver] preconditioner = choice`` for a ``dim``-dimensional
    domain: ``"auto"`` is :data:`coupling.options.AUTO_PRECONDITIONER` (substructuring in
    2D, amg in 3D; amg for elasticity, ``components`` > 1, in both), any other choice
    itself."""
    if choice != "auto":
        return choice
    return "amg" if components > 1 else AUTO_PRECONDITIONER[dim]


def create_matrix(problem: Any, options: SolverOptions) -> P1Matrix | PETSc.Mat:
    """The P1 matrix :func:`build_preconditioner` assembles in, which the solvers' Jacobians
    then reuse (the caller destroys it): a PETSc Mat for the amg preconditioner, which
    copies its nonzero structure, else a :class:`fem_py.forms.p1_matrix.P1Matrix`."""
    kind = preconditioner_kind(options.preconditioner, problem.domain.dim, problem.components)
    return problem.forms.create_matrix() if kind == "amg" else problem.forms.create_p1_matrix()


def build_preconditioner(
    problem: Any, options: SolverOptions, *, matrix: P1Matrix | PETSc.Mat | None = None
) -> Preconditioner:
    """B of ``options.preconditioner`` for ``problem`` (docs/method.md sections 5-6), factored
    once (collective). The caller owns it: call ``destroy()`` on every rank when done.

    Under MPI the substructuring preconditioner is distributed by subdomains
    (:class:`DistributedSubstructuringPreconditioner`) when every subdomain lies on one
    rank (``fem_py.mesh.build_domain`` partitions so whenever there are at least as
    many subdomains as ranks); otherwise, and for the exact preconditioner, B is built
    from the gathered stiffness matrix and runs on rank 0 (:class:`RootPreconditioner`).

    ``matrix`` (optional, the caller's, from :func:`create_matrix`): the amg
    preconditioner, which keeps a PETSc Mat, copies the nonzero structure of a PETSc Mat;
    the others assemble the stiffness matrix in a
    :class:`fem_py.forms.p1_matrix.P1Matrix`, this one or a new one. A caller that needs
    a P1 matrix afterwards (the solvers' Jacobian) saves creating one. B keeps no
    reference to it.
    """
    elastic = problem.components > 1
    kind = preconditioner_kind(options.preconditioner, problem.domain.dim, problem.components)
    comm, V = problem.comm, problem.V
    n_owned = V.dofmap.index_map.size_local * problem.components
    if kind == "identity":
        return IdentityPreconditioner(n_owned, problem.n_signorini)
    if kind == "amg":  # distributed as it is: no gathering
        return MultigridPreconditioner(
            V,
            constant_mode_weight(V, problem.S),
            signorini_hypersingular(
                comm, problem.boundary, problem.S, gap=problem.gap, kernel=problem.kernel
            ),
            lattice=problem.domain.lattice,
            rtol=AMG_RTOL,
            max_iterations=AMG_MAX_ITERATIONS,
            pattern=matrix if isinstance(matrix, PETSc.Mat) else None,
            stiffness=problem.material.stiffness_integrand if elastic else None,
        )
    if elastic:
        raise ValueError(
            f"preconditioner: {kind} is a preconditioner of the scalar equation; for elasticity"
            ' set [solver] preconditioner = "amg" (the default) or "identity"'
        )
    domain = problem.domain
    if kind == "substructuring" and domain.dim == 3:
        raise ValueError(
            "preconditioner: substructuring is the planar preconditioner (docs/method.md section "
            '6); for a 3D body set [solver] preconditioner = "amg" (or "exact", small problems)'
        )
    substructuring = kind == "substructuring"
    coarse = coarse_space(domain, options.coarse_space) if substructuring else None
    p1_matrix = matrix if isinstance(matrix, P1Matrix) else None
    arcs = problem_arcs(problem) if substructuring else None
    if kind == "substructuring" and comm.size > 1:
        ranks = subdomain_ranks(
            comm,
            domain.cell_tags,
            domain.mesh.topology.index_map(2).size_local,
            domain.coarse.n_subdomains,
        )
        if ranks is not None:  # whole subdomains per rank: no gathering
            return DistributedSubstructuringPreconditioner(
                comm,
                problem.forms.stiffness_local(p1_matrix),
                V.dofmap.index_map,
                domain.coarse,
                ranks,
                domain.subdomain_size,
                arcs,
                edge_form=options.edge_form,
                signorini_weight=options.signorini_weight,
                coarse_space=coarse,
            )
    csr = gather_owned_rows(comm, problem.forms.stiffness_rows(p1_matrix))
    S = dense_matrix(problem.S, "the exact preconditioner") if kind == "exact" else None

    def build() -> Preconditioner:
        if kind == "exact":
            return ExactPreconditioner(csr, problem.boundary.dofs, problem.boundary.signorini, S)
        return SubstructuringPreconditioner(
            csr,
            domain.coarse,
            None,  # the coordinates along the coarse edges: domain.coarse.edge_coords
            domain.subdomain_size,
            arcs,
            edge_form=options.edge_form,
            signorini_weight=options.signorini_weight,
            coarse_space=coarse,
            check_symmetry=False,  # assembled above from the symmetric form
        )

    return build() if comm.size == 1 else RootPreconditioner(comm, n_owned, build)
