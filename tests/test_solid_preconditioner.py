"""The ``amg`` preconditioner of a body in R^3 (coupling/preconditioners/multigrid.py,
docs/method.md section 11): its blocks, and the solvers' counts with it on the box pressed
onto its bottom face (measured in docs/design/three_dimensions.md over four refinements)."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
from mpi4py import MPI
from petsc4py import PETSc

from coupling.options import LATTICE_MG_SMOOTHING_STEPS, SolverOptions
from coupling.preconditioners import build_preconditioner
from coupling.preconditioners.multigrid import AMG_OPTIONS_PREFIX
from coupling.problem import SignoriniProblem
from coupling.solvers import solve
from fem_py.forms import make_material
from fem_py.mesh import GeometrySpec, build_domain

COMM = MPI.COMM_WORLD


def _problem(n: int) -> SignoriniProblem:
    domain = build_domain(COMM, GeometrySpec("box", width=0.5, h=0.5 / n, signorini=["bottom"]))
    return SignoriniProblem(
        domain, make_material("carstensen"), f="1", t0="-1", u0="0.02*x", boundary_operator="dense"
    )


@pytest.fixture(scope="module")
def problems():
    return {n: _problem(n) for n in (4, 8)}


@pytest.mark.parametrize("n", [4, 8])
def test_blocks(problems, n):
    problem = problems[n]
    B = build_preconditioner(problem, SolverOptions(preconditioner="amg"))
    try:
        # B_Omega^{-1} inverts B_Omega to the inner tolerance (1e-12, round-off beyond)
        rng = np.random.default_rng(1)
        u = rng.standard_normal(B.n_omega)
        assert np.linalg.norm(B.apply_omega(B.matvec_omega(u)) - u) <= 1e-9 * np.linalg.norm(u)
        # B_Omega on the constant: its boundary term c |Gamma| = <S_h 1, 1> (K 1 = 0)
        one = np.ones(B.n_omega)
        S = problem.S
        s11 = np.ones(S.shape[0]) @ (S @ np.ones(S.shape[0]))
        assert abs(COMM.allreduce(one @ B.matvec_omega(one)) - s11) <= 1e-12 * s11
        # M_s = E^T W_h E against the Hessian's phi block E^T S_h E: S_h >= W_h / 2 (the
        # maths), and the two are close on a face (measured 0.90..1.00)
        s = problem.boundary.signorini
        ratios = scipy.linalg.eigh(S[np.ix_(s, s)], B.signorini_metric, eigvals_only=True)
        assert ratios.min() >= 0.5 and ratios.max() <= 1.5
        assert B.lambda_max_signorini == pytest.approx(np.linalg.eigvalsh(B.signorini_metric)[-1])
        pc = B._ksp.getPC()
        if n == 4:
            # no coarser lattice: GAMG as AMG_OPTIONS configure it (graph not squared, one
            # smoothing step per level)
            assert pc.getType() == "gamg" and pc.getMGLevels() >= 2
            steps = 1
        else:
            # the geometric multigrid of the box's lattice (8 and 4 cubes per side)
            assert pc.getType() == "mg" and pc.getMGLevels() == 2
            steps = LATTICE_MG_SMOOTHING_STEPS
        assert all(
            pc.getMGSmoother(level).getTolerances()[3] == steps
            for level in range(1, pc.getMGLevels())
        )
        # the options gone from PETSc's database again
        assert not any(key.startswith(AMG_OPTIONS_PREFIX) for key in PETSc.Options().getAll())
    finally:
        B.destroy()


def test_counts_are_bounded_and_agree_with_the_exact_preconditioner(problems):
    # measured (docs/design/three_dimensions.md): ssn 8, 9; pgpm 64, 73; apgpm 17, 27
    counts = {}
    for n, problem in problems.items():
        reference = solve(problem, SolverOptions(preconditioner="exact", nested=False))
        for method in ("ssn", "pgpm", "apgpm"):
            run = solve(problem, SolverOptions(method=method, preconditioner="amg", nested=False))
            assert run.converged
            counts[n, method] = run.iterations
            if method == "ssn":
                counts[n, "cg"] = max(r.cg_iterations for r in run.history)
            # the same minimiser: the contact set, and phi to the tolerance's scale
            assert np.array_equal(run.contact, reference.contact)
            assert np.abs(run.phi - reference.phi).max() <= 1e-4 * np.abs(reference.phi).max()
        assert counts[n, "ssn"] <= 15  # issue 31: within 15 outer steps from a cold start
    print(counts)
    assert counts[8, "pgpm"] <= 1.3 * counts[4, "pgpm"]  # issue 31: at most 1.3x per halving
