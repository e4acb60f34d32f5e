"""The manufactured elastic contact problem (coupling/manufactured_elastic.py) solved by ssn
on any number of ranks; rank 0 writes the iterations, the gaps and u at the nodes sorted by
their coordinates (independent of the partition) to argv[1]. argv[2]: the dimension (2: the
square with 16 cells per side, Hencky, "slip"; 3: the box with 4 cubes per side, linear,
"slip"), argv[3]: the S_h ("dense" or "hmatrix"), argv[4] (optional): the box's cubes per
side (4: the amg preconditioner's GAMG; 8: its lattice multigrid, levels 8 and 4; the
square's 16 cells per side are always the lattice's)."""
import sys

import numpy as np
from mpi4py import MPI

from coupling.manufactured_elastic import elastic_contact
from coupling.options import SolverOptions
from coupling.preconditioners.lattice_multigrid import lattice_levels
from coupling.problem import SignoriniProblem
from coupling.solvers import solve
from fem_py.forms.elasticity import hencky, linear_elastic
from fem_py.mesh import GeometrySpec, build_domain

comm = MPI.COMM_WORLD
dim = int(sys.argv[2])
if dim == 2:
    spec = GeometrySpec("square", h=1 / 32, subdomain_size=0.125, signorini=["bottom"])
    material = hencky(2.0, "1 + 1/(1 + s)", 2)
else:
    cubes = int(sys.argv[4]) if len(sys.argv) > 4 else 4
    spec = GeometrySpec("box", h=0.5 / cubes, width=0.5, signorini=["bottom"])
    material = linear_elastic(2.5, 0.25, 3)
domain = build_domain(comm, spec)
case = elastic_contact(domain.mesh, material)
problem = SignoriniProblem(
    domain,
    material,
    **case.data,
    boundary_operator=sys.argv[3],
)
solution = solve(problem, SolverOptions(tol=1e-10))
# the lattice's multigrid on the square and the 8^3 box, GAMG on the 4^3 box
assert (lattice_levels(domain.lattice.n) is not None) == (dim == 2 or cubes > 4)
owned = problem.V.dofmap.index_map.size_local
x = problem.V.tabulate_dof_coordinates()[:owned]
u = solution.u.x.array[: owned * dim].reshape(-1, dim).copy()
parts = comm.gather((x, u), root=0)
if comm.rank == 0:
    x = np.concatenate([p[0] for p in parts])
    u = np.concatenate([p[1] for p in parts])
    order = np.lexsort(np.round(x, 12).T[::-1])
    np.savez(sys.argv[1], u=u[order], phi=solution.phi, iterations=solution.iterations)
