"""The arrays of fem_py.boundary.surface.SurfaceMap for the box and the ball, written as
JSON by rank 0 (tests/test_surface_map.py compares 1 and 2 ranks).

Usage: ``mpirun -n 2 python tests/mpi/surface_map_check.py out.json``.
"""
from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

import numpy as np
from dolfinx import fem
from mpi4py import MPI

from fem_py.boundary.surface import SurfaceMap
from fem_py.mesh.ball import ball_mesh
from fem_py.mesh.box import box_mesh
from fem_py.mesh.tet_distribute import solid_mesh
from fem_py.mesh.tet_file import read_tet_msh

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from solid_files import solid_msh  # noqa: E402


def _arrays(V, tags, signorini) -> dict:
    s = SurfaceMap(V, tags, signorini)
    u = fem.Function(V)
    u.interpolate(lambda x: np.sin(x[0]) + x[1] * x[2])
    ones = u.vector.duplicate()
    ones.set(0.0)
    s.scatter_add(np.ones(s.n_gamma), ones)
    out = {
        key: np.asarray(getattr(s, key)).tolist()
        for key in (
            "nodes",
            "triangles",
            "triangle_tags",
            "signorini",
            "on_signorini",
            "node_normals",
            "triangle_normals",
            "triangle_areas",
            "area",
            "volume",
        )
    }
    out["trace"] = s.gather(u.vector).tolist()
    out["scatter_sum"] = float(ones.sum())
    out["ranks"] = V.mesh.comm.size
    return out


def compute(comm: MPI.Comm) -> dict:
    """The surface arrays of the box (n = 4, Signorini on bottom and left), of the ball
    (Signorini on its lower hemisphere) and of a gmsh file (an unstructured cube,
    Signorini on its group "bottom")."""
    msh, tags, names = box_mesh(comm, [0.1, -0.2, 0.3], 0.5, 0.125)
    V = fem.FunctionSpace(msh, ("Lagrange", 1))
    box = _arrays(V, tags, [names["bottom"], names["left"]])
    try:  # an unknown Signorini tag: the same one-line ValueError on every rank
        SurfaceMap(V, tags, [99])
        refused = ""
    except ValueError as err:
        refused = str(err)
    box["refused_everywhere"] = comm.allgather(refused)
    msh, tags, names = ball_mesh(comm, [0.0, 0.1, 0.0], 0.4, 0.15)
    V = fem.FunctionSpace(msh, ("Lagrange", 1))
    ball = _arrays(V, tags, [names["bottom"]])
    solid = None
    if comm.rank == 0:
        with tempfile.TemporaryDirectory() as tmp:
            solid = read_tet_msh(solid_msh(Path(tmp) / "cube.msh", h=0.3))
    msh, tags, names = solid_mesh(comm, solid)
    V = fem.FunctionSpace(msh, ("Lagrange", 1))
    file = _arrays(V, tags, [names["bottom"]])
    return {"box": box, "ball": ball, "file": file}


if __name__ == "__main__":
    result = compute(MPI.COMM_WORLD)
    if MPI.COMM_WORLD.rank == 0:
        with open(sys.argv[1], "w") as f:
            json.dump(result, f)
