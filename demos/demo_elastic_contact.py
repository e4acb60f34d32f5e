# %% [markdown]
# # Elastic contact with a known contact set: the error table
#
# The elastic problem of docs/method.md section 12 with an exact solution: a Hencky square
# [-1/4, 1/4]^2 (bulk modulus 2, shear modulus mu(s) = 1 + 1/(1 + s)) in an unbounded
# elastic medium (E = 1.5, nu = 0.3), in frictionless unilateral contact on its bottom
# side (`tangential = "slip"`), bonded elsewhere.
#
# **The exact solution** (`coupling.manufactured_elastic`). With s = y + 1/4 the distance
# from the bottom side,
#
#     u = r + s^2 v + s w(x) e_y,      w(x) = -20 max(0, -x)^3,
#
# r a rigid motion and v smooth: on the bottom side eps(u) = w e_y e_y, so the tangential
# traction vanishes there (frictionless) and the contact pressure -n.sigma(u)n > 0 exactly
# where x < 0. The gap is normal, phi = 100 max(0, x)^3 (1/4 - x), > 0 exactly where
# x > 0: the contact set is {x < 0} on the bottom side. Outside, a translation and a
# Kelvin point force from inside the body: u_e = a + U(x - x0) F. The data f, t0 and u0
# follow from u, u_e and the gap (f = -div sigma(u), t0 = sigma(u) n - sigma_e(u_e) n,
# u0 = u - u_e + phi n).
#
# The demo solves it on three meshes and prints the nodal errors of u_h and of the gap,
# the slip (its exact value is 0) and how many nodes of the bottom side farther than h
# from x = 0 have the wrong contact state.
#
# Run: `python demos/demo_elastic_contact.py [--cells N] [--out DIR]` (N cells per side
# on the finest mesh, N/4 and N/2 on the others), or under `mpirun -n 2`: the numbers are
# the same.

# %%
import time

import numpy as np
from mpi4py import MPI

from common import OUTPUTS_HELP, begin_demo, write_solve_outputs
from coupling.manufactured_elastic import elastic_contact
from coupling.options import SolverOptions
from coupling.problem import SignoriniProblem
from coupling.solvers import solve
from fem_py.forms.elasticity import hencky
from fem_py.mesh import GeometrySpec, build_domain

description = "Elastic contact with a known contact set: errors over three meshes."
cells_help = "cells per side of the finest square mesh (h = 0.5/cells)"
comm = MPI.COMM_WORLD
args, say = begin_demo(
    comm,
    "demo_elastic_contact",
    description,
    cells=64,
    cells_help=cells_help,
    out_help=OUTPUTS_HELP,
)

# %% [markdown]
# ## Three meshes
#
# The errors are the largest over the nodes (gathered over the ranks): of u_h, of the
# normal gap and of the slip at the Signorini nodes. The slip's exact value is 0.

# %%
material = hencky(2.0, "1 + 1/(1 + s)", 2)
options = SolverOptions(tol=1e-10)
rows = []
for cells in (args.cells // 4, args.cells // 2, args.cells):
    tic = time.perf_counter()
    spec = GeometrySpec("square", h=0.5 / cells, subdomain_size=0.125, signorini=["bottom"])
    domain = build_domain(comm, spec)
    case = elastic_contact(domain.mesh, material)
    problem = SignoriniProblem(domain, material, **case.data, tangential="slip")
    result = solve(problem, options)
    owned = problem.V.dofmap.index_map.size_local
    x = problem.V.tabulate_dof_coordinates()[:owned, :2]
    error = np.abs(result.u.x.array[: 2 * owned].reshape(-1, 2) - case.u(x)).max()
    faces = problem.boundary.nodes[problem.boundary.signorini]
    gap = result.phi[problem.gap.bounded]
    away = np.abs(faces[:, 0]) > 0.5 / cells
    rows.append(
        dict(
            cells=cells,
            h=0.5 / cells,
            dofs=problem.n_dofs,
            converged=bool(result.converged),
            iterations=int(result.iterations),
            nodal_u=float(comm.allreduce(error, op=MPI.MAX)),
            gap=float(np.abs(gap - case.gap(faces)).max()),
            slip=float(np.abs(result.phi[~problem.gap.bounded]).max()),
            contact_nodes=int(np.count_nonzero(result.contact)),
            signorini_nodes=int(faces.shape[0]),
            contact_mismatch=int(np.count_nonzero(result.contact[away] != (faces[away, 0] < 0))),
            seconds=time.perf_counter() - tic,
        )
    )

say(
    f"\n{'h':>9} {'dofs':>6} {'its':>4} {'max|u-u_h|':>11} {'gap error':>10} {'slip':>10} "
    f"{'contact':>8} {'wrong':>5} {'time':>6}"
)
for r in rows:
    say(
        f"{r['h']:9.3e} {r['dofs']:6d} {r['iterations']:4d} {r['nodal_u']:11.3e} "
        f"{r['gap']:10.3e} {r['slip']:10.3e} {r['contact_nodes']:3d}/{r['signorini_nodes']:<4d} "
        f"{r['contact_mismatch']:5d} {r['seconds']:5.1f}s"
    )
rates = {
    key: [float(np.log2(a[key] / b[key])) for a, b in zip(rows, rows[1:])]
    for key in ("nodal_u", "gap", "slip")
}
for key, values in rates.items():
    say(f"rate of {key:>8}: {', '.join(f'{v:.2f}' for v in values)}")

# %% [markdown]
# ## Outputs of the finest run
#
# What `fembem solve` writes: summary.json, fields.npz, solution.xdmf and the figures
# (deformed.png, signorini.png, exterior.png, history.png).

# %%
files = write_solve_outputs(comm, args.out, problem, result, options, dict(rows=rows, rates=rates))
say(f"\nfiles:  {', '.join(sorted(files))} in {args.out} (the errors in results.json)")
