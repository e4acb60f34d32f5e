# %% [markdown]
# # Adaptive refinement at the re-entrant edge of an L-shaped prism
#
# Omega is the L-shape [-1/4, 1/4]^2 without its upper-right quarter, extruded over
# z in [-1/4, 1/4]: a body in R^3 with a re-entrant edge along the z-axis (interior
# dihedral angle 3 pi/2). The harmonic function u = r^(2/3) sin(2 theta/3) of the 2D
# L-shape (r, theta around the edge) has an unbounded gradient along the whole edge; with
# the linear material, f = 0 and the transmission data u0, t0 manufactured from u and an
# exterior field u_e = a + c/|x - x0| + d.(x - x0)/|x - x0|^3, uniform refinement converges
# like h^(2/3) = N^(-2/9) in the energy norm, and the adaptive loop (the 3D residual
# estimator, Doerfler marking with theta = 0.5, local refinement of the tetrahedra;
# docs/design/estimator.md, "Bodies in R^3") can recover N^(-1/3).
#
# The body is meshed by gmsh (a mesh file, as a user's body would be); the demo runs the
# adaptive loop and uniform refinement (theta = 1: every cell marked, Plaza's uniform
# refinement) from the same mesh and prints, per level, dofs, the energy error, eta, the
# efficiency index and the solver steps; then the slopes of error and eta against N.
#
# Run: `python demos/demo_adaptive_lprism.py [--cells N] [--steps K] [--max-dofs M]
# [--out DIR]` (the first mesh has h = 0.5/N).

# %%
import numpy as np
from mpi4py import MPI

from common import begin_demo, refinement_summary, write_gmsh_file, write_results
from coupling.adapt import AdaptOptions, adapt
from coupling.manufactured import ManufacturedSolution, exterior_field_3d, lshape_corner
from coupling.manufactured import solution_errors
from coupling.options import SolverOptions
from coupling.problem import SignoriniProblem
from fem_py.forms import make_material
from fem_py.mesh import GeometrySpec, build_domain

description = "Adaptive refinement at the re-entrant edge of an L-shaped prism."
cells_help = "the first mesh's size is h = 0.5/cells"
comm = MPI.COMM_WORLD
args, say = begin_demo(
    comm, "demo_adaptive_lprism", description, cells=4, cells_help=cells_help, max_dofs=30000
)

# %% [markdown]
# ## The body and the singular solution
#
# gmsh writes the prism (one physical volume, one physical surface group) on rank 0;
# `[geometry] mesh` reads it. u does not depend on z; as in the 2D demo,
# beta = atan2(x - y, -(x + y)) puts the branch cut of atan2 in the removed quarter: u is
# that of `coupling.manufactured.lshape_corner`.

# %%
CORNER = lshape_corner().u
exact = ManufacturedSolution(
    "mesh", 0.5, (0.0, 0.0, 0.0), (), CORNER, exterior_field_3d((-0.1, -0.1, 0.0))
)
material = make_material("linear")


def build_prism(gmsh, h: float) -> None:
    occ = gmsh.model.occ
    q = 0.25
    occ.cut(
        [(3, occ.addBox(-q, -q, -q, 2 * q, 2 * q, 2 * q))],
        [(3, occ.addBox(0, 0, -q, q, q, 2 * q))],
    )
    occ.synchronize()
    volumes = [v for _, v in gmsh.model.getEntities(3)]
    surfaces = [s for _, s in gmsh.model.getEntities(2)]
    gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, surfaces, 1), "surface")
    gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, volumes, 2), "omega")


mesh_file = write_gmsh_file(comm, args.out / "lprism.msh", build_prism, h=0.5 / args.cells, dim=3)


def build(domain):
    data = exact.data(domain.mesh, material)
    problem = SignoriniProblem(domain, material, f="0", u0=data["u0"], t0=data["t0"], a=data["a"])
    return problem, {"f": "0", "t0": data["t0"]}


def run(theta: float, max_dofs: int) -> list[dict]:
    """The adaptive loop (theta < 1) or uniform refinement (theta = 1): the rows printed
    per level."""
    domain = build_domain(comm, GeometrySpec(mesh=str(mesh_file)))
    rows = []

    def record(level):
        row = level.record()
        row["error"] = solution_errors(level.problem, exact, level.solution)["energy"]
        row["index"] = row["estimator"] / row["error"]
        rows.append(row)
        say(
            f"{row['level']:5d} {row['dofs']:8d} {row['boundary_dofs']:6d} "
            f"{row['error']:10.3e} {row['estimator']:10.3e} {row['index']:6.2f} "
            f"{row['iterations']:4d} {row['cg_iterations']:5d} {row['time']:7.1f}"
        )

    say("level     dofs  Gamma   |u-u_h|_1        eta  index  its    cg    time")
    options = AdaptOptions(steps=args.steps, theta=theta, max_dofs=max_dofs)
    adapt(build, domain, SolverOptions(preconditioner="amg"), options, on_level=record)
    return rows


# %% [markdown]
# ## Adaptive and uniform refinement
#
# Slopes are least-squares fits of log(error) and log(eta) against log(N) over the levels
# with N >= 2000 (the pre-asymptotic coarse levels left out; uniform refinement multiplies
# N by about 8 per level, so its slope is over all its levels).

# %%
results = {}
for name, theta in (("adaptive", 0.5), ("uniform", 1.0)):
    say(f"\n{name} (theta = {theta})")
    results[name] = summary = refinement_summary(
        run(theta, args.max_dofs), 2000 if theta < 1 else 0
    )
    index = [r["index"] for r in summary["rows"]]
    say(
        f"slopes: error {summary['error_slope']}, eta {summary['estimator_slope']}; "
        f"efficiency index {min(index):.2f} .. {max(index):.2f}"
    )

# %% [markdown]
# ## The rates
#
# Error and eta against N, log-log, with the reference slopes -1/3 (optimal for P1 in
# 3D) and -2/9 (uniform refinement at the edge singularity).

# %%
if comm.rank == 0:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 5))
    for name, style in (("adaptive", "o-"), ("uniform", "s--")):
        rows = results[name]["rows"]
        n = np.array([r["dofs"] for r in rows], dtype=float)
        ax.loglog(n, [r["error"] for r in rows], style, label=f"{name}: error")
        ax.loglog(n, [r["estimator"] for r in rows], style, mfc="none", label=f"{name}: eta")
    n0 = results["adaptive"]["rows"][0]["dofs"]
    e0 = results["adaptive"]["rows"][0]["error"]
    ref = np.array([n0, 10 * n0], dtype=float)
    ax.loglog(ref, 0.8 * e0 * (ref / n0) ** (-1 / 3), "k:", label="$N^{-1/3}$")
    ax.loglog(ref, 1.25 * e0 * (ref / n0) ** (-2 / 9), "k-.", label="$N^{-2/9}$")
    ax.set(xlabel="dofs N", ylabel="energy error, eta")
    ax.legend(fontsize=8)
    ax.set_title("L-shaped prism, re-entrant edge")
    fig.tight_layout()
    args.out.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out / "rates.png", dpi=120)
    plt.close(fig)
path = write_results(comm, args.out, results)
say(f"\nresults: {path}, figure: {args.out / 'rates.png'}")
