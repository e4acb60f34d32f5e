"""Iteration counts of the elastic contact problem as h -> 0 (docs/design/elasticity.md).

The manufactured case of coupling/manufactured_elastic.py (a Hencky body, "slip" on the
bottom face, a Kelvin point force and a translation outside) on the square with 8 to 64
cells per side and on the box with 4 to 16 cubes per side: ssn's Newton steps and CG
iterations per Newton step, pgpm's and apgpm's iterations (tol 1e-8, the amg
preconditioner: the lattice's geometric multigrid on the square and on the box from 8 cubes
per side, GAMG with the rigid-body modes on the 4^3 box; M_s = E^T W_L E), and the nodal
error.

    .venv/bin/python bench/elastic_counts.py [--dims 2 3] [--max-2d 64] [--max-3d 16]
"""
from __future__ import annotations

import argparse
import time

import numpy as np
from mpi4py import MPI

from coupling.manufactured_elastic import elastic_contact
from coupling.options import SolverOptions
from coupling.problem import SignoriniProblem
from coupling.solvers import solve
from fem_py.forms.elasticity import hencky
from fem_py.mesh import GeometrySpec, build_domain


def run(dim: int, n: int) -> dict:
    """The counts of one mesh."""
    comm = MPI.COMM_WORLD
    if dim == 2:
        spec = GeometrySpec("square", h=0.5 / n, subdomain_size=0.125, signorini=["bottom"])
    else:
        spec = GeometrySpec("box", h=0.5 / n, width=0.5, signorini=["bottom"])
    domain = build_domain(comm, spec)
    material = hencky(2.0, "1 + 1/(1 + s)", dim)
    case = elastic_contact(domain.mesh, material)
    tic = time.perf_counter()
    problem = SignoriniProblem(
        domain,
        material,
        **case.data,
        tangential="slip",
    )
    row = {"dim": dim, "n": n, "dofs": problem.V.dofmap.index_map.size_global * dim}
    row["gaps"], row["S_h"] = problem.n_signorini, problem.boundary_operator
    row["assembly"] = time.perf_counter() - tic
    for method in ("ssn", "pgpm", "apgpm"):
        tic = time.perf_counter()
        solution = solve(problem, SolverOptions(method=method, nested=False))
        row[f"{method}_seconds"] = time.perf_counter() - tic
        row[method] = solution.iterations
        if method == "ssn":
            cg = [r.cg_iterations for r in solution.history if r.cg_iterations]
            row["newton"], row["cg_per_newton"] = len(cg), float(np.mean(cg)) if cg else 0.0
            owned = problem.V.dofmap.index_map.size_local
            x = problem.V.tabulate_dof_coordinates()[:owned, :dim]
            u_h = solution.u.x.array[: owned * dim].reshape(-1, dim)
            error = np.abs(u_h - case.u(x)).max()
            row["error"] = comm.allreduce(error, op=MPI.MAX)
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dims", type=int, nargs="+", default=[2, 3])
    parser.add_argument("--max-2d", type=int, default=64)
    parser.add_argument("--max-3d", type=int, default=16)
    args = parser.parse_args()
    sizes = {2: [8, 16, 32, 64], 3: [4, 8, 16]}
    limits = {2: args.max_2d, 3: args.max_3d}
    header = (
        "| d | cells/side | dofs | gap unknowns | S_h | ssn steps (Newton) | CG per Newton step "
        "| pgpm | apgpm | nodal error | ssn s |"
    )
    print(header)
    print("|---" * 11 + "|")
    for dim in args.dims:
        for n in (n for n in sizes[dim] if n <= limits[dim]):
            r = run(dim, n)
            if MPI.COMM_WORLD.rank == 0:
                print(
                    f"| {dim} | {n} | {r['dofs']:,} | {r['gaps']} | {r['S_h']} | {r['ssn']} "
                    f"({r['newton']}) | {r['cg_per_newton']:.1f} | {r['pgpm']} | {r['apgpm']} "
                    f"| {r['error']:.2e} | {r['ssn_seconds']:.1f} |",
                    flush=True,
                )


if __name__ == "__main__":
    main()
