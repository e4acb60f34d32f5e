"""mpirun -n 2: solve on a disk read from a .msh file (tests/test_own_mesh.py) and write
the iteration count and the gap phi (replicated on every rank) to a JSON file."""
import json
import sys

from mpi4py import MPI

from coupling.options import SolverOptions
from coupling.problem import SignoriniProblem
from coupling.solvers import solve
from fem_py.forms import make_material
from fem_py.mesh import GeometrySpec, build_domain

comm = MPI.COMM_WORLD
domain = build_domain(
    comm, GeometrySpec(mesh=sys.argv[1], subdomain_size=0.16, signorini=["contact"])
)
problem = SignoriniProblem(domain, make_material("carstensen"), f="2", t0="-1")
result = solve(problem, SolverOptions(tol=1e-10))
if comm.rank == 0:
    with open(sys.argv[2], "w") as f:
        json.dump({"iterations": result.iterations, "phi": [float(v) for v in result.phi]}, f)
