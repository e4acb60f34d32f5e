"""PETSc peers of the project's solvers on the same discrete problem (2.3) (serial).

The discrete problem (METHOD.md section 4) is: minimise J_h(x) over x = (u, phi) in
R^N x R^{n_s} with phi >= 0. Its optimality system is the variational inequality

    F(x) = (grad_u J_h, grad_phi J_h) = 0 on the free unknowns (u, and phi > 0),
    phi >= 0,  grad_phi J_h >= 0,  phi . grad_phi J_h = 0,

and its Jacobian is the Hessian of J_h,

    H(x) = [[D^2G(u) + T^T S_h T,  T^T S_h E],
            [E^T S_h T,            E^T S_h E]]       (METHOD.md (4.1), section 4),

the sparse P1 matrix D^2G plus a dense block on the boundary and Signorini unknowns
(z = T u + E phi = P x, so the dense part is P^T S_h P). :class:`CoupledHessian`
assembles H as one SeqAIJ matrix: the union of both sparsity patterns is computed
once, each evaluation reassembles D^2G with DOLFINx and adds its values to the
constant dense part at precomputed positions.

Peers of the project's PGPM (``coupling.pgpm``), each on x in one PETSc Vec with u
first (the P1 dof order) and phi after it:

* :func:`solve_snes_vi` - SNES ``vinewtonrsls`` (reduced-space active-set Newton with a
  backtracking line search) with one of :data:`LINEAR_SOLVERS` on the reduced Newton system,
  among them CG preconditioned by the project's substructuring preconditioner B
  (METHOD.md section 6) restricted to the inactive set, through a PCSHELL;
* :func:`solve_tao` - TAO bound-constrained minimisation of J_h: ``blmvm``, ``bqnls``
  (objective and gradient) and ``bnls``, ``bntr`` (with the Hessian H);
* :func:`poisson_yardstick` - one linear P1 Poisson solve with CG + GAMG, the cost
  unit of a linear solve on the same mesh.

:func:`attach_preconditioner` switches the preconditioner of a
:class:`coupling.problem.SignoriniProblem`, so that the set-up cost of B can be timed
apart from the shared set-up (mesh, forms, S_h).

Everything here is serial: the Hessian, the PETSc solvers and the PCSHELL work on
``PETSc.COMM_SELF`` and a problem on a communicator with more than one rank is refused
with a ``ValueError``.
"""
from __future__ import annotations

import itertools
import time
from dataclasses import dataclass, field, replace
from typing import Any, Callable

import numpy as np
import scipy.linalg
from petsc4py import PETSc

__all__ = ["LINEAR_SOLVERS", "TAO_TYPES", "BudgetExceeded", "Budget", "PeerResult",
           "CoupledHessian", "attach_preconditioner", "solve_project", "solve_snes_vi",
           "solve_tao", "poisson_yardstick"]

#: Linear solvers of the Newton systems (SNES VI, TAO BNLS/BNTR): the KSP type and the
#: PETSc options of its PC. The AMG preconditioners are rebuilt from scratch for every
#: reduced system (a PCPYTHON wrapper, :class:`_RebuiltPC`): SNES VI changes the size of
#: the system with the active set, and PETSc 3.18's GAMG then fails in PCSetUp
#: ("Cannot change local size of Amat after use"). ``substructuring`` is the project's
#: B restricted to the inactive set (:class:`_InactiveSetShell`). MUMPS uses the AMD
#: ordering (ICNTL(7) = 0): its automatic choice in this build (PORD; METIS and SCOTCH
#: are absent) made the analysis 3x (6.2e4 dofs) to 7x (2.5e5 dofs) slower, the dense
#: block rows being the costly part of the graph; ``mumps-cholesky-auto`` keeps it.
LINEAR_SOLVERS: dict[str, dict[str, Any]] = {
    "mumps": {"ksp_type": "preonly", "pc": {"pc_type": "lu",
                                            "pc_factor_mat_solver_type": "mumps",
                                            "mat_mumps_icntl_7": 0}},
    "mumps-cholesky": {"ksp_type": "preonly", "pc": {"pc_type": "cholesky",
                                                     "pc_factor_mat_solver_type": "mumps",
                                                     "mat_mumps_icntl_7": 0}},
    "mumps-cholesky-auto": {"ksp_type": "preonly", "pc": {"pc_type": "cholesky",
                                                          "pc_factor_mat_solver_type": "mumps"}},
    "petsc-lu": {"ksp_type": "preonly", "pc": {"pc_type": "lu",
                                               "pc_factor_mat_solver_type": "petsc",
                                               "pc_factor_mat_ordering_type": "nd"}},
    "gamg": {"ksp_type": "cg", "rebuild": True, "pc": {"pc_type": "gamg"}},
    "hypre": {"ksp_type": "cg", "rebuild": True, "pc": {"pc_type": "hypre",
                                                        "pc_hypre_type": "boomeramg"}},
    "substructuring": {"ksp_type": "cg", "pc": {}},
}
#: Relative tolerance of the iterative (CG) Newton solves: the fastest measured for SNES
#: VI + CG/B at 6.2e4 dofs (1e-8: 5 Newton steps, 147 CG iterations; 1e-6: 5 and 104;
#: 1e-4: 9 and 144; Eisenstat-Walker: 14 and 68, each Newton step costing a Hessian
#: assembly and an inactive-set submatrix).
KRYLOV_RTOL = 1e-6
#: TAO bound-constrained types: first-order (objective and gradient) and Newton-Krylov.
TAO_TYPES = ("blmvm", "bqnls", "bnls", "bntr")
_NEWTON_TAO = ("bnls", "bntr")

