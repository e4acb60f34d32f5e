"""The 3D H-matrix tolerance against the discretisation error (docs/design/three_dimensions.md,
"The boundary operators' accuracy"): the manufactured box (``coupling.manufactured.box_contact``,
exact u, u_e and contact set known) solved by ssn (cold, not nested, tol 1e-8) with S_h
and the potentials built to each of ``--tols``; printed per tol: the set-up and solve
seconds, the ssn steps, the nodal, energy and trace errors, the Signorini nodes off the
exact contact set, and max |u_h(tol) - u_h(first tol)|, next to the tol the solver
chooses at that size (``coupling.options.hmatrix_tol``). No assertions.

    .venv/bin/python bench/boundary_tolerance.py [--cells 32 64] [--tols 1e-7 1e-6 1e-5 3e-5]

About 2 minutes at 32 cubes per side and 15 at 64 (one thread).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

if __package__ in (None, ""):  # run as a script: the repository's root on the path
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import numpy as np  # noqa: E402
from mpi4py import MPI  # noqa: E402

import coupling.options  # noqa: E402
from coupling.manufactured import box_contact, manufactured_problem, solution_errors  # noqa: E402
from coupling.options import SolverOptions  # noqa: E402
from coupling.solvers import solve  # noqa: E402
from fem_py.forms import make_material  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cells", type=int, nargs="+", default=[32, 64])
    parser.add_argument("--tols", type=float, nargs="+", default=[1e-7, 1e-6, 1e-5, 3e-5])
    args = parser.parse_args()
    material, solution = make_material("carstensen"), box_contact()
    options = coupling.options
    saved = options.HMATRIX_TOL_3D_MAX, options.HMATRIX_TOL_3D_SCALE
    for cells in args.cells:
        reference = None
        for tol in args.tols:
            # every H-matrix of the run at this tol (S_h, the potentials): hmatrix_tol
            # reads these two at each call
            options.HMATRIX_TOL_3D_MAX, options.HMATRIX_TOL_3D_SCALE = tol, float("inf")
            tic = time.perf_counter()
            problem = manufactured_problem(MPI.COMM_WORLD, solution, material, cells=cells)
            set_up = time.perf_counter() - tic
            result = solve(problem, SolverOptions())  # one level: cold
            solve_seconds = time.perf_counter() - tic - set_up
            errors = solution_errors(problem, solution, result)
            u = result.u.x.array.copy()
            reference = u if reference is None else reference
            options.HMATRIX_TOL_3D_MAX, options.HMATRIX_TOL_3D_SCALE = saved
            own = options.hmatrix_tol(problem.boundary.nodes)
            print(
                f"cells {cells} (N_Gamma {problem.boundary.n_gamma}, the solver's tol "
                f"{own:.1e}) tol {tol:.0e}: set-up {set_up:.1f} s, "
                f"solve {solve_seconds:.1f} s, {result.iterations} steps, "
                f"nodal {errors['nodal_u']:.4e}, energy {errors['energy']:.4e}, trace "
                f"{errors['ue_gamma']:.4e}, off the contact set {errors['contact_mismatch']}, "
                f"max |u_h - u_h({args.tols[0]:.0e})| {np.abs(u - reference).max():.2e}",
                flush=True,
            )


if __name__ == "__main__":
    main()
