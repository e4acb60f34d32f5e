# %% [markdown]
# # The linear transmission problem with a known solution
#
# The simplest case of the coupled problem (docs/method.md section 1): rho = 1 (the
# Laplace equation inside), no Signorini part (Gamma_t = Gamma), so (1.1)-(1.4) read
#
#     -Laplace u = f  in Omega,   Laplace u_e = 0 outside,   u_e = a + b log|x| + o(1),
#     u = u_e + u0,   du/dn = du_e/dn + t0   on Gamma.
#
# We pick u and u_e and compute f, u0 and t0 from them (a "manufactured" solution,
# :class:`coupling.manufactured.ManufacturedSolution` with no Signorini arc), solve on
# three meshes and print the errors: the energy error |u - u_h|_1 falls like h, the
# nodal errors of u_h and the error of u_e (evaluated outside by the representation
# formula of docs/method.md section 2) like h^2.
#
# Without contact J_h is a quadratic functional: PGPM would be a preconditioned
# Richardson iteration for the FEM-BEM system (K + T^T S_h T) u = b, and the default
# solver (`ssn`) solves that system by CG preconditioned with the substructuring B
# after its 5 PGPM start steps.
#
# Run: `python demos/demo_linear_transmission.py [--cells N] [--out DIR]` (N: finest mesh;
# results.json goes to DIR, default out/demo_linear_transmission).

# %%
import numpy as np
from mpi4py import MPI

from common import begin_demo, solve_row, write_results
from coupling.manufactured import (
    ManufacturedSolution,
    exterior_field,
    manufactured_problem,
    solution_errors,
)
from coupling.options import SolverOptions
from coupling.solvers import solve
from fem_py.forms import make_material

description = "Linear transmission problem, known solution."
cells_help = "cells per side of the finest mesh; the others have N/2, N/4"
comm = MPI.COMM_WORLD
args, say = begin_demo(
    comm, "demo_linear_transmission", description, cells=128, cells_help=cells_help
)

# %% [markdown]
# ## The exact solution
#
# u is smooth with a non-zero Laplacian; u_e has a logarithmic term (b = 0.1) and a
# dipole centred inside Omega, so it is harmonic outside and decays to a = 0.5 plus
# b log|x|. The data f, t0 are UFL expressions of the mesh (exact at the quadrature
# points); u0 = u - u_e is interpolated at the boundary nodes.

# %%
solution = ManufacturedSolution(
    shape="square",
    width=0.5,
    center=(0.0, 0.0),
    arcs=(),
    u="0.5 + x + 2*y + sin(pi*x)*cos(pi*y) + x*y^2",
    ue=exterior_field((0.03, -0.02)),
)
material = make_material("linear")
say(f"u   = {solution.u}\nu_e = {solution.ue}")

# %% [markdown]
# ## Three meshes at fixed d/h = 4
#
# Each mesh is a new problem; the solver options (here the defaults) are the same.

# %%
options = SolverOptions()
rows = []
for cells in (args.cells // 4, args.cells // 2, args.cells):
    problem = manufactured_problem(comm, solution, material, cells=cells)
    result = solve(problem, options)
    errors = solution_errors(problem, solution, result)
    rows.append(solve_row(cells, result, **errors))

say(
    f"\n{'h':>9} {'its':>5} {'|u-u_h|_1':>10} {'rate':>5} {'max|u-u_h|':>10} {'rate':>5} "
    f"{'max|ue err|':>11} {'rate':>5}"
)
rates = {"energy": [], "nodal_u": [], "ue_exterior": []}
for i, r in enumerate(rows):
    line = f"{r['h']:9.3e} {r['iterations']:5d}"
    for key in rates:
        rate = np.log2(rows[i - 1][key] / r[key]) if i else float("nan")
        if i:
            rates[key].append(rate)
        line += f" {r[key]:10.3e} {rate:5.2f}"
    say(line)
say("expected rates: 1 (energy norm), 2 (nodal values), 2 (u_e at exterior points)")

# %%
path = write_results(comm, args.out, dict(rows=rows, rates=rates))
say(f"numbers in {path}")