_prefixes = itertools.count()


class BudgetExceeded(RuntimeError):
    """A solver used up its wall-time budget (raised from inside a callback)."""


class Budget:
    """A wall-time budget of ``seconds`` from construction; :meth:`check` raises
    :class:`BudgetExceeded` once it is spent. ``None`` means no limit."""

    def __init__(self, seconds: float | None):
        self.seconds = seconds
        self.start = time.perf_counter()

    @property
    def spent(self) -> bool:
        return self.seconds is not None and time.perf_counter() - self.start > self.seconds

    def check(self) -> None:
        if self.spent:
            raise BudgetExceeded(f"not converged within the budget of {self.seconds:g} s")

    def run(self, solve: Callable[[], Any], reason_code: Callable[[], int],
            describe: Callable[[int], str]) -> tuple[bool, str, float]:
        """Call ``solve()``; return (converged, reason, wall time). A PETSc error raised
        after the budget is spent (a callback's BudgetExceeded surfacing through PETSc)
        counts as running out of budget."""
        tic = time.perf_counter()
        try:
            solve()
            code = reason_code()
            converged, reason = code > 0, describe(code)
        except BudgetExceeded as err:
            converged, reason = False, str(err)
        except PETSc.Error as err:
            converged = False
            reason = (f"not converged within the budget of {self.seconds:g} s" if self.spent
                      else f"PETSc error {err.ierr}")
        return converged, reason, time.perf_counter() - tic


@dataclass
class PeerResult:
    """Outcome of one peer solve.

    ``u`` (N,) and ``phi`` (n_s,) are the final iterate (also when not converged);
    ``iterations`` the outer (Newton, quasi-Newton) steps; ``linear_iterations`` the
    Krylov iterations summed over all steps (0 for direct solves); ``setup`` and
    ``solve`` wall times in seconds; ``evaluations`` the objective/gradient calls.
    """

    u: np.ndarray
    phi: np.ndarray
    converged: bool
    reason: str
    iterations: int
    linear_iterations: int
    setup: float
    solve: float
    evaluations: int = 0
    details: dict[str, Any] = field(default_factory=dict)


def _require_serial(comm) -> None:
    if comm.size > 1:
        raise ValueError(f"the PETSc peers are serial, got a communicator of {comm.size} ranks; "
                         "run without mpirun")


def _set_options(prefix: str, options: dict[str, Any]) -> None:
    db = PETSc.Options()
    for key, value in options.items():
        db[f"{prefix}{key}"] = value


def _clear_options(prefix: str, options: dict[str, Any]) -> None:
    db = PETSc.Options()
    for key in options:
        db.delValue(f"{prefix}{key}")


