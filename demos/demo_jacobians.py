# %% [markdown]
# # UFL-derived and handwritten Jacobians
#
# The interior energy G(u) = int g(|grad u|) dx (2.1) has the second derivative
#
#     D^2 G(u)(w, v) = int rho^(grad u) grad w . grad v dx,
#     rho^(x) = rho(|x|) I + rho'(|x|) x x^T / |x|                      (4.1)
#
# `fem_py.forms.InteriorForms` offers it twice: derived by UFL (`ufl.derivative` of
# the residual, option `jacobian = "ufl"`, the default) and written out by hand from
# (4.1) (`jacobian = "handwritten"`). This demo, at a nonlinear state (the exact
# solution of the manufactured square problem, where |grad u| ranges over [0.1, 4]):
#
# 1. times the assembly of both matrices (after a first, compiling call);
# 2. compares them entry by entry (relative Frobenius norm of the difference);
# 3. runs the Taylor test of `fembem check-jacobian` (the residual's second-order
#    remainder must fall like eps^2);
# 4. solves the contact problem once with each Jacobian and compares the iterates.
#    The Jacobian enters the solver through the step size tau = 1/C0,
#    C0 = lambda_max(B^-1 D^2 J_h(xi_0)) (docs/method.md section 5), so equal matrices
#    must give the same iterates up to round-off.
#
# Run: `python demos/demo_jacobians.py [--cells N] [--repeat R] [--out DIR]` (results.json
# goes to DIR, default out/demo_jacobians).

# %%
import time

import numpy as np
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from common import demo_parser, start_demo, write_results
from coupling.manufactured import manufactured_problem, square_contact
from coupling.options import SolverOptions
from coupling.solvers import solve
from fem_py.forms import check_jacobian, make_material, numpy_function

parser = demo_parser("demo_jacobians", "UFL-derived against handwritten Jacobians.", cells=256)
parser.add_argument("--repeat", type=int, default=10, help="timed assemblies of each matrix")
comm = MPI.COMM_WORLD
args, say = start_demo(parser, comm)

# %% [markdown]
# ## Assembly at a nonlinear state
#
# The Jacobian is part of the discretisation: each problem is assembled with its own
# (`jacobian=` of `manufactured_problem`, as of `coupling.problem.SignoriniProblem`).

# %%
solution = square_contact()
material = make_material("carstensen")
problems = {
    kind: manufactured_problem(comm, solution, material, cells=args.cells, jacobian=kind)
    for kind in ("ufl", "handwritten")
}
forms = problems["ufl"].forms
V = problems["ufl"].V
state = fem.Function(V)
exact_u = numpy_function(solution.u, ("x", "y"))
state.interpolate(lambda x: exact_u(x[0], x[1]))

matrices, seconds = {}, {}
for kind in ("ufl", "handwritten"):
    A = forms.create_matrix()
    forms.assemble_jacobian(state, A, kind)  # compiles the form on first use
    times = []
    for _ in range(args.repeat):
        tic = time.perf_counter()
        forms.assemble_jacobian(state, A, kind)
        times.append(comm.allreduce(time.perf_counter() - tic, op=MPI.MAX))
    matrices[kind], seconds[kind] = A, float(np.median(times))
reference = matrices["ufl"].norm(PETSc.NormType.FROBENIUS)
matrices["handwritten"].axpy(-1.0, matrices["ufl"])
difference = matrices["handwritten"].norm(PETSc.NormType.FROBENIUS) / reference
for A in matrices.values():
    A.destroy()
say(f"{V.dofmap.index_map.size_global} dofs; median of {args.repeat} assemblies:")
for kind in ("ufl", "handwritten"):
    say(f"  {kind:12s} {1e3 * seconds[kind]:8.2f} ms")
say(f"  ratio handwritten / ufl = {seconds['handwritten'] / seconds['ufl']:.2f}")
say(f"||A_ufl - A_handwritten||_F / ||A_ufl||_F = {difference:.2e}")

# %% [markdown]
# ## The Taylor test of `fembem check-jacobian`
#
# At three smooth random states: r1(eps) = ||F(u + eps du) - F(u)|| ~ eps and
# r2(eps) = ||F(u + eps du) - F(u) - eps J du|| ~ eps^2 (F the residual DG(u, .)).

# %%
report = check_jacobian(problems["ufl"].domain, material)
say(
    f"Taylor slopes of r1: {np.round(report['slope1'], 3).tolist()}, of r2: "
    f"{np.round(report['slope2'], 3).tolist()}; passed: {report['passed']}"
)

# %% [markdown]
# ## The same iterates with either Jacobian
#
# Both problems are solved with the same (default) solver options.

# %%
results = {kind: solve(problem, SolverOptions()) for kind, problem in problems.items()}
a, b = results["ufl"], results["handwritten"]
energies = [np.array([r.energy for r in res.history]) for res in (a, b)]
same_length = len(energies[0]) == len(energies[1])
energy_gap = (
    float(np.max(np.abs(energies[0] - energies[1]) / np.abs(energies[0])))
    if same_length
    else float("inf")
)
u_gap = comm.allreduce(float(np.abs(a.u.x.array - b.u.x.array).max()), op=MPI.MAX)
u_max = comm.allreduce(float(np.abs(a.u.x.array).max()), op=MPI.MAX)
say(
    f"iterations: ufl {a.iterations}, handwritten {b.iterations}; C0: {a.C0:.15g} vs "
    f"{b.C0:.15g}"
)
say(f"largest relative difference of J_h over the iterations: {energy_gap:.2e}")
say(
    f"max |u_ufl - u_handwritten| / max |u| = {u_gap / u_max:.2e}; "
    f"contact sets equal: {bool(np.array_equal(a.contact, b.contact))}"
)

# %%
path = write_results(
    comm,
    args.out,
    dict(
        cells=args.cells,
        seconds=seconds,
        matrix_rel_diff=difference,
        taylor_passed=report["passed"],
        slope2=report["slope2"],
        iterations={"ufl": a.iterations, "handwritten": b.iterations},
        C0={"ufl": a.C0, "handwritten": b.C0},
        energy_rel_diff=energy_gap,
        u_rel_diff=u_gap / u_max,
        same_contact=bool(np.array_equal(a.contact, b.contact)),
    ),
)
say(f"numbers in {path}")
