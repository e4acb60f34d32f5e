"""The peer benchmark (bench/peers/) and the PETSc baselines (bench/peers/baselines/).

The quick benchmark checks that every solver reaches the PGPM solution, not the
timings. Tolerances: PGPM stops at its default tol = 1e-8 on the B-norm step, which
leaves an error of about 1e-8 (u) and 2e-6 (phi) relative to the exact minimiser
(the Newton solvers below reach it to round-off); the benchmark's agreement test
(1e-6 in u, 1e-5 in phi) has a factor of 5-100 of margin over that.
"""
from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.sparse as sp
from mpi4py import MPI

from bench.peers import baselines
from bench.peers.cli import main as bench_main
from bench.peers.solvers import TOL_PHI, TOL_U

COMM = MPI.COMM_WORLD
pytestmark = pytest.mark.skipif(COMM.size > 1, reason="the peer benchmark is serial")


@pytest.fixture(scope="module")
def small_problem():
    from coupling.manufactured import manufactured_problem, square_contact
    from fem_py.forms import make_material

    return manufactured_problem(COMM, square_contact(), make_material("carstensen"), cells=16)


def test_hessian_matrix_equals_the_hessian_action(small_problem):
    """CoupledHessian (one AIJ matrix) against CoupledFunctional.hessian_action
    (D^2G matrix + dense S_h product) at a nonlinear state: equal to round-off."""
    from dolfinx import fem

    p = small_problem
    u = fem.Function(p.V)
    x = p.V.tabulate_dof_coordinates()
    u.x.array[:] = np.sin(3 * x[:, 0]) + x[:, 1] ** 2
    hessian = baselines.CoupledHessian(p)
    H = hessian.assemble(u)
    rng = np.random.default_rng(1)
    n_u, n_s = u.x.array.size, p.n_signorini
    e = rng.standard_normal(n_u + n_s)
    jac = p.forms.create_matrix()
    p.forms.assemble_jacobian(u, jac)
    e_u, out_u = jac.createVecRight(), jac.createVecRight()
    e_u.array[:] = e[:n_u]
    out_phi = p.functional.hessian_action(jac, e_u, e[n_u:], out_u)
    expected = np.concatenate([out_u.array_r, out_phi])
    xv, yv = H.createVecs()
    xv.array[:] = e
    H.mult(xv, yv)
    assert np.linalg.norm(yv.array_r - expected) <= 1e-12 * np.linalg.norm(expected)
    # symmetric: the dense block is P^T (S_h + S_h^T)/2 P
    indptr, indices, data = H.getValuesCSR()
    csr = sp.csr_matrix((data, indices, indptr), shape=H.getSize())
    assert abs(csr - csr.T).max() <= 1e-12 * abs(csr).max()
    for obj in (jac, e_u, out_u, xv, yv):
        obj.destroy()
    hessian.destroy()


def test_peers_reach_the_pgpm_minimiser(small_problem):
    """SNES VI (direct and CG + substructuring) and TAO BNLS reach the minimiser of J_h
    that PGPM reaches; the Newton solvers converge in a handful of steps."""
    ref = baselines.solve_project(small_problem, "pgpm", tol=1e-12, max_iterations=5000)
    assert ref.converged
    runs = [
        baselines.solve_snes_vi(small_problem, linear_solver="mumps-cholesky"),
        baselines.solve_snes_vi(small_problem, linear_solver="substructuring"),
        baselines.solve_tao(small_problem, "bnls", linear_solver="mumps-cholesky"),
    ]
    for run in runs:
        assert run.converged, run.reason
        assert run.iterations <= 10
        # PGPM at tol 1e-12: error <= ~kappa * 1e-12 (tests/test_pgpm.py)
        assert np.linalg.norm(run.u - ref.u) <= 1e-9 * np.linalg.norm(ref.u)
        assert np.linalg.norm(run.phi - ref.phi) <= 1e-8 * np.linalg.norm(ref.phi)
        assert np.all(run.phi >= 0.0)
    # CG with B needs few iterations per Newton step (B spectrally equivalent, Thm 4.1)
    assert runs[1].linear_iterations <= 60 * runs[1].iterations


def test_grid_sequenced_snes_vi_reaches_the_ssn_solution(small_problem):
    """SNES VI with grid sequencing (a coarse level of 8 cells, d = 2h, prolonged to the
    16-cell problem) reaches the discrete solution of ssn: both converge quadratically
    past their tolerances (ssn at tol 1e-12, SNES VI at rtol 1e-10 of ||F(0)||), so they
    agree to round-off amplified by the conditioning, as the cold peers above; every
    level converges, and the finest in no more Newton steps than the cold start."""
    from coupling.manufactured import manufactured_problem, square_contact
    from fem_py.forms import make_material

    def coarse():
        return manufactured_problem(
            COMM, square_contact(), make_material("carstensen"), cells=8, d_over_h=2
        )

    ref = baselines.solve_project(small_problem, "ssn", tol=1e-12)
    cold = baselines.solve_snes_vi(small_problem, linear_solver="substructuring", rtol=1e-10)
    assert ref.converged and cold.converged
    for linear_solver in ("substructuring", "mumps-cholesky"):
        run = baselines.solve_snes_vi_sequenced(
            small_problem, [coarse], linear_solver=linear_solver, rtol=1e-10
        )
        assert run.converged, run.reason
        levels = run.details["levels"]
        assert [lv["dofs"] for lv in levels] == [81, 289]
        assert all(lv["converged"] for lv in levels)
        assert levels[-1]["iterations"] == run.iterations <= cold.iterations
        assert np.linalg.norm(run.u - ref.u) <= 1e-9 * np.linalg.norm(ref.u)
        assert np.linalg.norm(run.phi - ref.phi) <= 1e-8 * np.linalg.norm(ref.phi)
        assert np.all(run.phi >= 0.0)
        assert run.setup >= 0.0 and run.solve > sum(lv["time"] for lv in levels[:-1])


def test_budget_stops_a_solver(small_problem):
    run = baselines.solve_tao(small_problem, "blmvm", gttol=1e-30, budget=0.2)
    assert not run.converged and "budget" in run.reason


def test_quick_benchmark_solvers_agree(tmp_path, capsys):
    code = bench_main(["--quick", "--json", "--out", str(tmp_path)])
    result = json.loads(capsys.readouterr().out)
    solves = [r for r in result["records"] if r["type"] == "solve"]
    assert not [r for r in result["records"] if r["type"] == "crash"]
    names = {r["solver"] for r in solves}
    assert {
        "pgpm",
        "apgpm",
        "ssn",
        "snes-substructuring",
        "snes-mumps-cholesky",
        "snes-seq-substructuring",
        "snes-seq-mumps-cholesky-deep",
        "tao-bnls",
        "poisson",
    } <= names
    sizes = sorted({r["dofs"] for r in solves})
    assert sizes[0] >= 1e4 and sizes[-1] >= 4e4
    for r in solves:
        assert r["status"] == "ok", (r["problem"], r["dofs"], r["solver"], r.get("reason"))
        if r["solver"] not in ("pgpm", "poisson"):
            assert r["du"] <= TOL_U and r["dphi"] <= TOL_PHI
    assert code == 0
    assert (tmp_path / "peers.png").stat().st_size > 0
    assert "| / (a) |" in (tmp_path / "results.md").read_text()


def test_benchmark_refuses_mpirun():
    from conftest import run_mpi

    proc = run_mpi(2, "-m", "bench.peers", "--quick", check=False, timeout=120)
    assert proc.returncode == 2
    assert "serial" in proc.stderr and "without mpirun" in proc.stderr
