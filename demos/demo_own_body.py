# %% [markdown]
# # Your own body: a block with a hole, built with gmsh's OpenCASCADE kernel
#
# A three-dimensional Omega from a gmsh mesh file that the demo writes itself: a block
# 0.6 x 0.4 x 0.3 with a cylindrical hole of radius 0.08 drilled through it along y. Its
# surface is split into physical surface groups named "bottom" (the face z = 0),
# "hole" (the cylinder's wall) and "sides" (the rest); the volume is the group "body".
# The run then does what a configuration with `geometry.mesh = "block.msh"` and
# `signorini = ["bottom"]` does: rank 0 reads the file and checks it (linear
# tetrahedra, one body whose exterior is connected - a hole through the body is
# allowed, a closed cavity is not), the mesh is distributed, and the Signorini condition
# holds on the bottom face.
#
# The data press the block onto its bottom face (t0 = -1), tilted by u0 = 0.1 (x - 0.3),
# with a nonlinear material and a source f = 1: a part of the face is in contact. No
# exact solution is known here; the demo prints what summary.json reports and checks
# the contact conditions at the solution.
#
# Run: `python demos/demo_own_body.py [--cells N] [--out DIR]` (mesh size h = 0.3/N; the
# .msh file, the outputs and results.json go to DIR), or under `mpirun -n 2`.

# %%
import numpy as np
from mpi4py import MPI

from common import OUTPUTS_HELP, begin_demo, outcome, write_gmsh_file, write_solve_outputs
from coupling.app.sizing import check_memory
from coupling.io.quantities import boundary_flux, complementarity, far_field_coefficient
from coupling.options import SolverOptions
from coupling.problem import SignoriniProblem
from coupling.solvers import solve
from fem_py.forms import make_material
from fem_py.mesh import GeometrySpec, build_domain
from fem_py.mesh.size_estimate import gmsh_model_size

description = "A block with a hole from a gmsh OpenCASCADE model, Signorini on a named face."
comm = MPI.COMM_WORLD
args, say = begin_demo(
    comm, "demo_own_body", description, cells=8, cells_help="h = 0.3/cells", out_help=OUTPUTS_HELP
)

# %% [markdown]
# ## Build and mesh the body with gmsh (rank 0)
#
# `occ.cut` drills the hole; the faces of the result are told apart by their centres of
# mass (the bottom's at z = 0, the wall's on the cylinder's axis, at the block's
# centre). Every surface and the volume carry a physical group (untagged entities are
# not read). Before gmsh meshes, `gmsh_model_size` estimates the mesh from the model's
# volume and areas and `check_memory` refuses, in one line, a mesh size h whose run
# could not fit in memory (a 3D mesh of too small an h takes gmsh minutes to hours).
# `write_gmsh_file` (demos/common.py) then meshes the model and writes the file.

# %%


def build_block(gmsh, h: float) -> None:
    occ = gmsh.model.occ
    block = occ.addBox(0.0, 0.0, 0.0, 0.6, 0.4, 0.3)
    drill = occ.addCylinder(0.3, -0.1, 0.15, 0.0, 0.6, 0.0, 0.08)
    (body,), _ = occ.cut([(3, block)], [(3, drill)])
    occ.synchronize()
    groups = {"bottom": [], "hole": [], "sides": []}
    for _, tag in gmsh.model.getEntities(2):
        centre = np.array(occ.getCenterOfMass(2, tag))
        if abs(centre[2]) < 1e-9:
            groups["bottom"].append(tag)
        elif np.allclose(centre, [0.3, 0.2, 0.15], atol=1e-9):  # the cylinder's wall
            groups["hole"].append(tag)
        else:
            groups["sides"].append(tag)
    for number, (name, tags) in enumerate(groups.items(), start=1):
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, tags, number), name)
    gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, [body[1]], 10), "body")
    check_memory(gmsh_model_size(h, signorini=["bottom"]), comm.size, plots=True)


msh_file = write_gmsh_file(comm, args.out / "block.msh", build_block, h=0.3 / args.cells, dim=3)

# %% [markdown]
# ## Read, solve, check
#
# `build_domain` reads the file on rank 0, checks it and distributes the mesh; the
# defaults solve it (ssn, the 3D preconditioner amg). The contact pressure sigma =
# rho du_h/dn on the bottom face must be <= 0, the gap phi >= 0, and their product 0.

# %%
domain = build_domain(comm, GeometrySpec(mesh=str(msh_file), signorini=["bottom"]))
material = make_material("carstensen")
problem = SignoriniProblem(domain, material, f="1", t0="-1", u0="0.1*(x - 0.3)")
options = SolverOptions()
result = solve(problem, options)
sigma = boundary_flux(problem, result)[problem.boundary.signorini]
name, value = far_field_coefficient(problem, result)
facts = dict(
    dofs=problem.V.dofmap.index_map.size_global,
    boundary_dofs=problem.boundary.n_gamma,
    signorini_dofs=problem.n_signorini,
    iterations=result.iterations,
    converged=bool(result.converged),
    contact_nodes=int(np.count_nonzero(result.contact)),
    energy=float(result.energy),
    complementarity=complementarity(result.phi, sigma),
    far_field=value,
)
say(
    f"{msh_file}: {facts['dofs']} dofs, {facts['boundary_dofs']} on Gamma, "
    f"{facts['signorini_dofs']} Signorini nodes; {outcome(result, options.method)}"
)
say(
    f"contact at {facts['contact_nodes']} of {facts['signorini_dofs']} nodes; J_h = "
    f"{facts['energy']:.10f}; complementarity {facts['complementarity']:.1e}; "
    f"u_e = a {value:+.4g}/|x| + ... far away"
)

# %% [markdown]
# ## Outputs
#
# What `fembem solve` writes: summary.json, fields.npz (the tetrahedra, u_h, and on the
# surface triangles the gap, u_e, the pressure and the contact set) and solution.xdmf
# (u_h and the named faces, for ParaView).

# %%
files = write_solve_outputs(comm, args.out, problem, result, options, facts)
say(f"files: {', '.join(sorted(files))} in {args.out}")