def attach_preconditioner(problem, kind: str) -> float:
    """Give ``problem`` (a :class:`coupling.problem.SignoriniProblem`) a freshly built
    preconditioner of ``kind`` ("substructuring", "identity", "exact") and the matching
    projection; the old preconditioner is destroyed. Returns the build time in seconds.

    Used to time B apart from the shared set-up and to give every solver its own B.
    """
    from coupling.projection import SignoriniProjection

    tic = time.perf_counter()
    problem.preconditioner.destroy()
    problem.options = replace(problem.options, preconditioner=kind)
    problem.preconditioner = problem._make_preconditioner()
    opts = problem.options
    problem.projection = SignoriniProjection(
        problem.preconditioner.signorini_metric, opts.projection, rho_in=opts.projection_tol,
        max_iterations=opts.projection_max_iterations,
        lambda_max=problem.preconditioner.lambda_max_signorini)
    return time.perf_counter() - tic


class _BudgetedFunctional:
    """J_h with a wall-time budget: every evaluation checks it and remembers the
    state it was called at (so that the last iterate survives a budget stop)."""

    def __init__(self, inner, budget: Budget):
        self._inner = inner
        self._budget = budget
        self.last: tuple[np.ndarray, np.ndarray] | None = None

    def __getattr__(self, name: str) -> Any:
        return getattr(self._inner, name)

    def _check(self, u_function, phi) -> None:
        self.last = (u_function.x.array.copy(), np.array(phi, dtype=float))
        self._budget.check()

    def value(self, u_function, phi):
        self._check(u_function, phi)
        return self._inner.value(u_function, phi)

    def gradient(self, u_function, phi, grad_u):
        self._check(u_function, phi)
        return self._inner.gradient(u_function, phi, grad_u)

    def value_and_gradient(self, u_function, phi, grad_u):
        self._check(u_function, phi)
        return self._inner.value_and_gradient(u_function, phi, grad_u)


def solve_project(problem, method: str = "pgpm", *, preconditioner: str = "substructuring",
                  budget: float | None = None, **options) -> PeerResult:
    """Run one of the project's methods (``pgpm``, ``apgpm``, ``ssn``) on ``problem``
    with a freshly built ``preconditioner`` and the result in the form of the peers.

    ``setup`` is the preconditioner build plus the step estimate (tau = 1/C0),
    ``solve`` the iteration; ``options`` override further
    :class:`coupling.problem.SolverOptions` fields (e.g. ``tol``, ``max_iterations``).
    ``linear_iterations`` is the number of CG iterations of ``ssn`` (0 otherwise).
    The budget is checked at every evaluation of J_h.
    """
    _require_serial(problem.comm)
    saved = problem.options
    build = attach_preconditioner(problem, preconditioner)
    problem.options = replace(problem.options, method=method, **options)
    clock = Budget(budget)
    inner = problem.functional
    problem.functional = _BudgetedFunctional(inner, clock)
    tic = time.perf_counter()
    try:
        solution = problem.solve()
    except BudgetExceeded as err:
        u, phi = problem.functional.last
        return PeerResult(u=u, phi=phi, converged=False, reason=str(err), iterations=-1,
                          linear_iterations=0, setup=build,
                          solve=time.perf_counter() - tic)
    finally:
        problem.functional = inner
        problem.options = replace(saved, preconditioner=preconditioner)
    n_u = problem.V.dofmap.index_map.size_local
    newton = solution.history[5:] if method == "ssn" else []  # after the PGPM start steps
    return PeerResult(u=solution.u.x.array[:n_u].copy(), phi=solution.phi.copy(),
                      converged=solution.converged, reason=solution.reason,
                      iterations=solution.iterations,
                      linear_iterations=int(sum(r.inner for r in newton)),
                      setup=build + solution.timings["step_estimate"],
                      solve=solution.timings["solve"],
                      details={"tau": solution.tau, "C0": solution.C0,
                               "energy_increases": solution.energy_increases})


