"""A body pressed onto its bottom face, solved by ssn with the preconditioner argv[3] on
any number of ranks; rank 0 writes the iterations, phi and u at the nodes sorted by their
coordinates (independent of the partition) to argv[1]. argv[2]: "box" (the box, 8 cubes
per side, tilted: u0 = x, so that part of the bottom face leaves contact; the amg
preconditioner's multigrid is the geometric one of its lattice) or "ball" (the gmsh ball of
radius 1/4 with h = 1/8, u0 = x; GAMG)."""
import sys

import numpy as np
from mpi4py import MPI

from coupling.options import SolverOptions
from coupling.problem import SignoriniProblem
from coupling.solvers import solve
from fem_py.forms import make_material
from fem_py.mesh import GeometrySpec, build_domain

comm = MPI.COMM_WORLD
shape = sys.argv[2]
sizes = {"box": {"width": 0.5, "h": 0.0625}, "ball": {"radius": 0.25, "h": 0.125}}[shape]
domain = build_domain(comm, GeometrySpec(shape, signorini=["bottom"], **sizes))
problem = SignoriniProblem(
    domain, make_material("carstensen"), f="1", t0="-1", u0="x", boundary_operator="dense"
)
solution = solve(problem, SolverOptions(preconditioner=sys.argv[3], nested=False))
owned = problem.V.dofmap.index_map.size_local
x = problem.V.tabulate_dof_coordinates()[:owned]
parts = comm.gather((x, solution.u.x.array[:owned].copy()), root=0)
if comm.rank == 0:
    x = np.concatenate([p[0] for p in parts])
    u = np.concatenate([p[1] for p in parts])
    order = np.lexsort(np.round(x, 12).T[::-1])
    np.savez(sys.argv[1], u=u[order], phi=solution.phi, iterations=solution.iterations)
