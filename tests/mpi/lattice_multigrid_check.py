"""One V-cycle of the geometric multigrid of a vertex lattice
(coupling/preconditioners/lattice_multigrid.py) applied on any number of ranks to
g = sin(3x + 2y + z) (component k: sin(3x + 2y + z + k)) at the nodes: rank 0 writes the
result at the nodes sorted by their coordinates (independent of the partition) to argv[1],
and the levels' Gershgorin bounds. argv[2]: cells per side; argv[3] (optional, default
"box"): "box" (the scalar K + c M_Gamma on the box), "elastic-box" or "elastic-square"
(the linear elastic stiffness, E = 2.5, nu = 0.25, plus c M_Gamma on the vector P1 space)."""
import sys

import numpy as np
from mpi4py import MPI

from coupling.options import AMG_MAX_ITERATIONS, AMG_RTOL
from coupling.preconditioners.lattice_multigrid import gershgorin_bound
from coupling.preconditioners.multigrid import MultigridPreconditioner
from fem_py.forms.elasticity import linear_elastic
from fem_py.mesh import GeometrySpec, build_domain

comm = MPI.COMM_WORLD
n = int(sys.argv[2])
case = sys.argv[3] if len(sys.argv) > 3 else "box"
if case.endswith("square"):
    spec = GeometrySpec("square", h=0.5 / n, subdomain_size=0.125, signorini=["bottom"])
else:
    spec = GeometrySpec("box", width=1.0, h=1.0 / n, signorini=["bottom"])
domain = build_domain(comm, spec)
from dolfinx import fem  # noqa: E402  (after the domain: the same import order as the app)

elastic = case.startswith("elastic")
dim = domain.dim
if elastic:
    V = fem.VectorFunctionSpace(domain.mesh, ("CG", 1))
    stiffness = linear_elastic(2.5, 0.25, dim).stiffness_integrand
else:
    V, stiffness = fem.FunctionSpace(domain.mesh, ("CG", 1)), None
B = MultigridPreconditioner(
    V,
    0.7,
    np.zeros((0, 0)),
    lattice=domain.lattice,
    rtol=AMG_RTOL,
    max_iterations=AMG_MAX_ITERATIONS,
    stiffness=stiffness,
)
assert B._hierarchy is not None  # the lattice's multigrid, not GAMG
owned = V.dofmap.index_map.size_local
x = V.tabulate_dof_coordinates()[:owned]
components = V.dofmap.index_map_bs
phase = 3 * x[:, 0] + 2 * x[:, 1] + x[:, 2]
g = np.sin(phase[:, None] + np.arange(components)).ravel()  # node-major, as V's dofs
cycle = B.cycle_omega(g).reshape(-1, components)
bounds = [gershgorin_bound(op) for op in B._hierarchy.operators]
parts = comm.gather((x, cycle), root=0)
B.destroy()
if comm.rank == 0:
    x = np.concatenate([p[0] for p in parts])
    cycle = np.concatenate([p[1] for p in parts])
    order = np.lexsort(np.round(x, 12).T[::-1])
    np.savez(sys.argv[1], cycle=cycle[order], bounds=np.array(bounds))