# ----------------------------------------------------------------------------- J_h on x
class _Evaluator:
    """J_h, its gradient and its Hessian on x = (u, phi) in one sequential PETSc Vec."""

    def __init__(self, problem, budget: Budget):
        from dolfinx import fem

        _require_serial(problem.comm)
        self.problem = problem
        self.functional = problem.functional
        self.budget = budget
        self.u = fem.Function(problem.V)
        self.n_u = problem.V.dofmap.index_map.size_local
        if self.u.x.array.size != self.n_u:
            raise ValueError("the P1 space has ghost entries; the PETSc peers are serial")
        self.n_s = problem.n_signorini
        self.grad_u = problem.forms.create_vector()
        self.evaluations = 0

    @property
    def size(self) -> int:
        return self.n_u + self.n_s

    def create_vec(self) -> PETSc.Vec:
        x = PETSc.Vec().createSeq(self.size, comm=PETSc.COMM_SELF)
        x.set(0.0)
        return x

    def bounds(self) -> tuple[PETSc.Vec, PETSc.Vec]:
        """u free, phi >= 0."""
        lower, upper = self.create_vec(), self.create_vec()
        lower.array[:self.n_u] = PETSc.NINFINITY
        lower.array[self.n_u:] = 0.0
        upper.set(PETSc.INFINITY)
        return lower, upper

    def _state(self, x: PETSc.Vec) -> np.ndarray:
        self.budget.check()
        values = x.array_r
        self.u.x.array[:] = values[:self.n_u]
        return values[self.n_u:].copy()

    def objective(self, x: PETSc.Vec) -> float:
        self.evaluations += 1
        return self.functional.value(self.u, self._state(x))

    def gradient(self, x: PETSc.Vec, g: PETSc.Vec) -> None:
        self.evaluations += 1
        g_phi = self.functional.gradient(self.u, self._state(x), self.grad_u)
        g.array[:self.n_u] = self.grad_u.array_r
        g.array[self.n_u:] = g_phi

    def objective_gradient(self, x: PETSc.Vec, g: PETSc.Vec) -> float:
        self.evaluations += 1
        value, g_phi = self.functional.value_and_gradient(self.u, self._state(x), self.grad_u)
        g.array[:self.n_u] = self.grad_u.array_r
        g.array[self.n_u:] = g_phi
        return value

    def split(self, x: PETSc.Vec) -> tuple[np.ndarray, np.ndarray]:
        values = x.array_r
        return values[:self.n_u].copy(), values[self.n_u:].copy()

    def destroy(self) -> None:
        self.grad_u.destroy()


