"""``fem_py.mesh.placed.mesh_of_placed_cells`` against ``dolfinx.mesh.create_mesh`` given
the same cells, node blocks and ghost links (tests/test_placed_cells.py runs it on 1, 2 and
3 ranks): a structured square of quadrilaterals cut into triangles and the box of
tetrahedra. Each rank writes JSON: per case, the fields of :func:`summary` that differ
between the two meshes (none when they are the same mesh up to the local order), and the
owned and ghost cell counts.

Usage: ``mpirun -n 3 python tests/mpi/placed_cells_check.py out`` (writes out.<rank>).
"""
from __future__ import annotations

import json
import sys

import numpy as np
import ufl
from dolfinx import fem
from dolfinx import mesh as dmesh
from mpi4py import MPI

from fem_py.mesh.box import box_cells
from fem_py.mesh.distribute import destinations, structured_cells
from fem_py.mesh.placed import mesh_of_placed_cells, p1_domain
from fem_py.mesh.structured import refine


def square_inputs(comm: MPI.Comm):
    """A 6 x 5 grid of coarse squares on [0, 1.2] x [0, 1], each refined into 4 x 4
    squares of 2 triangles, written down over the ranks as the solver does it."""
    nx, ny = 6, 5
    V = np.array([[0.2 * i, 0.2 * j] for j in range(ny + 1) for i in range(nx + 1)])
    q = np.array(
        [
            [i + (nx + 1) * j for i, j in ((a, b), (a + 1, b), (a + 1, b + 1), (a, b + 1))]
            for b in range(ny)
            for a in range(nx)
        ]
    )
    _, cells, x, links = structured_cells(comm, refine(V, q, 4))
    return "triangle", cells, x, links


def box_inputs(comm: MPI.Comm):
    """The unit box of 4 cubes a side, 6 tetrahedra each, in slabs of cubes over the ranks,
    written down as ``fem_py.mesh.box.box_mesh`` does it."""
    return "tetrahedron", *box_cells(comm, np.zeros(3), np.ones(3), 4)


def summary(msh) -> dict:
    """What the mesh is, independent of its local order: the input numbers of the owned and
    the ghost cells with the ghosts' owners and every cell's vertex coordinates, the vertex
    counts, and the integral of the P1 interpolant of x^2 + y + z."""
    top, tdim = msh.topology, msh.topology.dim
    cell_map, vertex_map = top.index_map(tdim), top.index_map(0)
    own, ghosts = cell_map.size_local, cell_map.num_ghosts
    original = np.asarray(top.original_cell_index[: own + ghosts], dtype=np.int64)
    k = tdim + 1
    corners = msh.geometry.x[msh.geometry.dofmap.array.reshape(-1, k)[: own + ghosts]]
    corners = np.sort(corners.round(12).view([("", float)] * 3).ravel().reshape(-1, k), axis=1)
    o, g = np.argsort(original[:own]), own + np.argsort(original[own:])
    V = fem.FunctionSpace(msh, ("Lagrange", 1))
    u = fem.Function(V)
    u.interpolate(lambda p: p[0] ** 2 + p[1] + p[2])
    integral = msh.comm.allreduce(fem.assemble_scalar(fem.form(u * ufl.dx)), op=MPI.SUM)
    return {
        "owned": original[o].tolist(),
        "ghosts": original[g].tolist(),
        "ghost_owners": np.asarray(cell_map.owners)[g - own].tolist(),
        "corners": corners[np.concatenate([o, g])].tolist(),
        "vertices": [vertex_map.size_local, vertex_map.num_ghosts, vertex_map.size_global],
        "integral": round(integral, 12),
    }


def main(out: str) -> None:
    comm = MPI.COMM_WORLD
    result = {}
    for name, inputs in (("square", square_inputs), ("box", box_inputs)):
        cell, cells, x, links = inputs(comm)
        placed = summary(mesh_of_placed_cells(comm, cell, cells, x, links))

        def partitioner(comm_, nparts, tdim, local_cells, ghost_mode):
            return destinations(np.full(len(cells), comm.rank, dtype=np.int64), links)

        made = summary(dmesh.create_mesh(comm, cells, x, p1_domain(cell), partitioner=partitioner))
        result[name] = {
            "differ": [key for key in made if made[key] != placed[key]],
            "owned": len(placed["owned"]),
            "ghosts": len(placed["ghosts"]),
        }
    with open(f"{out}.{comm.rank}", "w") as f:
        json.dump(result, f)


if __name__ == "__main__":
    main(sys.argv[1])
