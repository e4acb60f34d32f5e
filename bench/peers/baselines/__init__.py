"""PETSc baselines for the project's solvers on the same discrete problem (2.3) (serial).

The discrete problem (docs/method.md section 4) is: minimise J_h(x) over x = (u, phi) in
R^N x R^{n_s} with phi >= 0. Its optimality system is the variational inequality

    F(x) = (grad_u J_h, grad_phi J_h) = 0 on the free unknowns (u, and phi > 0),
    phi >= 0,  grad_phi J_h >= 0,  phi . grad_phi J_h = 0,

and its Jacobian is the Hessian of J_h,

    H(x) = [[D^2G(u) + T^T S_h T,  T^T S_h E],
            [E^T S_h T,            E^T S_h E]]       (docs/method.md (4.1), section 4),

the sparse P1 matrix D^2G plus a dense block on the boundary and Signorini unknowns
(z = T u + E phi = P x, so the dense part is P^T S_h P).
:class:`~bench.peers.baselines.hessian.CoupledHessian` assembles H as one SeqAIJ matrix.

The baselines (the benchmark's "peers" of PGPM, ``bench.peers``), each on x in one
PETSc Vec with u first (the P1 dof order) and phi after it:

* :func:`~bench.peers.baselines.snes.solve_snes_vi` - SNES ``vinewtonrsls`` (reduced-space
  active-set Newton with a backtracking line search) with one of :data:`LINEAR_SOLVERS`
  on the reduced Newton system, among them CG preconditioned by the project's
  substructuring preconditioner B (docs/method.md section 6) restricted to the inactive set,
  through a PCSHELL;
* :func:`~bench.peers.baselines.sequenced.solve_snes_vi_sequenced` - the same with grid
  sequencing: solved on the coarser meshes of a hierarchy first, each solution
  prolonged (:func:`coupling.solvers.nested.prolong`) to start the next finer level;
* :func:`~bench.peers.baselines.tao.solve_tao` - TAO bound-constrained minimisation of J_h:
  ``blmvm``, ``bqnls`` (objective and gradient) and ``bnls``, ``bntr`` (with H);
* :func:`~bench.peers.baselines.yardstick.poisson_yardstick` - one linear P1 Poisson solve
  with CG + GAMG, the cost unit of a linear solve on the same mesh;
* :func:`~bench.peers.baselines.project.solve_project` - the project's own methods
  (``pgpm``, ``apgpm``, ``ssn``) with a wall-time budget, in the same result form.

They read the assembled :class:`coupling.problem.SignoriniProblem` and never change it:
every solver builds its own B (:func:`coupling.preconditioners.build_preconditioner`)
and destroys it. Everything here is serial: the Hessian, the PETSc solvers and the
PCSHELL work on ``PETSc.COMM_SELF`` and a problem on a communicator with more than one
rank is refused with a ``ValueError``. Measurements behind the settings:
docs/design/baselines.md.
"""
from bench.peers.baselines.budget import Budget, BudgetExceeded, PeerResult
from bench.peers.baselines.hessian import CoupledHessian
from bench.peers.baselines.linear import KRYLOV_RTOL, LINEAR_SOLVERS
from bench.peers.baselines.project import solve_project
from bench.peers.baselines.sequenced import solve_snes_vi_sequenced
from bench.peers.baselines.snes import solve_snes_vi
from bench.peers.baselines.tao import TAO_TYPES, solve_tao
from bench.peers.baselines.yardstick import poisson_yardstick

__all__ = [
    "LINEAR_SOLVERS",
    "KRYLOV_RTOL",
    "TAO_TYPES",
    "BudgetExceeded",
    "Budget",
    "PeerResult",
    "CoupledHessian",
    "solve_project",
    "solve_snes_vi",
    "solve_snes_vi_sequenced",
    "solve_tao",
    "poisson_yardstick",
]