class CoupledHessian:
    """The Hessian H(x) of J_h (module docstring) as one SeqAIJ matrix.

    Set-up, O(nnz): the pattern of D^2G (the P1 pattern of DOLFINx) and the dense block
    P^T S_h P on the sorted indices ``idx`` of P = [T, E] (boundary dofs and phi). A row
    outside ``idx`` is the D^2G row; a row in ``idx`` is ``idx`` merged with the few
    D^2G columns outside it, so every position is known without a global sort. The
    matrix shares its CSR arrays with numpy (``MatCreateSeqAIJWithArrays``): the dense
    values are written once, and :meth:`assemble` costs one DOLFINx Jacobian assembly
    plus one vector update at the D^2G positions. S_h is symmetrised, (S_h + S_h^T)/2,
    the Hessian of 1/2 z^T S_h z whatever the round-off asymmetry of S_h.

    Parameters
    ----------
    problem
        A :class:`coupling.problem.SignoriniProblem` on one rank.
    """

    def __init__(self, problem):
        from dolfinx import fem

        _require_serial(problem.comm)
        self.forms = problem.forms
        b = problem.boundary
        n_u = problem.V.dofmap.index_map.size_local
        n_s = problem.n_signorini
        n = n_u + n_s
        self.n = n
        self._jacobian = self.forms.create_matrix()
        self.forms.assemble_jacobian(fem.Function(problem.V), self._jacobian)
        k_indptr, k_indices, _ = self._jacobian.getValuesCSR()  # sorted columns per row
        k_indptr = k_indptr.astype(np.int64)
        k_indices = k_indices.astype(np.int64)
        k_len = np.diff(k_indptr)
        k_rows = np.repeat(np.arange(n_u), k_len)
        # the dense block: block index p <-> unknown idx[p] <-> boundary position inv[p]
        idx = np.concatenate([b.dofs, n_u + np.arange(n_s)]).astype(np.int64)
        inv = np.concatenate([np.arange(b.n_gamma), b.signorini]).astype(np.int64)
        order = np.argsort(idx)
        idx, inv = idx[order], inv[order]
        m = idx.size
        in_block = np.zeros(n, dtype=bool)
        in_block[idx] = True
        # D^2G entries of block rows whose column is outside the block: "extra" columns
        in_block_row = in_block[k_rows]
        extra = in_block_row & ~in_block[k_indices]
        row_len = np.zeros(n, dtype=np.int64)
        row_len[:n_u] = k_len
        row_len[idx] = m + np.bincount(k_rows[extra], minlength=n)[idx]
        indptr = np.concatenate([[0], np.cumsum(row_len)])
        nnz = int(indptr[-1])
        # position of every D^2G entry: its rank in the row (outside the block: the
        # D^2G row itself; in a block row: block columns before it + extras before it)
        rank = np.arange(k_indices.size) - k_indptr[k_rows]
        extras_before = np.cumsum(extra) - extra
        extras_before -= np.concatenate([[0], np.cumsum(extra)])[k_indptr[:-1]][k_rows]
        merged_rank = np.searchsorted(idx, k_indices) + extras_before
        k_pos = indptr[k_rows] + np.where(in_block_row, merged_rank, rank)
        indices = np.empty(nnz, dtype=PETSc.IntType)
        values = np.zeros(nnz)
        indices[k_pos] = k_indices
        s_sym = 0.5 * (problem.S + problem.S.T)
        extra_cols = k_indices[extra]
        extra_ptr = np.concatenate([[0], np.cumsum(np.bincount(k_rows[extra], minlength=n))])
        for p, row in enumerate(idx):
            cols = extra_cols[extra_ptr[row]:extra_ptr[row + 1]]
            pos = indptr[row] + np.arange(m) + np.searchsorted(cols, idx)
            indices[pos] = idx
            values[pos] = s_sym[inv[p], inv]
        self._k_pos = k_pos
        self._k_base = values[k_pos].copy()  # the dense part at the D^2G positions
        self._indptr = indptr.astype(PETSc.IntType)
        self._indices = indices
        self._values = values
        self.matrix = PETSc.Mat().createAIJWithArrays(
            (n, n), (self._indptr, self._indices, self._values), comm=PETSc.COMM_SELF)
        self.matrix.setOption(PETSc.Mat.Option.SYMMETRIC, True)
        self.matrix.assemble()
        self.nnz = nnz

    def assemble(self, u) -> PETSc.Mat:
        """H at the state ``u`` (dolfinx Function) into :attr:`matrix`; returns it."""
        self.forms.assemble_jacobian(u, self._jacobian)
        _, _, k_values = self._jacobian.getValuesCSR()
        self._values[self._k_pos] = self._k_base + k_values
        self.matrix.assemble()  # marks the shared arrays as changed (state increase)
        return self.matrix

    def destroy(self) -> None:
        self._jacobian.destroy()
        self.matrix.destroy()


class _InactiveSetShell:
    """PCSHELL context: the substructuring B restricted to the inactive set,
    diag(B_Omega^{-1}, (omega M_s)[I, I]^{-1}) (as in ``coupling.newton``).

    ``inactive()`` returns the indices (into x) of the reduced system, which must be
    all of u followed by the free phi; the M_s block is refactored whenever it changes.
    """

    def __init__(self, preconditioner, n_u: int, inactive: Callable[[], np.ndarray]):
        self.preconditioner = preconditioner
        self.n_u = n_u
        self.inactive = inactive
        self.metric = np.asarray(preconditioner.signorini_metric)
        self._free = None
        self._factor = None
        self.applications = 0
        self.time_setup = 0.0
        self.time_apply = 0.0

    def setUp(self, pc: PETSc.PC) -> None:
        start = time.perf_counter()
        idx = np.asarray(self.inactive(), dtype=np.int64)
        size = pc.getOperators()[0].getSize()[0]
        if idx.size != size or not np.array_equal(idx[:self.n_u], np.arange(self.n_u)):
            raise RuntimeError(f"inactive set of size {idx.size} does not match the reduced "
                               f"system of size {size} with all u unknowns first")
        free = idx[self.n_u:] - self.n_u
        if self._free is None or not np.array_equal(free, self._free):
            self._free = free
            block = self.metric[np.ix_(free, free)]
            self._factor = scipy.linalg.cho_factor(block) if free.size else None
        self.time_setup += time.perf_counter() - start

    def apply(self, pc: PETSc.PC, x: PETSc.Vec, y: PETSc.Vec) -> None:
        start = time.perf_counter()
        self.applications += 1
        values = x.array_r
        out = y.array
        out[:self.n_u] = self.preconditioner.apply_omega(values[:self.n_u])
        if self._factor is not None:
            out[self.n_u:] = scipy.linalg.cho_solve(self._factor, values[self.n_u:])
        self.time_apply += time.perf_counter() - start


