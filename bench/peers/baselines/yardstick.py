"""The yardstick of the benchmark: one linear P1 Poisson solve with CG + GAMG on the
same mesh, the cost unit of a linear solve."""
from __future__ import annotations

import time
from typing import Any

import numpy as np
from petsc4py import PETSc

from bench.peers.baselines.budget import PeerResult, require_serial

__all__ = ["poisson_yardstick"]


def poisson_yardstick(V: Any, boundary_dofs: np.ndarray, *, rtol: float = 1e-8) -> PeerResult:
    """One linear solve on the mesh of ``V``: -Laplace w = 1 in Omega, w = 0 on Gamma,
    P1 stiffness matrix, CG + GAMG to ||r|| <= rtol ||b|| (preconditioned norm, the
    PETSc default for CG).

    ``setup`` is the assembly of matrix and load plus the GAMG set-up (the forms are
    compiled before the clock starts); ``solve`` the CG iterations. The result's ``u``
    is w (N,) and ``phi`` is empty.
    """
    import ufl
    from dolfinx import fem

    from fem_py.forms import compile_form

    comm = V.mesh.comm
    require_serial(comm)
    w, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    # form compilation (JIT, cached on disk) is not part of the solve's cost
    a = compile_form(
        ufl.inner(ufl.grad(w), ufl.grad(v)) * ufl.dx(metadata={"quadrature_degree": 0})
    )
    load = compile_form(
        ufl.inner(fem.Constant(V.mesh, PETSc.ScalarType(1.0)), v)
        * ufl.dx(metadata={"quadrature_degree": 1})
    )
    tic = time.perf_counter()
    bc = fem.dirichletbc(PETSc.ScalarType(0.0), np.asarray(boundary_dofs, dtype=np.int32), V)
    A = fem.petsc.assemble_matrix(a, bcs=[bc])
    A.assemble()
    b = fem.petsc.assemble_vector(load)
    fem.petsc.apply_lifting(b, [a], bcs=[[bc]])
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    fem.petsc.set_bc(b, [bc])
    ksp = PETSc.KSP().create(PETSc.COMM_SELF)
    ksp.setOperators(A)
    ksp.setType("cg")
    ksp.getPC().setType("gamg")
    ksp.setTolerances(rtol=rtol, atol=0.0, max_it=1000)
    A.setOption(PETSc.Mat.Option.SPD, True)
    ksp.setUp()
    setup = time.perf_counter() - tic
    x = b.duplicate()
    tic = time.perf_counter()
    ksp.solve(b, x)
    solve = time.perf_counter() - tic
    code = ksp.getConvergedReason()
    result = PeerResult(
        u=x.array_r.copy(),
        phi=np.zeros(0),
        converged=code > 0,
        reason=f"KSP reason {code}",
        iterations=ksp.getIterationNumber(),
        linear_iterations=ksp.getIterationNumber(),
        setup=setup,
        solve=solve,
    )
    for obj in (ksp, A, b, x):
        obj.destroy()
    return result
