# %% [markdown]
# # An MPI run
#
# Run with `mpirun -n 2 python demos/demo_mpi.py [--cells N] [--out DIR]` (results.json
# goes to DIR, default out/demo_mpi).
#
# Everything in the Python API takes its communicator from the mesh: here the mesh is
# built on MPI.COMM_WORLD, so DOLFINx distributes the cells and the P1 dofs over the
# ranks. The boundary element part (S_h, dense, of the size of the boundary) is
# computed once on rank 0 and replicated, and so is phi. The mesh is partitioned by
# whole subdomains, so the substructuring preconditioner is distributed: every rank
# factors the Dirichlet problems of its own subdomains and the small coarse system is
# solved on every rank. The solver's reductions are arranged so that its iterates do
# not depend on the number of ranks.
#
# The demo solves the manufactured contact problem on the square on all ranks, then
# solves it again on rank 0 alone (a communicator of one rank, MPI.COMM_SELF) and
# compares the two solutions.

# %%
import time

import numpy as np
from mpi4py import MPI

from common import begin_demo, write_results
from coupling.io.outputs import gather_p1
from coupling.manufactured import manufactured_problem, solution_errors, square_contact
from coupling.options import SolverOptions
from coupling.solvers import solve
from fem_py.forms import make_material

world = MPI.COMM_WORLD
args, say = begin_demo(world, "demo_mpi", "The contact problem on several MPI ranks.", cells=128)


def solve_on(comm: MPI.Comm):
    """Assemble and solve on ``comm``; return (problem, result, seconds)."""
    tic = time.perf_counter()
    problem = manufactured_problem(
        comm, square_contact(), make_material("carstensen"), cells=args.cells
    )
    result = solve(problem, SolverOptions())
    return problem, result, comm.allreduce(time.perf_counter() - tic, op=MPI.MAX)


def sorted_by_coordinates(x: np.ndarray, u: np.ndarray) -> np.ndarray:
    """u in an order independent of the dof numbering (which depends on the ranks)."""
    key = np.round(x, 12)  # exact ties despite 1e-18 noise in the coordinates
    return u[np.lexsort((key[:, 1], key[:, 0]))]


# %% [markdown]
# ## The distributed solve

# %%
problem, result, seconds = solve_on(world)
owned = world.gather(problem.V.dofmap.index_map.size_local, root=0)
errors = solution_errors(problem, square_contact(), result)
say(f"{world.size} ranks own {owned} of {problem.V.dofmap.index_map.size_global} dofs")
say(
    f"{'converged' if result.converged else 'NOT converged'} after {result.iterations} "
    f"iterations in {seconds:.1f} s; |u - u_h|_1 = {errors['energy']:.3e}, "
    f"contact nodes {np.count_nonzero(result.contact)} of {problem.n_signorini}"
)
gathered = gather_p1(result.u)  # collective: every rank sends its owned dofs to rank 0

# %% [markdown]
# ## The same problem on rank 0 alone
#
# Only rank 0 takes part (COMM_SELF); the other ranks wait at the end of the script.

# %%
if world.rank == 0:
    serial, serial_result, serial_seconds = solve_on(MPI.COMM_SELF)
    x_par, u_par, _ = gathered
    x_ser, u_ser, _ = gather_p1(serial_result.u)
    u_diff = float(
        np.abs(sorted_by_coordinates(x_par, u_par) - sorted_by_coordinates(x_ser, u_ser)).max()
        / np.abs(u_ser).max()
    )
    phi_diff = float(
        np.abs(result.phi - serial_result.phi).max() / max(np.abs(serial_result.phi).max(), 1e-300)
    )
    say(f"serial: {serial_result.iterations} iterations in {serial_seconds:.1f} s")
    say(f"max |u_parallel - u_serial| / max |u| = {u_diff:.1e}, same for phi: {phi_diff:.1e}")
    path = write_results(
        world,
        args.out,
        dict(
            ranks=world.size,
            owned=owned,
            cells=args.cells,
            converged=bool(result.converged),
            iterations=int(result.iterations),
            serial_iterations=int(serial_result.iterations),
            u_rel_diff=u_diff,
            phi_rel_diff=phi_diff,
            errors=errors,
            seconds=seconds,
            serial_seconds=serial_seconds,
        ),
    )
    say(f"numbers in {path}")
world.barrier()
