# %% [markdown]
# # A shrink fit: a shaft in an infinite plate, against Lamé's closed form
#
# The elastic problem of docs/method.md section 12 with an answer in closed form: a
# circular shaft of radius b (Young's modulus E, Poisson's ratio nu) pressed into a hole in
# an infinite plate (E_e, nu_e) whose radius is smaller by the interference delta. Plane
# strain. The interface is unilateral: it may open but not interpenetrate, so the shaft
# and the plate meet with a contact pressure p that Lamé's solutions give.
#
# **The closed form.** A solid disk under an external pressure p has the radial
# displacement u_r(b) = -p b (1 + nu)(1 - 2 nu) / E at its rim (plane strain: sigma_rr =
# sigma_tt = -p, eps_rr = ((1 - nu^2) sigma_rr - nu (1 + nu) sigma_tt) / E). An infinite
# plate with a hole of radius b under an internal pressure p has u_r(b) = p b (1 + nu_e) /
# E_e (sigma_rr = -p b^2/r^2 = -sigma_tt: a pure shear, no volume change). The two rims
# meet when the hole opens and the shaft shrinks by delta in all:
#
#     p = delta / (b ((1 + nu_e) / E_e + (1 + nu)(1 - 2 nu) / E)).
#
# **The discrete problem.** The gap j = u_e + u0 - u with u0 = -delta n: j.n >= 0 says the
# plate's rim has moved out by at least delta more than the shaft's. With `"slip"` on the
# whole circle the shaft could turn freely (a rigid rotation changes no energy: the
# problem refuses that configuration in one line), so the interface is `"stick"`: the
# jump is normal. The contact pressure is -n.sigma(u_h)n at the nodes of the circle
# (`coupling.io.quantities`), on three gmsh meshes of the disk.
#
# Run it with `python demos/demo_shrink_fit.py [--cells N] [--out DIR]` (N: b/h on the
# finest mesh; N/4 and N/2 on the others), or under `mpirun -n 2`: the numbers are the
# same.

# %%
import time

import numpy as np
from mpi4py import MPI

from common import OUTPUTS_HELP, begin_demo, write_solve_outputs
from coupling.io.quantities import boundary_flux, elastic_boundary_fields
from coupling.options import SolverOptions
from coupling.problem import SignoriniProblem
from coupling.solvers import solve
from fem_py.forms.elasticity import linear_elastic
from fem_py.mesh import GeometrySpec, build_domain

description = "A shrink fit against Lamé's closed form (plane strain, unilateral interface)."
cells_help = "b/h on the finest mesh of the disk"
comm = MPI.COMM_WORLD
args, say = begin_demo(
    comm, "demo_shrink_fit", description, cells=32, cells_help=cells_help, out_help=OUTPUTS_HELP
)

# %% [markdown]
# ## The data

# %%
b, delta = 0.25, 1e-3
shaft, plate = (2.0, 0.3), (1.0, 0.25)  # (E, nu)
(E, nu), (E_e, nu_e) = shaft, plate
p_exact = delta / (b * ((1 + nu_e) / E_e + (1 + nu) * (1 - 2 * nu) / E))
say(f"shaft E = {E}, nu = {nu}; plate E = {E_e}, nu = {nu_e}; b = {b}, delta = {delta}")
say(f"Lame's contact pressure p = {p_exact:.6e}")

# %% [markdown]
# ## Three meshes
#
# The pressure at every node of the circle against p: its largest relative error falls
# like h^2.

# %%
options = SolverOptions(tol=1e-10)
rows = []
for cells in (args.cells // 4, args.cells // 2, args.cells):
    tic = time.perf_counter()
    domain = build_domain(comm, GeometrySpec("disk", radius=b, h=b / cells, signorini="all"))
    problem = SignoriniProblem(
        domain,
        linear_elastic(E, nu, 2),
        u0=[f"-{delta}*nx", f"-{delta}*ny"],
        exterior=plate,
        tangential="stick",
    )
    result = solve(problem, options)
    fields = elastic_boundary_fields(problem, result, boundary_flux(problem, result))
    p = -fields["pressure"]
    rows.append(
        dict(
            cells=cells,
            h=b / cells,
            dofs=problem.n_dofs,
            nodes_on_gamma=problem.boundary.n_nodes,
            converged=bool(result.converged),
            iterations=int(result.iterations),
            contact_nodes=int(np.count_nonzero(result.contact)),
            pressure_mean=float(p.mean()),
            pressure_error=float(np.abs(p - p_exact).max() / p_exact),
            seconds=time.perf_counter() - tic,
        )
    )

say(
    f"\n{'b/h':>4} {'dofs':>6} {'Gamma':>5} {'its':>4} {'contact':>8} {'mean p':>12} "
    f"{'max |p - p*|/p*':>16} {'time':>6}"
)
for r in rows:
    say(
        f"{r['cells']:4d} {r['dofs']:6d} {r['nodes_on_gamma']:5d} {r['iterations']:4d} "
        f"{r['contact_nodes']:4d}/{r['nodes_on_gamma']:<3d} {r['pressure_mean']:12.6e} "
        f"{r['pressure_error']:16.3e} {r['seconds']:5.1f}s"
    )
rates = [
    float(np.log(a["pressure_error"] / c["pressure_error"]) / np.log(c["cells"] / a["cells"]))
    for a, c in zip(rows, rows[1:])
]
say(f"rate of the pressure error: {', '.join(f'{v:.2f}' for v in rates)}")

# %% [markdown]
# ## Outputs of the finest run
#
# summary.json (with `force`, the net force on the plate: zero here, by symmetry),
# fields.npz (u (N, 2), the traction, the pressure, the jump on the circle) and
# solution.xdmf (u_h as a vector: "Warp By Vector" in ParaView shows the shaft
# shrunk by the fit).

# %%
results = dict(rows=rows, rates=rates, p_exact=p_exact)
files = write_solve_outputs(comm, args.out, problem, result, options, results)
say(f"\nfiles:  {', '.join(sorted(files))} in {args.out} (the errors in results.json)")
