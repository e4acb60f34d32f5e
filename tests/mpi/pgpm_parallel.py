"""Solve the manufactured contact problem on the square and save what rank 0 gathers
(iterations, energy, u at the nodes sorted by coordinates, phi, the class of B) to the
.npz in argv[1]."""
import sys

from mpi4py import MPI

from coupling.manufactured import manufactured_problem, square_contact
from coupling.options import SolverOptions
from coupling.preconditioners import build_preconditioner
from coupling.solvers import solve
from fem_py.forms import make_material
from saved import save_solve

comm = MPI.COMM_WORLD
cells, preconditioner = int(sys.argv[2]), sys.argv[3]
problem = manufactured_problem(comm, square_contact(), make_material("carstensen"), cells=cells)
options = SolverOptions(preconditioner=preconditioner, tol=1e-10)
B = build_preconditioner(problem, options)  # built here to report its class
result = solve(problem, options, preconditioner=B)
B.destroy()
save_solve(comm, sys.argv[1], result, preconditioner_class=type(B).__name__)
