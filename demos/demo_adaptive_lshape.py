# %% [markdown]
# # Adaptive refinement at the re-entrant corner of an L-shape
#
# Omega is the square [-1/4, 1/4]^2 without its upper-right quarter; its re-entrant
# corner (0, 0) has the interior angle 3 pi/2, where the harmonic function
# u = r^(2/3) sin(2 theta/3) (theta measured from the side x = 0, y > 0) has an
# unbounded gradient (docs/method.md section 10). With the linear material, f = 0 and the
# transmission data u0, t0 manufactured from u and an exterior field u_e, the discrete
# solution converges like N^(-1/3) in the energy norm on uniform meshes (N dofs).
#
# The adaptive loop (`coupling.adapt.adapt`, docs/design/estimator.md): solve, estimate
# (the residual estimator of the FEM-BEM coupling, per cell), mark by Doerfler's rule
# (theta = 0.5), refine the marked cells (Plaza), each level started from the previous
# solution. The demo runs it next to uniform refinement (theta = 1, every cell marked)
# and prints, per level, dofs, the energy error, the estimator eta, the efficiency index
# eta/error and the solver steps; then the slopes of error and eta against N.
#
# Run: `python demos/demo_adaptive_lshape.py [--cells N] [--steps K] [--out DIR]`
# (N cells per side of the bounding square of the first mesh, K refinements).

# %%
import numpy as np
from mpi4py import MPI

from common import begin_demo, refinement_summary, write_results
from coupling.adapt import AdaptOptions, adapt
from coupling.manufactured import (
    ManufacturedSolution,
    lshape_corner,
    lshape_corner_contact,
    solution_errors,
)
from coupling.options import SolverOptions
from coupling.problem import SignoriniProblem
from fem_py.forms import make_material
from fem_py.mesh import GeometrySpec, build_domain

description = "Adaptive refinement at the re-entrant corner of an L-shape."
cells_help = "cells per side of the bounding square of the first mesh"
comm = MPI.COMM_WORLD
args, say = begin_demo(
    comm, "demo_adaptive_lshape", description, cells=8, cells_help=cells_help, max_dofs=40000
)

# %% [markdown]
# ## The singular solution
#
# With beta = atan2(x - y, -(x + y)) (zero along the direction (-1, -1), into Omega),
# theta = beta + 3 pi/4 and sin(2 theta/3) = cos(2 beta/3): the branch cut of atan2
# lies in the removed quarter (`coupling.manufactured.lshape_corner`).

# %%
exact = lshape_corner()
material = make_material("linear")


def builder(solution: ManufacturedSolution, harmonic: bool):
    def build(domain):
        data = solution.data(domain.mesh, material)
        if harmonic:
            data["f"] = "0"  # u is harmonic
        problem = SignoriniProblem(
            domain, material, f=data["f"], u0=data["u0"], t0=data["t0"], a=data["a"]
        )
        return problem, data

    return build


def run(solution: ManufacturedSolution, theta: float, max_dofs: int) -> tuple[list[dict], list]:
    """The adaptive loop (theta < 1) or uniform refinement (theta = 1) of ``solution``:
    the rows printed per level and the levels."""
    domain = build_domain(
        comm,
        GeometrySpec(
            "lshape",
            h=0.5 / args.cells,
            subdomain_size=1.0 / args.cells,
            structured=True,
            signorini=solution.signorini,
        ),
    )
    rows = []

    def record(level):
        row = level.record()
        errors = solution_errors(level.problem, solution, level.solution)
        row["error"] = errors["energy"]
        row["contact_mismatch"] = errors["contact_mismatch"]
        row["index"] = row["estimator"] / row["error"]
        rows.append(row)
        say(
            f"{row['level']:5d} {row['dofs']:8d} {row['boundary_dofs']:6d} "
            f"{row['error']:10.3e} {row['estimator']:10.3e} {row['index']:6.2f} "
            f"{row['iterations']:4d} {row['gradient_steps']:4d} {row['newton_steps']:4d}"
        )

    say("level     dofs  Gamma   |u-u_h|_1        eta  index  its  pgpm  ssn")
    options = AdaptOptions(steps=args.steps, theta=theta, max_dofs=max_dofs)
    harmonic = not solution.arcs
    levels = adapt(builder(solution, harmonic), domain, SolverOptions(), options, on_level=record)
    return rows, levels


# %% [markdown]
# ## Adaptive and uniform refinement
#
# Slopes are least-squares fits of log(error) and log(eta) against log(N) over the levels
# with N >= 1000 (the pre-asymptotic coarse levels left out).

# %%
results = {}
for name, theta in (("adaptive", 0.5), ("uniform", 1.0)):
    say(f"\n{name} (theta = {theta})")
    results[name] = summary = refinement_summary(run(exact, theta, args.max_dofs)[0], 1000)
    index = [r["index"] for r in summary["rows"]]
    say(
        f"slopes (N >= 1000): error {summary['error_slope']}, eta {summary['estimator_slope']}; "
        f"efficiency index {min(index):.2f} .. {max(index):.2f}"
    )

# %% [markdown]
# ## With contact
#
# `coupling.manufactured.lshape_corner_contact`: the same corner singularity (times
# (1 + 4y)^2, which is 1 at the corner and vanishes with its normal derivative on the
# bottom side) plus the manufactured contact term, the bottom side a Signorini arc with
# the exact contact set x < 0. Adaptive up to a third of `--max-dofs`, against uniform
# refinement to the first mesh with more dofs than the last adaptive level; the figure
# shows the final adaptive mesh, graded towards the corner and the ends of the arc, and
# its contact set.

# %%
contact_case = lshape_corner_contact()
say("\nwith contact: adaptive (theta = 0.5)")
rows, levels = run(contact_case, 0.5, args.max_dofs // 3)
say("with contact: uniform")
uniform_rows, _ = run(contact_case, 1.0, 4 * rows[-1]["dofs"])
results["contact"] = dict(adaptive=rows, uniform=uniform_rows)
final = levels[-1]
x = final.domain.mesh.geometry.x[:, :2]
triangles = final.domain.mesh.geometry.dofmap.array.reshape(-1, 3)
parts = comm.gather(x[triangles], root=0)
boundary = final.problem.boundary
s_nodes = boundary.nodes[boundary.signorini]
if comm.rank == 0:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    fig, ax = plt.subplots(figsize=(6, 6))
    polys = np.concatenate(parts)
    ax.add_collection(PolyCollection(polys, facecolors="none", edgecolors="k", linewidths=0.2))
    ax.plot(*s_nodes[final.solution.contact].T, "r.", ms=5, label="contact (phi_h = 0)")
    ax.plot(*s_nodes[~final.solution.contact].T, "b.", ms=5, label="open gap")
    ax.set_aspect("equal")
    ax.autoscale()
    ax.legend(loc="upper right")
    ax.set_title(f"adaptive mesh with contact, {rows[-1]['dofs']} dofs")
    args.out.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out / "mesh.png", dpi=150)
    plt.close(fig)
say(
    f"final adaptive level {rows[-1]['dofs']} dofs, error {rows[-1]['error']:.3e}; uniform "
    + ", ".join(f"{r['dofs']} dofs {r['error']:.3e}" for r in uniform_rows)
)
path = write_results(comm, args.out, results)
say(f"\nresults: {path}, mesh: {args.out / 'mesh.png'}")
