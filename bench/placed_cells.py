"""DOLFINx's ``create_mesh`` against ``fem_py.mesh.placed.mesh_of_placed_cells``, the path
of the project's structured meshes (issue 33; docs/design/parallel.md, "The ninth session"
and "The tenth session").

The structured meshes write each rank's own cells on that rank, yet DOLFINx 0.5.2's
``create_mesh`` still calls the partitioner, sends every cell to its rank (itself), builds
the dual graph and reorders the cells before it makes the topology;
``mesh_of_placed_cells`` (the module ``fem_py.mesh._placed_cells``) calls
``create_topology`` and ``create_geometry`` on the cells as given.

For each size and rank count, the unit square of ``cells`` x ``cells`` squares cut into
2 triangles is made both ways, each in a fresh process (``mpirun -n P`` for P > 1),
alternating, ``--repeat`` times. Each rank owns a block of whole rows of squares and
ghosts its neighbours' triangles across its outer facets; both paths get the same cells,
node blocks and ghost links (``create_mesh`` through a partitioner that keeps every cell
where it is). The fastest time of each path is printed (the slowest rank's), with a check
that both meshes have the same cells and ghost cells, area and integral of x^2 + y (to
round-off).

    .venv/bin/python bench/placed_cells.py [--cells 1000 2000] [--ranks 1 2] [--repeat 2]
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

PATHS = ("create_mesh", "placed")


def worker(cells: int, path: str) -> None:
    """Make the mesh one way on every rank of COMM_WORLD, time it (the slowest rank), and
    print the time and two integrals over it on rank 0.

    The squares are split into blocks of whole rows, one block per rank; a rank owns both
    triangles of its squares, and the lower triangles of its first row and the upper ones
    of its last row are ghosted by the neighbour across their outer facet."""
    import numpy as np
    import ufl
    from dolfinx import fem
    from dolfinx import mesh as dmesh
    from mpi4py import MPI

    from fem_py.mesh.distribute import destinations
    from fem_py.mesh.placed import mesh_of_placed_cells, p1_domain

    comm = MPI.COMM_WORLD
    rank, size = comm.rank, comm.size
    first, last = rank * cells // size, (rank + 1) * cells // size  # my rows of squares
    # triangle k (0: below the diagonal, 1: above) of square j of row i: 2 (i cells + j) + k
    i, j, k = (
        a.ravel()
        for a in np.meshgrid(np.arange(first, last), np.arange(cells), (0, 1), indexing="ij")
    )
    corner = i * (cells + 1) + j  # nodes row by row, (cells + 1)^2 of them
    owned = np.where(
        (k == 0)[:, None],
        np.stack([corner, corner + 1, corner + cells + 2], axis=1),
        np.stack([corner, corner + cells + 2, corner + cells + 1], axis=1),
    ).astype(np.int64)
    per_row = 2 * cells
    links = [np.zeros((0, 2), dtype=np.int64)]
    if rank > 0:
        lower = np.arange(0, per_row, 2)
        links.append(np.stack([lower, np.full_like(lower, rank - 1)], axis=1))
    if rank < size - 1:
        upper = np.arange(len(owned) - per_row + 1, len(owned), 2)
        links.append(np.stack([upper, np.full_like(upper, rank + 1)], axis=1))
    links = np.concatenate(links)
    n_nodes = (cells + 1) ** 2
    block = np.arange(rank * n_nodes // size, (rank + 1) * n_nodes // size)
    axis = np.linspace(0.0, 1.0, cells + 1)
    x = np.stack([axis[block // (cells + 1)], axis[block % (cells + 1)]], axis=1)

    def partitioner(comm_, nparts, tdim, local_cells, ghost_mode):
        return destinations(np.full(len(owned), rank), links)

    comm.Barrier()
    tic = time.perf_counter()
    if path == "create_mesh":
        msh = dmesh.create_mesh(comm, owned, x, p1_domain("triangle"), partitioner=partitioner)
    else:
        msh = mesh_of_placed_cells(comm, "triangle", owned, x, links)
    comm.Barrier()
    seconds = time.perf_counter() - tic

    V = fem.FunctionSpace(msh, ("Lagrange", 1))
    u = fem.Function(V)
    u.interpolate(lambda p: p[0] ** 2 + p[1])
    total = {
        "area": fem.assemble_scalar(fem.form(1.0 * ufl.dx(domain=msh))),
        "integral": fem.assemble_scalar(fem.form(u * ufl.dx)),
    }
    total = {k: comm.allreduce(v, op=MPI.SUM) for k, v in total.items()}
    cell_map = msh.topology.index_map(2)
    n_cells = comm.allreduce(cell_map.size_local, op=MPI.SUM)
    n_ghosts = comm.allreduce(cell_map.num_ghosts, op=MPI.SUM)
    if rank == 0:
        print(
            json.dumps(
                {"path": path, "seconds": seconds, "cells": n_cells, "ghosts": n_ghosts, **total}
            )
        )


def run(cells: int, path: str, ranks: int) -> dict:
    """One fresh run of ``path`` (``mpirun -n ranks`` for more than one rank)."""
    cmd = [sys.executable, __file__, "--worker", path, "--cells", str(cells)]
    if ranks > 1:
        mpirun = ["mpirun", "--allow-run-as-root", "--oversubscribe", "--bind-to", "none"]
        cmd = mpirun + ["-n", str(ranks)] + cmd
    proc = subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ))
    if proc.returncode != 0:
        output = (proc.stdout + proc.stderr)[-2000:]
        sys.exit(f"error: the {path} run on {ranks} rank(s) failed:\n{output}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, nargs="+", default=[1000], help="squares a side")
    parser.add_argument("--ranks", type=int, nargs="+", default=[1], help="rank counts (default 1)")
    parser.add_argument("--repeat", type=int, default=2, help="runs of each path (default 2)")
    parser.add_argument("--worker", choices=PATHS, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if any(c < 1 for c in args.cells) or args.repeat < 1 or any(p < 1 for p in args.ranks):
        print("error: --cells, --ranks and --repeat must be >= 1", file=sys.stderr)
        return 2
    if min(args.cells) < max(args.ranks):
        print("error: --cells must be >= every --ranks (a rank owns whole rows)", file=sys.stderr)
        return 2
    if args.worker:
        worker(args.cells[0], args.worker)
        return 0
    print("| cells a side | triangles | ranks | create_mesh | placed | ratio | the same mesh |")
    print("|---:|---:|---:|---:|---:|---:|---|")
    for cells in args.cells:
        for ranks in args.ranks:
            runs = {path: [] for path in PATHS}
            for _ in range(args.repeat):
                for path in PATHS:
                    runs[path].append(run(cells, path, ranks))
            best = {path: min(r["seconds"] for r in runs[path]) for path in PATHS}
            a, b = runs["create_mesh"][0], runs["placed"][0]
            same = a["cells"] == b["cells"] == 2 * cells * cells and a["ghosts"] == b["ghosts"]
            same = same and all(abs(a[k] - b[k]) <= 1e-12 * abs(a[k]) for k in ("area", "integral"))
            print(
                f"| {cells} | {2 * cells * cells} | {ranks} | {best['create_mesh']:.3f} s | "
                f"{best['placed']:.3f} s | {best['create_mesh'] / best['placed']:.2f}x | "
                f"{'yes' if same else 'NO'} |",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