class _RebuiltPC:
    """PCPYTHON context: a PC of the given options, built from scratch at every set-up
    (every new reduced Newton system), applied as is."""

    def __init__(self, prefix: str):
        self.prefix = prefix
        self.inner: PETSc.PC | None = None

    def setUp(self, pc: PETSc.PC) -> None:
        if self.inner is not None:
            self.inner.destroy()
        self.inner = PETSc.PC().create(PETSc.COMM_SELF)
        self.inner.setOptionsPrefix(self.prefix)
        self.inner.setOperators(*pc.getOperators())
        self.inner.setFromOptions()
        self.inner.setUp()

    def apply(self, pc: PETSc.PC, x: PETSc.Vec, y: PETSc.Vec) -> None:
        self.inner.apply(x, y)

    def destroy(self, pc: PETSc.PC | None = None) -> None:
        if self.inner is not None:
            self.inner.destroy()
            self.inner = None


def _linear_options(prefix: str, ksp_prefix: str, name: str, krylov_rtol: float, *,
                    ksp_type: str | None = None) -> dict[str, Any]:
    """Options (without ``prefix``) of the KSP with options prefix ``prefix + ksp_prefix``
    for the linear solver ``name``; a rebuilt PC reads its options under ``inner_``."""
    spec = LINEAR_SOLVERS[name]
    out: dict[str, Any] = {f"{ksp_prefix}ksp_type": ksp_type or spec["ksp_type"],
                           f"{ksp_prefix}ksp_rtol": krylov_rtol,
                           f"{ksp_prefix}ksp_max_it": 2000}
    pc_prefix = f"{ksp_prefix}inner_" if spec.get("rebuild") else ksp_prefix
    out.update({f"{pc_prefix}{k}": v for k, v in spec["pc"].items()})
    return out


def _python_pc(ksp: PETSc.KSP, prefix: str, name: str, shell: Any) -> None:
    """Install the PCPYTHON context of the linear solver ``name`` (if it has one) on
    ``ksp`` after its set-from-options (no pc_type option, so a KSP reset keeps it)."""
    context = shell if name == "substructuring" else (
        _RebuiltPC(prefix + "inner_") if LINEAR_SOLVERS[name].get("rebuild") else None)
    if context is not None:
        ksp.getPC().setType("python")
        ksp.getPC().setPythonContext(context)


def _count_krylov(ksp: PETSc.KSP) -> list[int]:
    """Attach a monitor to ``ksp`` that counts its Krylov iterations (returns the
    counter; a direct solve, KSP ``preonly``, counts none)."""
    counter = [0]

    def monitor(k, its, _rnorm):
        if its > 0 and k.getType() != "preonly":
            counter[0] += 1

    ksp.setMonitor(monitor)
    return counter


