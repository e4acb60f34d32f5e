"""One V-cycle of the box's geometric multigrid (coupling/preconditioners/lattice_multigrid.py)
applied on any number of ranks to g = sin(3x + 2y + z) at the nodes: rank 0 writes the
result at the nodes sorted by their coordinates (independent of the partition) to argv[1],
and the levels' Gershgorin bounds. argv[2]: cubes per side of the box."""
import sys

import numpy as np
from mpi4py import MPI

from coupling.options import AMG_MAX_ITERATIONS, AMG_RTOL
from coupling.preconditioners.lattice_multigrid import gershgorin_bound
from coupling.preconditioners.multigrid import MultigridPreconditioner
from fem_py.mesh import GeometrySpec, build_domain

comm = MPI.COMM_WORLD
n = int(sys.argv[2])
domain = build_domain(comm, GeometrySpec("box", width=1.0, h=1.0 / n, signorini=["bottom"]))
from dolfinx import fem  # noqa: E402  (after the domain: the same import order as the app)

V = fem.FunctionSpace(domain.mesh, ("CG", 1))
B = MultigridPreconditioner(
    V,
    0.7,
    np.zeros((0, 0)),
    lattice=domain.lattice,
    rtol=AMG_RTOL,
    max_iterations=AMG_MAX_ITERATIONS,
)
owned = V.dofmap.index_map.size_local
x = V.tabulate_dof_coordinates()[:owned]
cycle = B.cycle_omega(np.sin(3 * x[:, 0] + 2 * x[:, 1] + x[:, 2]))
bounds = [gershgorin_bound(op) for op in B._hierarchy.operators]
parts = comm.gather((x, cycle), root=0)
B.destroy()
if comm.rank == 0:
    x = np.concatenate([p[0] for p in parts])
    cycle = np.concatenate([p[1] for p in parts])
    order = np.lexsort(np.round(x, 12).T[::-1])
    np.savez(sys.argv[1], cycle=cycle[order], bounds=np.array(bounds))
