"""SNES ``vinewtonrsls`` on the optimality system of (2.3): F(x) = grad J_h(x) with the
bounds phi >= 0 (u free) and the Jacobian H(x) (:class:`CoupledHessian`)."""
from __future__ import annotations

import time
from typing import Any

import numpy as np
from petsc4py import PETSc

from bench.peers.baselines.budget import Budget, PeerResult
from bench.peers.baselines.hessian import CoupledHessian, Evaluator
from bench.peers.baselines.linear import (
    KRYLOV_RTOL,
    LINEAR_SOLVERS,
    InactiveSetShell,
    clear_options,
    count_krylov,
    linear_options,
    new_prefix,
    python_pc,
    set_options,
)
from coupling.options import SolverOptions
from coupling.preconditioners import build_preconditioner
from coupling.problem import SignoriniProblem

__all__ = ["solve_snes_vi", "snes_reason", "vi_norm"]


def solve_snes_vi(
    problem: SignoriniProblem,
    *,
    linear_solver: str = "mumps",
    rtol: float = 1e-12,
    max_iterations: int = 100,
    budget: float | None = None,
    krylov_rtol: float = KRYLOV_RTOL,
    line_search: str = "bt",
    objective: bool = False,
    initial: tuple[np.ndarray, np.ndarray] | None = None,
) -> PeerResult:
    """Solve the optimality system with SNES ``vinewtonrsls`` from x_0 = 0 (or from
    ``initial``).

    F(x) = grad J_h(x) with bounds phi >= 0 (u free), Jacobian H(x)
    (:class:`CoupledHessian`), line search ``line_search`` on ||F|| (or on J_h with
    ``objective=True``, which stalls near the solution with inexact Newton steps:
    docs/design/baselines.md). Converged when ||F on the inactive set|| <= rtol ||F(x_0)||
    (PETSc's VI norm).

    Parameters
    ----------
    problem
        A serial :class:`coupling.problem.SignoriniProblem`.
    linear_solver
        A key of :data:`LINEAR_SOLVERS`; ``substructuring`` builds the project's B
        (:func:`coupling.preconditioners.build_preconditioner` with the default
        options, counted in the set-up time; destroyed at the end).
    rtol
        SNES relative tolerance (the Newton steps converge quadratically, so the
        last step takes the error far below it).
    max_iterations
        Newton step cap.
    budget
        Wall-time budget in seconds (checked at every function evaluation).
    krylov_rtol
        Relative tolerance of the CG solves.
    initial
        (u, phi >= 0) to start from (grid sequencing:
        :func:`bench.peers.baselines.sequenced.solve_snes_vi_sequenced`). The stopping test
        stays that of the cold start, ||F(x)|| <= rtol ||F(0)|| in PETSc's VI norm
        (:func:`vi_norm`), as an absolute tolerance (snes_rtol = 0), so that both runs
        stop at the same residual.
    """
    if linear_solver not in LINEAR_SOLVERS:
        raise ValueError(
            f"linear_solver must be one of {tuple(LINEAR_SOLVERS)}, " f"got {linear_solver!r}"
        )
    clock = Budget(budget)
    tic = time.perf_counter()
    b = None
    if linear_solver == "substructuring":
        options = SolverOptions(
            preconditioner="substructuring",
            flux_space=problem.flux_space,
            jacobian=problem.jacobian,
        )
        b = build_preconditioner(problem, options)
    ev = Evaluator(problem, clock)
    hessian = CoupledHessian(problem)
    f_vec, x = ev.create_vec(), ev.create_vec()
    spent = {"function": 0.0, "jacobian": 0.0}
    lower, upper = ev.bounds()
    atol = 0.0
    if initial is not None:
        ev.gradient(x, f_vec)  # x = 0 here: the cold start's residual
        atol = rtol * vi_norm(x, f_vec, lower)
        x.array[: ev.n_u] = initial[0]
        x.array[ev.n_u :] = initial[1]
    prefix = new_prefix("snes")
    petsc_options = {
        "snes_type": "vinewtonrsls",
        "snes_linesearch_type": line_search,
        "snes_rtol": rtol if initial is None else 0.0,
        "snes_atol": atol,
        "snes_stol": 0.0,
        "snes_max_it": max_iterations,
        "snes_max_funcs": 100 * max_iterations,
        **linear_options(prefix, "", linear_solver, krylov_rtol),
    }
    set_options(prefix, petsc_options)
    snes = PETSc.SNES().create(PETSc.COMM_SELF)
    snes.setOptionsPrefix(prefix)

    def function(_snes: PETSc.SNES, xv: PETSc.Vec, fv: PETSc.Vec) -> None:
        start = time.perf_counter()
        ev.gradient(xv, fv)
        spent["function"] += time.perf_counter() - start

    def jacobian(_snes: PETSc.SNES, xv: PETSc.Vec, _a: Any, _p: Any) -> None:
        # _a is hessian.matrix
        start = time.perf_counter()
        clock.check()
        ev.state(xv)
        hessian.assemble(ev.u)
        spent["jacobian"] += time.perf_counter() - start

    snes.setFunction(function, f_vec)
    snes.setJacobian(jacobian, hessian.matrix)
    if objective:
        snes.setObjective(lambda _snes, xv: ev.objective(xv))
    snes.setVariableBounds(lower, upper)
    snes.setFromOptions()
    ksp = snes.getKSP()
    shell = None
    if b is not None:
        shell = InactiveSetShell(b, ev.n_u, lambda: snes.getVIInactiveSet().getIndices())
    python_pc(ksp, prefix, linear_solver, shell)
    krylov = count_krylov(ksp)
    setup = time.perf_counter() - tic

    result = ev.run(
        snes,
        lambda: snes.solve(None, x),
        snes_reason,
        x,
        linear_iterations=krylov[0],
        setup=setup,
        details={
            "hessian_nnz": hessian.nnz,
            "time_function": spent["function"],
            "time_jacobian": spent["jacobian"],
            "pc_applications": shell.applications if shell else 0,
            "time_pc_setup": shell.time_setup if shell else 0.0,
            "time_pc_apply": shell.time_apply if shell else 0.0,
        },
    )
    for obj in (snes, f_vec, x, lower, upper):
        obj.destroy()
    hessian.destroy()
    ev.destroy()
    if b is not None:
        b.destroy()
    clear_options(prefix, petsc_options)
    return result


def vi_norm(x: PETSc.Vec, f: PETSc.Vec, lower: PETSc.Vec) -> float:
    """||F|| over the inactive set at x with the lower bounds ``lower`` (no upper ones):
    the norm SNES ``vinewtonrsls`` tests, which leaves out every index at its bound
    whose F does not point into the feasible set (x_i <= l_i + 1e-8 and F_i >= 0; PETSc's
    SNESVIComputeInactiveSetFnorm)."""
    values, bound = f.array_r, lower.array_r
    active = (x.array_r <= bound + 1e-8) & (values >= 0)
    return float(np.linalg.norm(values[~active]))


def snes_reason(code: int) -> str:
    """The name of a SNES converged reason, with its code."""
    names = {v: k for k, v in vars(PETSc.SNES.ConvergedReason).items() if isinstance(v, int)}
    return f"{names.get(code, 'UNKNOWN')} ({code})"