# ----------------------------------------------------------------------------- SNES VI
def solve_snes_vi(problem, *, linear_solver: str = "mumps", rtol: float = 1e-12,
                  max_iterations: int = 100, budget: float | None = None,
                  krylov_rtol: float = KRYLOV_RTOL, line_search: str = "bt",
                  objective: bool = False) -> PeerResult:
    """Solve the optimality system with SNES ``vinewtonrsls`` from x_0 = 0.

    F(x) = grad J_h(x) with bounds phi >= 0 (u free), Jacobian H(x)
    (:class:`CoupledHessian`), line search ``line_search`` on ||F|| (or on J_h with
    ``objective=True``: measured to fail near the solution once J_h changes by less than
    its round-off while ||F|| is still 1e-7 ||F(x_0)||, with inexact (CG) Newton steps).
    Converged when ||F on the inactive set|| <= rtol ||F(x_0)|| (PETSc's VI norm).

    Parameters
    ----------
    problem
        A serial :class:`coupling.problem.SignoriniProblem`.
    linear_solver
        A key of :data:`LINEAR_SOLVERS`; ``substructuring`` builds the project's B
        (:func:`attach_preconditioner`, counted in the set-up time).
    rtol
        SNES relative tolerance (the Newton steps converge quadratically, so the
        last step takes the error far below it).
    max_iterations
        Newton step cap.
    budget
        Wall-time budget in seconds (checked at every function evaluation).
    krylov_rtol
        Relative tolerance of the CG solves.
    """
    if linear_solver not in LINEAR_SOLVERS:
        raise ValueError(f"linear_solver must be one of {tuple(LINEAR_SOLVERS)}, "
                         f"got {linear_solver!r}")
    clock = Budget(budget)
    tic = time.perf_counter()
    if linear_solver == "substructuring":
        attach_preconditioner(problem, "substructuring")
    ev = _Evaluator(problem, clock)
    hessian = CoupledHessian(problem)
    f_vec, x = ev.create_vec(), ev.create_vec()
    spent = {"function": 0.0, "jacobian": 0.0}
    lower, upper = ev.bounds()
    prefix = f"peers_snes_{next(_prefixes)}_"
    options = {"snes_type": "vinewtonrsls", "snes_linesearch_type": line_search,
               "snes_rtol": rtol, "snes_atol": 0.0, "snes_stol": 0.0,
               "snes_max_it": max_iterations, "snes_max_funcs": 100 * max_iterations,
               **_linear_options(prefix, "", linear_solver, krylov_rtol)}
    _set_options(prefix, options)
    snes = PETSc.SNES().create(PETSc.COMM_SELF)
    snes.setOptionsPrefix(prefix)

    def function(_snes, xv, fv):
        start = time.perf_counter()
        ev.gradient(xv, fv)
        spent["function"] += time.perf_counter() - start

    def jacobian(_snes, xv, _a, _p):  # _a is hessian.matrix
        start = time.perf_counter()
        clock.check()
        ev._state(xv)
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
    if linear_solver == "substructuring":
        shell = _InactiveSetShell(problem.preconditioner, ev.n_u,
                                  lambda: snes.getVIInactiveSet().getIndices())
    _python_pc(ksp, prefix, linear_solver, shell)
    krylov = _count_krylov(ksp)
    setup = time.perf_counter() - tic

    converged, reason_text, solve = clock.run(lambda: snes.solve(None, x),
                                              snes.getConvergedReason, _snes_reason)
    u, phi = ev.split(x)
    result = PeerResult(u=u, phi=phi, converged=converged, reason=reason_text,
                        iterations=snes.getIterationNumber(), linear_iterations=krylov[0],
                        setup=setup, solve=solve, evaluations=ev.evaluations,
                        details={"hessian_nnz": hessian.nnz,
                                 "time_function": spent["function"],
                                 "time_jacobian": spent["jacobian"],
                                 "pc_applications": shell.applications if shell else 0,
                                 "time_pc_setup": shell.time_setup if shell else 0.0,
                                 "time_pc_apply": shell.time_apply if shell else 0.0})
    for obj in (snes, f_vec, x, lower, upper):
        obj.destroy()
    hessian.destroy()
    ev.destroy()
    _clear_options(prefix, options)
    return result


def _snes_reason(code: int) -> str:
    names = {v: k for k, v in vars(PETSc.SNES.ConvergedReason).items() if isinstance(v, int)}
    return f"{names.get(code, 'UNKNOWN')} ({code})"


def _tao_reason(code: int) -> str:
    names = {v: k for k, v in vars(PETSc.TAO.Reason).items() if isinstance(v, int)}
    return f"{names.get(code, 'UNKNOWN')} ({code})"


