# %% [markdown]
# # An elastic footing in an elastic medium: your own body from gmsh, part of its base lifting
#
# The elastic problem of docs/method.md section 12 on a body built with gmsh's OpenCASCADE
# kernel: a footing, a slab 0.6 x 0.4 x 0.15 with a column stub 0.2 x 0.2 x 0.15 on top,
# embedded in an unbounded elastic medium (soil or rock: E_e = 1, nu_e = 0.3). Its base
# (the face z = 0, the physical group "base") rests on the medium in frictionless
# unilateral contact (`tangential = "slip"`): it may lift off, never sink in, and slides
# freely; the rest of its surface ("sides") is bonded to the medium. The footing is a
# Hencky material (bulk modulus 3, shear modulus mu(s) = 1 + 1/(1 + 10 s): softening
# under shear).
#
# The load: a horizontal push, f = (1, 0, 0) (a full-space model has no gravity of its
# own), and a misfit of the base, u0 = (0, 0, 0.02 (x - 0.3)): where u0_z > 0 the base
# must stand that much above the medium's surface to touch it, where u0_z < 0 it is
# pressed into it. The push tilts the footing; part of the base lifts (a third of it
# stays in contact at the default size). No exact solution is known; the
# demo checks the contact conditions at the solution (gap >= 0, contact pressure >= 0,
# one of them zero at every node), that the net force on the medium balances the load,
# and prints what summary.json reports.
#
# Run: `python demos/demo_elastic_footing.py [--cells N] [--out DIR]` (mesh size h =
# 0.15/N; the .msh file, the outputs and results.json go to DIR), or under
# `mpirun -n 2`: the numbers are the same.

# %%
import numpy as np
from mpi4py import MPI

from common import OUTPUTS_HELP, begin_demo, outcome, write_gmsh_file, write_solve_outputs
from coupling.io.quantities import (
    boundary_flux,
    complementarity,
    elastic_boundary_fields,
    net_force,
)
from coupling.options import SolverOptions
from coupling.problem import SignoriniProblem
from coupling.solvers import solve
from fem_py.forms.elasticity import hencky
from fem_py.mesh import GeometrySpec, build_domain

description = "An elastic footing from gmsh in an elastic medium, part of its base lifting."
comm = MPI.COMM_WORLD
args, say = begin_demo(
    comm,
    "demo_elastic_footing",
    description,
    cells=3,
    cells_help="h = 0.15/cells",
    out_help=OUTPUTS_HELP,
)

# %% [markdown]
# ## Build and mesh the footing with gmsh (rank 0)
#
# `occ.fuse` joins the slab and the column; the faces of the result are told apart by
# their centres of mass: the base's lies on z = 0. Every surface and the volume carry a
# physical group. `write_gmsh_file` (demos/common.py) meshes the model and writes the file.

# %%


def build_footing(gmsh, h: float) -> None:
    occ = gmsh.model.occ
    slab = occ.addBox(0.0, 0.0, 0.0, 0.6, 0.4, 0.15)
    column = occ.addBox(0.2, 0.1, 0.15, 0.2, 0.2, 0.15)
    (body,), _ = occ.fuse([(3, slab)], [(3, column)])
    occ.synchronize()
    groups = {"base": [], "sides": []}
    for _, tag in gmsh.model.getEntities(2):
        centre = occ.getCenterOfMass(2, tag)
        groups["base" if abs(centre[2]) < 1e-9 else "sides"].append(tag)
    for number, (name, tags) in enumerate(groups.items(), start=1):
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, tags, number), name)
    gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, [body[1]], 10), "footing")


msh_file = write_gmsh_file(
    comm, args.out / "footing.msh", build_footing, h=0.15 / args.cells, dim=3
)

# %% [markdown]
# ## Read, solve, check
#
# The defaults solve it: ssn with the `amg` preconditioner (GAMG on the elastic stiffness
# with the six rigid motions as its near-nullspace, the Lamé hypersingular operator on
# the base). At the solution the normal gap phi >= 0 and the contact pressure
# p = -n.sigma(u_h)n >= 0 on the base, with phi p = 0; the net force the footing exerts
# on the medium is its load, int f = volume (1, 0, 0).

# %%
domain = build_domain(comm, GeometrySpec(mesh=str(msh_file), signorini=["base"]))
problem = SignoriniProblem(
    domain,
    hencky(3.0, "1 + 1/(1 + 10*s)", 3),
    f=["1", "0", "0"],
    u0=["0", "0", "0.02*(x - 0.3)"],
    exterior=(1.0, 0.3),
    tangential="slip",
)
options = SolverOptions()
result = solve(problem, options)
fields = elastic_boundary_fields(problem, result, boundary_flux(problem, result))
base = problem.boundary.signorini
force = net_force(problem, result)
volume = 0.6 * 0.4 * 0.15 + 0.2 * 0.2 * 0.15
facts = dict(
    dofs=problem.n_dofs,
    boundary_dofs=problem.boundary.n_gamma,
    base_nodes=int(base.size),
    iterations=result.iterations,
    converged=bool(result.converged),
    contact_nodes=int(np.count_nonzero(result.contact)),
    energy=float(result.energy),
    complementarity=complementarity(
        fields["phi"][base], fields["pressure"][base], float(np.abs(fields["pressure"]).max())
    ),
    force=force,
    force_error=float(np.abs(np.array(force) - volume * np.array([1.0, 0.0, 0.0])).max()),
    largest_gap=float(fields["phi"][base].max()),
)
say(
    f"{msh_file}: {facts['dofs']} dofs, {facts['boundary_dofs']} on Gamma, "
    f"{facts['base_nodes']} nodes inside the base; {outcome(result, options.method)}"
)
say(
    f"contact at {facts['contact_nodes']} of {facts['base_nodes']} base nodes, the largest "
    f"gap {facts['largest_gap']:.3e}; complementarity {facts['complementarity']:.1e}"
)
say(
    f"net force on the medium {np.round(force, 6)} against the load "
    f"{np.round(volume * np.array([1.0, 0.0, 0.0]), 6)}"
)

# %% [markdown]
# ## Outputs
#
# What `fembem solve` writes: summary.json (with `force`), fields.npz (u (N, 3), and on
# the surface triangles the jump, its normal part phi, the traction and the contact
# pressure) and solution.xdmf (u_h as a vector and the named faces, for ParaView's
# "Warp By Vector").

# %%
files = write_solve_outputs(comm, args.out, problem, result, options, facts)
say(f"files: {', '.join(sorted(files))} in {args.out}")
