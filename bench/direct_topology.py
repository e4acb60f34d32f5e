"""DOLFINx's ``create_mesh`` against a topology made directly from cells already on their
rank (issue 33; docs/design/parallel.md, "The ninth session").

The structured mesh's cells are written on the rank that owns them
(``fem_py.mesh.structured``), yet DOLFINx 0.5.2's ``create_mesh`` still calls the
partitioner, sends every cell to its rank (itself), builds the dual graph and reorders
the cells before it makes the topology. Its Python layer does not expose
``create_topology`` and ``create_geometry``; the probe ``bench/direct_topology/`` (a
pybind11 module against libdolfinx, built here with CMake into a temporary directory)
calls them on the cells as given.

For each size and rank count, the unit square of ``cells`` x ``cells`` squares cut into
2 triangles is made both ways, each in a fresh process (``mpirun -n P`` for P > 1),
alternating, ``--repeat`` times. Each rank owns a block of whole rows of squares and
ghosts its neighbours' triangles across its outer facets; ``create_mesh`` is given a
partitioner that keeps every cell where it is. The fastest time of each path is printed
(the slowest rank's), with a check that both meshes have the same cells and ghost cells,
area and integral of x^2 + y (to round-off). A measurement for the project's structured
meshes, not a replacement for their path (``fem_py.mesh.distribute``).

    .venv/bin/python bench/direct_topology.py [--cells 1000 2000] [--ranks 1 2] [--repeat 2]
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
SOURCE = HERE / "direct_topology"
PATHS = ("create_mesh", "direct")


def build(into: Path) -> Path:
    """Configure and build the probe module in ``into``; its directory (exit on failure)."""
    import pybind11

    configure = ["cmake", "-S", str(SOURCE), "-B", str(into), "-DCMAKE_BUILD_TYPE=Release"]
    configure += [f"-DPython3_EXECUTABLE={sys.executable}"]  # the one that sees mpi4py
    configure += [f"-Dpybind11_DIR={pybind11.get_cmake_dir()}"]
    for cmd in (
        configure,
        ["cmake", "--build", str(into), "-j2"],
    ):
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            sys.exit(f"error: building the probe failed:\n{(proc.stdout + proc.stderr)[-2000:]}")
    return into


def worker(cells: int, path: str, module_dir: str) -> None:
    """Make the mesh one way on every rank of COMM_WORLD, time it (the slowest rank), and
    print the time and two integrals over it on rank 0.

    The squares are split into blocks of whole rows, one block per rank; a rank owns both
    triangles of its squares and ghosts its neighbours' triangles across its first and
    last rows' outer facets."""
    import numpy as np
    import ufl
    from dolfinx import fem
    from dolfinx import mesh as dmesh
    from mpi4py import MPI

    from fem_py.mesh.distribute import destinations

    comm = MPI.COMM_WORLD
    rank, size = comm.rank, comm.size
    first, last = rank * cells // size, (rank + 1) * cells // size  # my rows of squares

    def triangles(rows: np.ndarray, which: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
        """Triangles ``which`` (0: below the diagonal, 1: above) of the squares of ``rows``:
        their nodes and their input numbers 2 (i cells + j) + k."""
        i, j, k = (a.ravel() for a in np.meshgrid(rows, np.arange(cells), which, indexing="ij"))
        corner = i * (cells + 1) + j  # nodes row by row, (cells + 1)^2 of them
        nodes = np.where(
            (k == 0)[:, None],
            np.stack([corner, corner + 1, corner + cells + 2], axis=1),
            np.stack([corner, corner + cells + 2, corner + cells + 1], axis=1),
        )
        return nodes.astype(np.int64), 2 * (i * cells + j) + k

    owned, numbers = triangles(np.arange(first, last), (0, 1))
    # ghosts: the upper triangles of the row below, the lower ones of the row above
    below = triangles(np.arange(first - 1, first), (1,)) if rank > 0 else None
    above = triangles(np.arange(last, last + 1), (0,)) if rank < size - 1 else None
    n_nodes = (cells + 1) ** 2
    block = np.arange(rank * n_nodes // size, (rank + 1) * n_nodes // size)
    axis = np.linspace(0.0, 1.0, cells + 1)
    x = np.stack([axis[block // (cells + 1)], axis[block % (cells + 1)]], axis=1)
    domain = ufl.Mesh(ufl.VectorElement("Lagrange", ufl.triangle, 1))

    comm.Barrier()
    tic = time.perf_counter()
    if path == "create_mesh":

        def partitioner(comm_, nparts, tdim, local_cells, ghost_mode):
            # every cell stays here; the first row's lower and the last row's upper
            # triangles are ghosted by the neighbour across their outer facet
            links = [np.zeros((0, 2), dtype=np.int64)]
            per_row = 2 * cells
            if rank > 0:
                lower = np.arange(0, per_row, 2)
                links.append(np.stack([lower, np.full_like(lower, rank - 1)], axis=1))
            if rank < size - 1:
                upper = np.arange(len(owned) - per_row + 1, len(owned), 2)
                links.append(np.stack([upper, np.full_like(upper, rank + 1)], axis=1))
            return destinations(np.full(len(owned), rank), np.concatenate(links))

        msh = dmesh.create_mesh(comm, owned, x, domain, partitioner=partitioner)
    else:
        sys.path.insert(0, module_dir)
        import direct_topology

        ghosts = [g for g in (below, above) if g is not None]
        all_cells = np.concatenate([owned] + [g[0] for g in ghosts])
        original = np.concatenate([numbers] + [g[1] for g in ghosts]).astype(np.int64)
        owners = [np.full(len(below[0]), rank - 1)] if below is not None else []
        owners += [np.full(len(above[0]), rank + 1)] if above is not None else []
        ghost_owners = np.concatenate(owners).astype(np.int32) if owners else np.zeros(0, np.int32)
        cpp_mesh = direct_topology.triangle_mesh(comm, all_cells, x, original, ghost_owners)
        msh = dmesh.Mesh(cpp_mesh, domain)
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


def run(cells: int, path: str, ranks: int, module_dir: Path) -> dict:
    """One fresh run of ``path`` (``mpirun -n ranks`` for more than one rank)."""
    cmd = [sys.executable, __file__, "--worker", path, "--cells", str(cells)]
    cmd += ["--module-dir", str(module_dir)]
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
    parser.add_argument("--module-dir", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if any(c < 1 for c in args.cells) or args.repeat < 1 or any(p < 1 for p in args.ranks):
        print("error: --cells, --ranks and --repeat must be >= 1", file=sys.stderr)
        return 2
    if min(args.cells) < max(args.ranks):
        print("error: --cells must be >= every --ranks (a rank owns whole rows)", file=sys.stderr)
        return 2
    if args.worker:
        worker(args.cells[0], args.worker, args.module_dir)
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        module_dir = build(Path(tmp))
        print("| cells a side | triangles | ranks | create_mesh | direct | ratio | the same mesh |")
        print("|---:|---:|---:|---:|---:|---:|---|")
        for cells in args.cells:
            for ranks in args.ranks:
                runs = {path: [] for path in PATHS}
                for _ in range(args.repeat):
                    for path in PATHS:
                        runs[path].append(run(cells, path, ranks, module_dir))
                best = {path: min(r["seconds"] for r in runs[path]) for path in PATHS}
                a, b = runs["create_mesh"][0], runs["direct"][0]
                same = a["cells"] == b["cells"] == 2 * cells * cells and a["ghosts"] == b["ghosts"]
                same = same and all(
                    abs(a[k] - b[k]) <= 1e-12 * abs(a[k]) for k in ("area", "integral")
                )
                print(
                    f"| {cells} | {2 * cells * cells} | {ranks} | {best['create_mesh']:.3f} s | "
                    f"{best['direct']:.3f} s | {best['create_mesh'] / best['direct']:.2f}x | "
                    f"{'yes' if same else 'NO'} |",
                    flush=True,
                )
    return 0


if __name__ == "__main__":
    sys.exit(main())
