"""Where one PGPM iteration spends its time, at about 2.5e5 dofs.

Prints the time of one iteration split into residual assembly, energy assembly,
S_h product, B^{-1} application and projection, each as a ratio to one residual
assembly measured in the same run (target: one iteration <= 3 residual assemblies).

    .venv/bin/python bench/pgpm_profile.py [--cells 500] [--iterations 50]
"""
from __future__ import annotations

import argparse
import platform
import time

import numpy as np
from mpi4py import MPI

from coupling.manufactured import manufactured_problem, square_contact
from coupling.options import SolverOptions
from coupling.preconditioners import build_preconditioner, create_matrix
from coupling.solvers import solve
from coupling.solvers.projection import SignoriniProjection
from coupling.timing import best_of as _best_of
from fem_py.forms import make_material


def best_of(fn) -> float:
    """Best of 7 wall times (see coupling.timing.best_of)."""
    return _best_of(fn, repeat=7)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, default=500, help="cells per side (default 500)")
    parser.add_argument("--iterations", type=int, default=50)
    args = parser.parse_args()
    comm = MPI.COMM_WORLD

    # tol = 0: exactly --iterations steps of the paper's method
    options = SolverOptions(method="pgpm", max_iterations=args.iterations, tol=0.0)
    tic = time.perf_counter()
    problem = manufactured_problem(
        comm, square_contact(), make_material("carstensen"), cells=args.cells
    )
    built = time.perf_counter()
    matrix = create_matrix(problem, options)  # shared by B and the Jacobians, as in solve()
    pre = build_preconditioner(problem, options, matrix=matrix)  # kept for the parts timed below
    timings = {**problem.timings, "preconditioner": time.perf_counter() - built}
    setup = time.perf_counter() - tic
    result = solve(problem, options, preconditioner=pre, matrix=matrix)
    timings.update(result.timings)
    per_iteration = result.timings["solve"] / result.iterations

    f, u = problem.functional, result.u
    projection = SignoriniProjection.exact(pre.signorini_metric)
    grad = problem.forms.create_vector()
    g_u = grad.array_r.copy()
    g_phi = np.ones(problem.n_signorini)
    parts = {
        "residual assembly": best_of(lambda: problem.forms.assemble_residual(u, grad)),
        "energy assembly": best_of(lambda: problem.forms.energy(u)),
        "S_h product (+ trace)": best_of(lambda: f.S @ f.boundary_block(u.vector, result.phi)),
        "B^-1 (B_Omega^-1, M_s^-1)": best_of(
            lambda: (pre.apply_omega(g_u), pre.apply_signorini(g_phi))
        ),
        "projection (exact)": best_of(lambda: projection(result.phi - 1e-3 * g_phi, result.phi)),
        "J_h and gradient": best_of(lambda: f.value_and_gradient(u, result.phi, grad)),
    }
    assembly = parts["residual assembly"]
    if comm.rank == 0:
        dofs = problem.V.dofmap.index_map.size_global
        print(
            f"# PGPM iteration profile: {dofs} dofs, {problem.boundary.n_gamma} boundary "
            f"dofs, {problem.n_signorini} Signorini dofs, {comm.size} rank(s)"
        )
        print(
            f"# machine: {platform.machine()} {platform.processor() or ''}, "
            f"python {platform.python_version()}; setup {setup:.2f} s "
            f"({', '.join(f'{k} {v:.2f} s' for k, v in timings.items())})"
        )
        print(f"{'part':32s} {'time [ms]':>10s} {'/ residual':>11s}")
        for name, t in parts.items():
            print(f"{name:32s} {1e3 * t:10.2f} {t / assembly:11.2f}")
        print(
            f"{'one PGPM iteration (measured)':32s} {1e3 * per_iteration:10.2f} "
            f"{per_iteration / assembly:11.2f}"
        )
        print(
            f"target: one iteration <= 3 residual assemblies -> "
            f"{'met' if per_iteration <= 3 * assembly else 'MISSED'}"
        )
    grad.destroy()
    pre.destroy()
    matrix.destroy()


if __name__ == "__main__":
    main()
