"""The box of fem_py.mesh.box written down in parallel, against ``dolfinx.mesh.create_box``
(tests/test_box_mesh.py runs it on 1, 2 and 3 ranks): rank 0 writes JSON with

- ``same_tetrahedra``: the global set of tetrahedra (their vertices' lattice indices)
  equals create_box's;
- ``open_facets_inside``: facets of owned cells that have no second local cell but lie
  inside the box (0 when the shared-facet ghost layer is complete);
- ``owned``: the owned cells of every rank.

Usage: ``mpirun -n 2 python tests/mpi/box_mesh_check.py out.json``.
"""
from __future__ import annotations

import json
import sys

import numpy as np
from dolfinx import mesh as dmesh
from mpi4py import MPI

from fem_py.mesh.box import box_mesh

N, CENTER, WIDTH = 5, np.array([0.1, -0.2, 0.3]), 0.5


def _tetrahedra(comm: MPI.Comm, msh) -> np.ndarray | None:
    """On rank 0 the sorted rows of every owned cell's sorted lattice vertex numbers."""
    owned = msh.topology.index_map(3).size_local
    x = msh.geometry.x[:, :3]
    ijk = np.rint((x - (CENTER - WIDTH / 2)) / (WIDTH / N)).astype(np.int64)
    number = ijk @ np.array([1, N + 1, (N + 1) ** 2])
    cells = np.sort(number[msh.geometry.dofmap.array.reshape(-1, 4)[:owned]], axis=1)
    every = comm.gather(cells, root=0)
    return None if comm.rank else np.unique(np.concatenate(every), axis=0)


def _open_facets_inside(msh) -> int:
    """Facets of owned cells with one local cell whose midpoint is inside the box."""
    top = msh.topology
    top.create_connectivity(2, 3)
    f2c = top.connectivity(2, 3)
    owned = top.index_map(3).size_local
    count = np.diff(f2c.offsets)
    single = np.flatnonzero(count == 1)
    single = single[f2c.array[f2c.offsets[single]] < owned]
    mid = dmesh.compute_midpoints(msh, 2, single.astype(np.int32))
    inside = np.all(np.abs(mid - CENTER) < WIDTH / 2 - 1e-12, axis=1)
    return int(inside.sum())


def main(out: str) -> None:
    comm = MPI.COMM_WORLD
    msh, _, _ = box_mesh(comm, CENTER, WIDTH, WIDTH / N)
    lo, hi = CENTER - WIDTH / 2, CENTER + WIDTH / 2
    ref = dmesh.create_box(comm, [lo, hi], [N, N, N], dmesh.CellType.tetrahedron)
    mine, theirs = _tetrahedra(comm, msh), _tetrahedra(comm, ref)
    open_inside = comm.gather(_open_facets_inside(msh), root=0)
    owned = comm.gather(msh.topology.index_map(3).size_local, root=0)
    if comm.rank == 0:
        result = {
            "ranks": comm.size,
            "same_tetrahedra": bool(np.array_equal(mine, theirs)),
            "tetrahedra": len(mine),
            "open_facets_inside": int(sum(open_inside)),
            "owned": owned,
        }
        with open(out, "w") as f:
            json.dump(result, f)


if __name__ == "__main__":
    main(sys.argv[1])
