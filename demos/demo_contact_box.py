# %% [markdown]
# # Signorini contact on a box in R^3
#
# The problem of the main demo in three dimensions (docs/method.md section 11): a
# nonlinear equation in the box Omega = [-1/4, 1/4]^3, the Laplace equation in the
# unbounded exterior, whose solution now decays like u_e = a + c/|x| + O(1/|x|^2) (no
# logarithm), transmission conditions on the surface Gamma and the Signorini condition
# on the bottom face z = -1/4.
#
# The discrete problem is the same functional J_h(u, phi), with P1 on tetrahedra (six
# per cube of the structured box mesh), the 3D Steklov-Poincare operator S_h of
# `bem_cpp` on the surface triangles (dense below 3,000 boundary nodes, a hierarchical
# matrix above) and phi on the nodes inside the bottom face. The default solver is ssn,
# and `preconditioner = "auto"` picks the 3D block preconditioner `amg`: algebraic
# multigrid for the interior block, the hypersingular operator E^T W_h E for the
# Signorini block (docs/method.md section 11).
#
# The data come from a manufactured solution with a known contact set
# (`coupling.manufactured.box_contact`): the gap vanishes exactly where x < 0 on the
# bottom face and on the face's four edges. The demo prints the errors over three meshes
# and writes the outputs of the finest run as `fembem solve` does.
#
# Run it with `python demos/demo_contact_box.py [--cells N] [--out DIR]` (N cubes per side
# on the finest mesh, N/2 and N/4 on the others), or under `mpirun -n 2`: the numbers are
# the same.

# %%
import numpy as np
from mpi4py import MPI

from common import OUTPUTS_HELP, begin_demo, solve_manufactured, write_solve_outputs
from coupling.manufactured import box_contact
from coupling.options import SolverOptions
from fem_py.forms import make_material

description = "Signorini contact on a box in R^3 (manufactured solution, known contact set)."
cells_help = "cubes per side of the finest box mesh (h = 0.5/cells)"
comm = MPI.COMM_WORLD
args, say = begin_demo(
    comm, "demo_contact_box", description, cells=16, cells_help=cells_help, out_help=OUTPUTS_HELP
)

# %% [markdown]
# ## The exact solution
#
# On the bottom face the gap is G max(0, x)^3 (1/4 - x)(1/4 - y)(y + 1/4) and the flux
# rho du/dn = -K rho max(0, -x)^3: one of the two vanishes at every point, the gap where
# x <= 0 (contact), the flux where x >= 0. f, t0 and u0 follow from u and u_e by UFL.

# %%
material = make_material("carstensen")
solution = box_contact()
face = solution.faces[0]
say(f"material rho(t) = {material.rho_sym}")
say(f"exact u   = {solution.u}")
say(f"exact u_e = {solution.ue}")
say(f"Signorini face {face.name!r}: exact gap {face.gap}, contact exactly where x < 0")

# %% [markdown]
# ## Three meshes
#
# The energy error |u - u_h|_1 falls like h, the nodal errors of u_h and of the trace
# of u_e like h^2; `solution_errors` also counts the Signorini nodes whose contact state
# differs from the exact one away from the switch line x = 0.

# %%
options = SolverOptions()  # the defaults: ssn, preconditioner "auto" (amg in 3D), tol 1e-8
meshes = (args.cells // 4, args.cells // 2, args.cells)
rows, problem, result = solve_manufactured(comm, solution, material, meshes, options)

say(
    f"\n{'h':>9} {'dofs':>6} {'Gamma':>5} {'its':>4} {'|u-u_h|_1':>10} {'max|u-u_h|':>10} "
    f"{'max|ue-ue_h|':>12} {'contact':>9} {'wrong':>5} {'time':>6}"
)
for r in rows:
    say(
        f"{r['h']:9.3e} {r['dofs']:6d} {r['boundary_dofs']:5d} {r['iterations']:4d} "
        f"{r['energy']:10.3e} {r['nodal_u']:10.3e} {r['ue_gamma']:12.3e} "
        f"{r['contact_nodes']:4d}/{r['signorini_nodes']:<4d} {r['contact_mismatch']:5d} "
        f"{r['seconds']:5.1f}s"
    )
rates = {
    key: [float(np.log2(a[key] / b[key])) for a, b in zip(rows, rows[1:])]
    for key in ("energy", "nodal_u", "ue_gamma", "ue_exterior")
}
for key, values in rates.items():
    say(f"rate of {key:>11}: {', '.join(f'{v:.2f}' for v in values)}")

# %% [markdown]
# ## Outputs of the finest run
#
# summary.json, fields.npz (x (N, 3), the tetrahedra `cells`, and on Gamma
# `boundary_triangles`, the gap, u_e, the pressure and the contact set) and
# solution.xdmf (u_h, the named faces and the boundary fields: open it in ParaView), and
# the figures: signorini.png (the gap with the contact set outlined and the pressure on
# the bottom face), surface.png (u_h on Gamma from two sides), slice.png (u_h inside and
# u_e outside on the plane y = 0 through the bottom face, `[output] slice`'s default) and
# history.png.

# %%
out = args.out
files = write_solve_outputs(comm, out, problem, result, options, dict(rows=rows, rates=rates))
say(f"\nfiles:  {', '.join(sorted(files))} in {out} (the errors in results.json)")