# ----------------------------------------------------------------------------- TAO
def solve_tao(problem, kind: str, *, gttol: float = 1e-10, linear_solver: str = "mumps",
              max_iterations: int = 100000, budget: float | None = None,
              krylov_rtol: float = KRYLOV_RTOL,
              stop: Callable[[np.ndarray, np.ndarray], bool] | None = None) -> PeerResult:
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
        raise ValueError(f"linear_solver must be one of {tuple(LINEAR_SOLVERS)}, "
                         f"got {linear_solver!r}")
    if kind in _NEWTON_TAO and linear_solver == "substructuring":
        raise ValueError("TAO does not expose its inactive set; use a direct or AMG "
                         "linear_solver for bnls/bntr")
    clock = Budget(budget)
    tic = time.perf_counter()
    ev = _Evaluator(problem, clock)
    x, g = ev.create_vec(), ev.create_vec()
    lower, upper = ev.bounds()
    prefix = f"peers_tao_{next(_prefixes)}_"
    options: dict[str, Any] = {"tao_type": kind, "tao_max_funcs": 10 * max_iterations}
    if kind in _NEWTON_TAO:
        # BNTR needs a trust-region CG; STCG is also BNLS's default. With an exact
        # factor as preconditioner one STCG step is the Newton step.
        options.update(_linear_options(prefix, "tao_bnk_", linear_solver, krylov_rtol,
                                       ksp_type="stcg"))
    _set_options(prefix, options)
    tao = PETSc.TAO().create(PETSc.COMM_SELF)
    tao.setOptionsPrefix(prefix)
    tao.setObjectiveGradient(lambda _tao, xv, gv: ev.objective_gradient(xv, gv), g)
    tao.setVariableBounds(lower, upper)
    hessian = None
    if kind in _NEWTON_TAO:
        hessian = CoupledHessian(problem)

        def hess(_tao, xv, _a, _p):  # _a is hessian.matrix
            clock.check()
            ev._state(xv)
            hessian.assemble(ev.u)

        tao.setHessian(hess, hessian.matrix)
    tao.setTolerances(gatol=0.0, grtol=0.0, gttol=gttol)
    if stop is not None:
        def monitor(t):
            if stop(*ev.split(t.getSolution())):
                t.setConvergedReason(PETSc.TAO.Reason.CONVERGED_USER)

        tao.setMonitor(monitor)
    tao.setMaximumIterations(max_iterations)
    tao.setFromOptions()
    krylov = [0]
    if kind in _NEWTON_TAO:
        _python_pc(tao.getKSP(), prefix + "tao_bnk_", linear_solver, None)
        krylov = _count_krylov(tao.getKSP())
    setup = time.perf_counter() - tic

    converged, reason_text, solve = clock.run(lambda: tao.solve(x), tao.getConvergedReason,
                                              _tao_reason)
    u, phi = ev.split(x)
    result = PeerResult(u=u, phi=phi, converged=converged, reason=reason_text,
                        iterations=tao.getIterationNumber(), linear_iterations=krylov[0],
                        setup=setup, solve=solve, evaluations=ev.evaluations,
                        details={"hessian_nnz": hessian.nnz if hessian else 0})
    for obj in (tao, x, g, lower, upper):
        obj.destroy()
    if hessian is not None:
        hessian.destroy()
    ev.destroy()
    _clear_options(prefix, options)
    return result


# ----------------------------------------------------------------------------- yardstick
def poisson_yardstick(V, boundary_dofs: np.ndarray, *, rtol: float = 1e-8) -> PeerResult:
    """One linear solve on the mesh of ``V``: -Laplace w = 1 in Omega, w = 0 on Gamma,
    P1 stiffness matrix, CG + GAMG to ||r|| <= rtol ||b|| (preconditioned norm, the
    PETSc default for CG).

    ``setup`` is the assembly of matrix and load plus the GAMG set-up (the forms are
    compiled before the clock starts); ``solve`` the CG iterations. The result's ``u`` is w (N,) and ``phi`` is empty.
    """
    import ufl
    from dolfinx import fem

    from fem_py.forms import compile_form

    comm = V.mesh.comm
    _require_serial(comm)
    w, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    # form compilation (JIT, cached on disk) is not part of the solve's cost
    a = compile_form(ufl.inner(ufl.grad(w), ufl.grad(v)) * ufl.dx(metadata={"quadrature_degree": 0}))
    load = compile_form(ufl.inner(fem.Constant(V.mesh, PETSc.ScalarType(1.0)), v)
                        * ufl.dx(metadata={"quadrature_degree": 1}))
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
    result = PeerResult(u=x.array_r.copy(), phi=np.zeros(0), converged=code > 0,
                        reason=f"KSP reason {code}", iterations=ksp.getIterationNumber(),
                        linear_iterations=ksp.getIterationNumber(), setup=setup, solve=solve)
    for obj in (ksp, A, b, x):
        obj.destroy()
    return result
