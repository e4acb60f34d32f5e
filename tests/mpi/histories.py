"""Solve manufactured contact problems with pgpm and the default method and save the
whole histories (C0, tau, J_h and the step norm of every iteration), phi and u in the
input numbering to the .npz in argv[1] (rank 0)."""
import sys

import numpy as np
from mpi4py import MPI

from coupling.io.outputs import gather_p1
from coupling.manufactured import MANUFACTURED, manufactured_problem
from coupling.options import SolverOptions
from coupling.solvers import solve
from fem_py.forms import make_material

comm = MPI.COMM_WORLD
out = {}
for case, structured in (("square", True), ("lshape", False)):
    problem = manufactured_problem(
        comm, MANUFACTURED[case](), make_material("carstensen"), cells=32, structured=structured
    )
    for method in ("pgpm", SolverOptions().method):
        result = solve(problem, SolverOptions(method=method))
        gathered = gather_p1(result.u)
        key = f"{case}_{method}"
        out[f"{key}_C0"] = result.C0
        out[f"{key}_history"] = np.array(
            [[r.energy, r.step_norm, r.tau, r.contact] for r in result.history]
        )
        out[f"{key}_phi"] = result.phi
        if comm.rank == 0:
            out[f"{key}_x"], out[f"{key}_u"], out[f"{key}_triangles"] = gathered
if comm.rank == 0:
    np.savez(sys.argv[1], **out)
