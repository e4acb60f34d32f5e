# %% [markdown]
# # Bring your own mesh: a gmsh file with named boundary parts
#
# Omega is read from a gmsh mesh file instead of being generated. The demo writes the
# file itself with the gmsh Python API - a disk of radius 1/4, its boundary split into
# the physical curve groups "contact" (the lower quarter of the circle) and "free" (the
# rest) - and then does what `geometry.mesh = "disk.msh"` with `signorini = ["contact"]`
# does in a configuration: rank 0 reads the file, the mesh is split automatically into
# connected subdomains of size d (``fem_py.partition``) and distributed by whole
# subdomains, and the group ends become coarse vertices (docs/method.md section 6).
#
# The data are those of the manufactured solution
# :func:`coupling.manufactured.disk_contact` (Carstensen material), in contact on the
# left half of the contact arc (x < 0). The demo prints the errors, and draws the
# subdomains and the computed contact set.
#
# Run: `python demos/demo_own_mesh.py [--cells N] [--out DIR]` (mesh size h = 0.5/N;
# the figure, the .msh file and results.json go to DIR, default out/demo_own_mesh).

# %%
import math

import numpy as np
from mpi4py import MPI

from common import begin_demo, outcome, write_gmsh_file, write_results
from coupling.manufactured import disk_contact, solution_errors
from coupling.options import SolverOptions
from coupling.problem import SignoriniProblem
from coupling.solvers import solve
from fem_py.forms import make_material
from fem_py.mesh import GeometrySpec, build_domain

description = "A disk read from a gmsh .msh file with named physical groups."
out_help = "folder for the .msh file, the figure and results.json"
comm = MPI.COMM_WORLD
args, say = begin_demo(
    comm, "demo_own_mesh", description, cells=64, cells_help="h = 0.5/cells", out_help=out_help
)

# %% [markdown]
# ## Write the mesh file with gmsh
#
# Three points on the circle cut it into circle arcs; the lower one is the group
# "contact", the two others the group "free". Every element of the file is a linear
# triangle (MSH 4.1; 2.2 is read as well). `write_gmsh_file` (demos/common.py) meshes
# the model on rank 0 and writes the file.

# %%
h = 0.5 / args.cells


def build_disk(gmsh, h: float) -> None:
    geo = gmsh.model.geo
    R = 0.25
    centre = geo.addPoint(0, 0, 0, h)
    angles = [-3 * math.pi / 4, -math.pi / 4, math.pi / 2]
    points = [geo.addPoint(R * math.cos(a), R * math.sin(a), 0, h) for a in angles]
    arcs = [geo.addCircleArc(points[i], centre, points[(i + 1) % 3]) for i in range(3)]
    surface = geo.addPlaneSurface([geo.addCurveLoop(arcs)])
    geo.synchronize()
    gmsh.model.setPhysicalName(1, gmsh.model.addPhysicalGroup(1, [arcs[0]], 1), "contact")
    gmsh.model.setPhysicalName(1, gmsh.model.addPhysicalGroup(1, arcs[1:], 2), "free")
    gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, [surface], 3), "omega")


msh_file = write_gmsh_file(comm, args.out / "disk.msh", build_disk, h=h, dim=2)

# %% [markdown]
# ## Read, partition, solve

# %%
domain = build_domain(
    comm, GeometrySpec(mesh=str(msh_file), subdomain_size=4 * h, signorini=["contact"])
)
solution, material = disk_contact(), make_material("carstensen")
problem = SignoriniProblem(domain, material, **solution.data(domain.mesh, material))
options = SolverOptions()
result = solve(problem, options)
errors = solution_errors(problem, solution, result)
say(
    f"{msh_file}: {problem.V.dofmap.index_map.size_global} dofs, "
    f"{domain.coarse.n_subdomains} subdomains, {problem.n_signorini} Signorini nodes; "
    f"{outcome(result, options.method)}"
)
say(
    f"|u - u_h|_1 = {errors['energy']:.3e}   max |u - u_h| = {errors['nodal_u']:.3e}   "
    f"max |gap error| = {errors['gap']:.3e}   contact nodes in the wrong state: "
    f"{errors['contact_mismatch']}"
)

# %% [markdown]
# ## The subdomains and the contact set
#
# Each subdomain in its own colour, the coarse vertices as black dots, the contact arc
# red where phi_h = 0 and blue where the gap is open.

# %%
x = domain.mesh.geometry.x[:, :2]
triangles = domain.mesh.geometry.dofmap.array.reshape(-1, 3)
tags = np.zeros(len(triangles), dtype=int)
tags[domain.cell_tags.indices] = domain.cell_tags.values
parts = comm.gather((x[triangles], tags), root=0)
boundary = problem.boundary
contact_x = boundary.nodes[boundary.signorini]
figure = args.out / "subdomains.png"
if comm.rank == 0:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    fig, ax = plt.subplots(figsize=(6, 6))
    polys = np.concatenate([p[0] for p in parts])
    colour = np.concatenate([p[1] for p in parts])
    ax.add_collection(
        PolyCollection(polys, array=(colour * 7919) % 20, cmap="tab20", edgecolors="none")
    )
    vc = domain.coarse.vertex_coords
    ax.plot(vc[:, 0], vc[:, 1], "k.", ms=4)
    ax.plot(*contact_x[result.contact].T, "r.", ms=6, label="contact (phi_h = 0)")
    ax.plot(*contact_x[~result.contact].T, "b.", ms=6, label="open gap")
    ax.set_aspect("equal")
    ax.autoscale()
    ax.legend(loc="upper right")
    ax.set_title(f"{domain.coarse.n_subdomains} subdomains of size d = {4 * h:.3g}")
    fig.savefig(figure, dpi=120)
    plt.close(fig)
results = write_results(
    comm,
    args.out,
    dict(
        cells=args.cells,
        converged=bool(result.converged),
        iterations=int(result.iterations),
        subdomains=int(domain.coarse.n_subdomains),
        contact=int(result.contact.sum()),
        signorini_nodes=int(problem.n_signorini),
        errors=errors,
    ),
)
say(f"figure: {figure}, numbers: {results}")
