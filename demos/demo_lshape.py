# %% [markdown]
# # An L-shaped domain with two Signorini arcs
#
# Omega is the square [-1/4, 1/4]^2 without its upper-right quarter. Two parts of
# Gamma carry the Signorini condition (1.5): the bottom side, and the bottom side of
# the notch, y = 0 from (1/4, 0) to (0, 0) - both given as pairs of boundary points in
# counter-clockwise order, as in the `signorini` key of a configuration (the side
# names "bottom" and "notch_bottom" would do the same). The rest of Gamma is a
# transmission boundary (1.4).
#
# The manufactured solution :func:`coupling.manufactured.lshape_contact` (Carstensen
# material) has contact on the left half of the bottom arc (x < 0) and on the half of
# the notch arc away from the re-entrant corner (x > 1/8). The demo solves it, prints
# the errors and the computed contact set of each arc next to the exact one, and
# writes the figures.
#
# Run: `python demos/demo_lshape.py [--cells N] [--out DIR]` (N cells per side of the
# square; the figures, fields and results.json go to DIR, default out/demo_lshape).

# %%
from mpi4py import MPI

from common import (
    OUTPUTS_HELP,
    begin_demo,
    outcome,
    write_solve_outputs,
)
from coupling.manufactured import lshape_contact, manufactured_problem, solution_errors
from coupling.options import SolverOptions
from coupling.solvers import solve
from fem_py.forms import make_material

description = "L-shaped domain with two Signorini arcs."
comm = MPI.COMM_WORLD
args, say = begin_demo(comm, "demo_lshape", description, cells=128, out_help=OUTPUTS_HELP)

# %% [markdown]
# ## Solve
#
# The arc end points are corners of the coarse partition (subdomains of size d = 4h),
# as the substructuring preconditioner requires (docs/method.md section 6); the L-shape's
# corners and the arcs' ends lie on the coarse grid for any `cells` divisible by 8.

# %%
solution = lshape_contact()
material = make_material("carstensen")
for k, arc in enumerate(solution.arcs):
    say(f"Signorini arc {k}: {arc.start} -> {arc.end}, exact gap {arc.gap}")
problem = manufactured_problem(comm, solution, material, cells=args.cells)
options = SolverOptions()  # the defaults: ssn with the substructuring B
result = solve(problem, options)
errors = solution_errors(problem, solution, result)
say(
    f"\nh = {0.5 / args.cells:.4g}, {problem.V.dofmap.index_map.size_global} dofs, "
    f"{problem.n_signorini} Signorini nodes: {outcome(result, options.method)}"
)
say(
    f"|u - u_h|_1 = {errors['energy']:.3e}   max |u - u_h| = {errors['nodal_u']:.3e}   "
    f"max |gap error| = {errors['gap']:.3e}   max |u_e error| outside = "
    f"{errors['ue_exterior']:.3e}"
)

# %% [markdown]
# ## The contact set of each arc
#
# The computed contact set {phi_h = 0} of each arc is printed as the x-interval of its
# nodes in contact; `solution_errors` counts the nodes whose state differs from the
# exact one away from the switch points (there both the gap and the multiplier vanish
# like |x - x_switch|^3, so the state of the closest nodes is not decided by the mesh).

# %%
boundary = problem.boundary
nodes = boundary.nodes[boundary.signorini]
exact_contact = solution.exact_gap(nodes) <= 0
arcs = []
for k in range(len(solution.arcs)):
    on = boundary.arc_of_signorini == k
    x_c, x_e = nodes[on & result.contact, 0], nodes[on & exact_contact, 0]
    arcs.append(
        dict(
            arc=k,
            nodes=int(on.sum()),
            contact=int((on & result.contact).sum()),
            computed=[float(x_c.min()), float(x_c.max())],
            exact=[float(x_e.min()), float(x_e.max())],
        )
    )
    say(
        f"arc {k}: {arcs[-1]['contact']:3d} of {arcs[-1]['nodes']:3d} nodes in contact, "
        f"x in [{x_c.min():+.4f}, {x_c.max():+.4f}]  (exact nodes: "
        f"[{x_e.min():+.4f}, {x_e.max():+.4f}])"
    )
say(f"nodes in the wrong state away from the switch points: {errors['contact_mismatch']}")

# %%
out = args.out
results = dict(
    cells=args.cells,
    converged=bool(result.converged),
    iterations=int(result.iterations),
    errors=errors,
    arcs=arcs,
)
files = write_solve_outputs(comm, out, problem, result, options, results)
say(f"\nplots:  {', '.join(str(out / f) for f in files if f.endswith('.png'))}")
say(f"fields: {out / 'fields.npz'}, numbers: {out / 'results.json'}")
