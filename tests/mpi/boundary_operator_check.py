"""Solve the manufactured contact problem on the square with the S_h of
``[solver] boundary_operator`` argv[4] and save what rank 0 gathers (iterations, energy,
u at the nodes sorted by coordinates, phi, the flux, the class of S_h) to the .npz in
argv[1]; argv[2] cells per side, argv[3] the method."""
import sys

from mpi4py import MPI

from coupling.manufactured import manufactured_problem, square_contact
from coupling.options import SolverOptions
from coupling.solvers import solve
from fem_py.forms import make_material
from saved import save_solve

comm = MPI.COMM_WORLD
cells, method, kind = int(sys.argv[2]), sys.argv[3], sys.argv[4]
problem = manufactured_problem(
    comm, square_contact(), make_material("carstensen"), cells=cells, boundary_operator=kind
)
result = solve(problem, SolverOptions(method=method, tol=1e-10, boundary_operator=kind))
# bytes of S_h on rank 0, and of the serial operator of the same boundary (H-matrix only)
nbytes = {}
if kind == "hmatrix":
    import bem_cpp
    from coupling.options import HMATRIX_TOL

    serial = bem_cpp.steklov_poincare(
        problem.boundary.nodes, problem.flux_space, compression="hmatrix", tol=HMATRIX_TOL
    )
    nbytes = dict(distributed_bytes=problem.S.nbytes, serial_bytes=serial.nbytes)
save_solve(
    comm,
    sys.argv[1],
    result,
    flux=result.flux,
    operator_class=type(problem.S).__name__,
    boundary_operator=problem.boundary_operator,
    **nbytes,
)
