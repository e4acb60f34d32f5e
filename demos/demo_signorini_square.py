# %% [markdown]
# # Nonlinear Signorini contact on a square (the main demo)
#
# This demo solves the coupled problem of docs/method.md section 1: a nonlinear equation
# in the square Omega = [-1/4, 1/4]^2, the Laplace equation in the unbounded exterior,
# transmission conditions on Gamma and a unilateral (Signorini) contact condition on
# the bottom side Gamma_s:
#
#     -div(rho(|grad u|) grad u) = f                    in Omega          (1.1)
#     Laplace u_e = 0,  u_e = a + b log|x| + o(1)       outside           (1.2)-(1.3)
#     u = u_e + u0,  rho du/dn = du_e/dn + t0           on Gamma_t        (1.4)
#     u <= u_e + u0,  rho du/dn = du_e/dn + t0 <= 0,
#     (u_e + u0 - u) rho du/dn = 0                       on Gamma_s        (1.5)
#
# with the material of Carstensen, rho(t) = 2 + 1/(1 + t). The data come from a
# manufactured solution (docs/method.md section 8, :mod:`coupling.manufactured`) whose gap
# u_e + u0 - u vanishes exactly on the left half of Gamma_s: the contact set is known,
# so the demo can print the errors of u_h, of the gap phi_h, of u_e and of the
# computed contact set.
#
# The discrete problem minimises the convex functional J_h(u, phi) over phi >= 0. The
# default solver is our semismooth Newton method (`method = "ssn"`): 5 steps of the
# paper's preconditioned projection-gradient method (Algorithm 3.1), then Newton steps
# whose linear systems are solved by CG preconditioned with the substructuring
# preconditioner of section 4 (subdomains of size d = 4h here). Set
# `options = SolverOptions(method="pgpm")` below for the paper's method alone (about 190
# iterations here). On each mesh `solve_manufactured` (demos/common.py) assembles the
# problem once (`coupling.manufactured.manufactured_problem` returns a
# `coupling.problem.SignoriniProblem`) and `coupling.solvers.solve(problem, options)` solves it.
#
# Run it with `make demo` or `python demos/demo_signorini_square.py [--cells N] [--out DIR]`
# (the figures, fields and results.json go to DIR, default out/demo_signorini_square).

# %%
import numpy as np
from mpi4py import MPI

from common import (
    OUTPUTS_HELP,
    begin_demo,
    solve_manufactured,
    write_solve_outputs,
)
from coupling.manufactured import square_contact
from coupling.options import SolverOptions
from fem_py.forms import make_material

description = (
    "Nonlinear Signorini contact on a square (manufactured solution with a known contact set)."
)
comm = MPI.COMM_WORLD
args, say = begin_demo(comm, "demo_signorini_square", description, cells=128, out_help=OUTPUTS_HELP)

# %% [markdown]
# ## The material and the exact solution
#
# `make_material` derives the energy density g(t) = int_0^t s rho(s) ds and rho'
# symbolically and checks the structure condition of docs/method.md section 1 on
# t in [0, 1e3]; alpha and beta are the measured bounds of d(t rho(t))/dt.

# %%
material = make_material("carstensen")
solution = square_contact()
say(
    f"material rho(t) = {material.rho_sym}: alpha = {material.alpha:.3f}, "
    f"beta = {material.beta:.3f}"
)
say(f"exact u   = {solution.u}")
say(f"exact u_e = {solution.ue}")
say(
    f"Signorini arc {solution.arcs[0].start} -> {solution.arcs[0].end}: "
    f"exact gap {solution.arcs[0].gap}, contact exactly where x < 0"
)

# %% [markdown]
# ## Two mesh sizes at fixed d/h = 4
#
# The energy error |u - u_h|_1 is O(h) (docs/method.md section 7, item 5) and the iteration
# count does not grow at fixed d/h (Theorem 4.1). `solution_errors` also counts the
# Signorini nodes whose contact state differs from the exact one away from the two
# points where the exact contact set switches.

# %%
options = SolverOptions()  # the defaults: ssn, substructuring B, tol = 1e-8
meshes = (args.cells // 2, args.cells)
rows, problem, result = solve_manufactured(comm, solution, material, meshes, options)

say(
    f"\n{'h':>9} {'dofs':>7} {'its':>5} {'|u-u_h|_1':>10} {'max|u-u_h|':>10} "
    f"{'max|gap err|':>12} {'max|ue err|':>11} {'contact':>9} {'wrong':>5} {'time':>6}"
)
for r in rows:
    say(
        f"{r['h']:9.3e} {r['dofs']:7d} {r['iterations']:5d} {r['energy']:10.3e} "
        f"{r['nodal_u']:10.3e} {r['gap']:12.3e} {r['ue_exterior']:11.3e} "
        f"{r['contact_nodes']:4d}/{r['signorini_nodes']:<4d} {r['contact_mismatch']:5d} "
        f"{r['seconds']:5.1f}s"
    )
rate = np.log2(rows[0]["energy"] / rows[1]["energy"])
say(f"energy-norm convergence rate: {rate:.2f} (theory: 1)")

# %% [markdown]
# ## Outputs of the finer run
#
# `write_solve_outputs` (demos/common.py, with `coupling.io.outputs.write_outputs`) writes
# what `fembem solve` writes: summary.json (with the seconds of every stage of the
# assembly and of the solve), fields.npz, solution.xdmf (open it in ParaView) and the PNG
# figures.

# %%
out = args.out
files = write_solve_outputs(comm, out, problem, result, options, dict(rows=rows, energy_rate=rate))
say(f"\nplots:  {', '.join(str(out / f) for f in files if f.endswith('.png'))}")
say(f"fields: {out / 'fields.npz'} (u on the mesh; gap, u_e, du_e/dn, contact set on Gamma)")
say(f"        {out / 'solution.xdmf'} (u_h and the subdomains, for ParaView)")
say(f"errors: {out / 'results.json'}")
