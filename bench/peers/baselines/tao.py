"""TAO bound-constrained minimisation of J_h over phi >= 0 (u free): first-order
(``blmvm``, ``bqnls``: J_h and its gradient) and Newton-Krylov (``bnls``, ``bntr``: with
the Hessian H, :class:`CoupledHessian`)."""
from __future__ import annotations

import time
from typing import Any, Callable

import numpy as np
from petsc4py import PETSc

from bench.peers.baselines.budget import Budget, PeerResult
from bench.peers.baselines.hessian import CoupledHessian, Evaluator
from bench.peers.baselines import linear
from bench.peers.baselines.linear import KRYLOV_RTOL, LINEAR_SOLVERS
from coupling.problem import SignoriniProblem

__all__ = ["TAO_TYPES", "solve_tao", "tao_reason"]

#: TAO bound-constrained types: first-order (objective and gradient) and Newton-Krylov.
TAO_TYPES = ("blmvm", "bqnls", "bnls", "bntr")
_NEWTON_TAO = ("bnls", "bntr")


def tao_reason(code: int) -> str:
    """The name of a TAO converged reason, with its code."""
    names = {v: k for k, v in vars(PETSc.TAO.Reason).items() if isinstance(v, int)}
    return f"{names.get(code, 'UNKNOWN')} ({code})"


def solve_tao(
    problem: SignoriniProblem,
    kind: str,
    *,
    gttol: float = 1e-10,
    linear_solver: str = "mumps",
    max_iterations: int = 100000,
    budget: float | None = None,
    krylov_rtol: float = KRYLOV_RTOL,
    stop: Callable[[np.ndarray, np.ndarray], bool] | None = None,
) -> PeerResult:
    """Minimise J_h over phi >= 0 with the TAO bound-constrained method ``kind``, from x_0 = 0.

    ``blmvm`` and ``bqnls`` use J_h and its gradient only; ``bnls`` and ``bntr`` also
    the Hessian H (:class:`CoupledHessian`), with ``linear_solver`` (a key of
    :data:`LINEAR_SOLVERS` other than ``substructuring``) on the reduced Newton system.
    Converged when the projected gradient satisfies ||g(x)|| <= gttol ||g(x_0)||, or,
    if ``stop`` is given, as soon as ``stop(u, phi)`` is true at an iterate (checked
    after every iteration by a TAO monitor; the reason is then ``CONVERGED_USER``).
    ``budget`` is checked at every objective evaluation.
    """
    if kind not in TAO_TYPES:
        raise ValueError(f"kind must be one of {TAO_TYPES}, got {kind!r}")
    if kind in _NEWTON_TAO and linear_solver not in LINEAR_SOLVERS:
        raise ValueError(
            f"linear_solver must be one of {tuple(LINEAR_SOLVERS)}, " f"got {linear_solver!r}"
        )
    if kind in _NEWTON_TAO and linear_solver == "substructuring":
        raise ValueError(
            "TAO does not expose its inactive set; use a direct or AMG "
            "linear_solver for bnls/bntr"
        )
    clock = Budget(budget)
    tic = time.perf_counter()
    ev = Evaluator(problem, clock)
    x, g = ev.create_vec(), ev.create_vec()
    lower, upper = ev.bounds()
    prefix = linear.new_prefix("tao")
    options: dict[str, Any] = {"tao_type": kind, "tao_max_funcs": 10 * max_iterations}
    if kind in _NEWTON_TAO:
        # BNTR needs a trust-region CG; STCG is also BNLS's default. With an exact
        # factor as preconditioner one STCG step is the Newton step.
        options.update(
            linear.linear_options(prefix, "tao_bnk_", linear_solver, krylov_rtol, ksp_type="stcg")
        )
    linear.set_options(prefix, options)
    tao = PETSc.TAO().create(PETSc.COMM_SELF)
    tao.setOptionsPrefix(prefix)
    tao.setObjectiveGradient(lambda _tao, xv, gv: ev.objective_gradient(xv, gv), g)
    tao.setVariableBounds(lower, upper)
    hessian = None
    if kind in _NEWTON_TAO:
        hessian = CoupledHessian(problem)

        def hess(_tao: PETSc.TAO, xv: PETSc.Vec, _a: Any, _p: Any) -> None:
            # _a is hessian.matrix
            clock.check()
            ev.state(xv)
            hessian.assemble(ev.u)

        tao.setHessian(hess, hessian.matrix)
    tao.setTolerances(gatol=0.0, grtol=0.0, gttol=gttol)
    if stop is not None:

        def monitor(t: PETSc.TAO) -> None:
            if stop(*ev.split(t.getSolution())):
                t.setConvergedReason(PETSc.TAO.Reason.CONVERGED_USER)

        tao.setMonitor(monitor)
    tao.setMaximumIterations(max_iterations)
    tao.setFromOptions()
    krylov = [0]
    if kind in _NEWTON_TAO:
        linear.python_pc(tao.getKSP(), prefix + "tao_bnk_", linear_solver, None)
        krylov = linear.count_krylov(tao.getKSP())
    setup = time.perf_counter() - tic

    result = ev.run(
        tao,
        lambda: tao.solve(x),
        tao_reason,
        x,
        linear_iterations=krylov[0],
        setup=setup,
        details={"hessian_nnz": hessian.nnz if hessian else 0},
    )
    for obj in (tao, x, g, lower, upper):
        obj.destroy()
    if hessian is not None:
        hessian.destroy()
    ev.destroy()
    linear.clear_options(prefix, options)
    return result
