"""The adaptive loop on a body in R^3 on the ranks of COMM_WORLD (tests/test_mpi_adapt.py):
coupling.manufactured.box_contact from 4 cubes per side, two refinements; per level the
records, energy errors and contact mismatches, and the sorted cell midpoints of the last
mesh with the sorted (centroid, tag) rows of its boundary triangles, written as JSON to
argv[1] by rank 0."""
import json
import sys
from pathlib import Path

import numpy as np
from dolfinx import mesh as dmesh
from mpi4py import MPI

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from test_adapt_solid import adapt_box  # noqa: E402

from coupling.manufactured import box_contact, solution_errors  # noqa: E402

comm = MPI.COMM_WORLD
exact = box_contact()
levels = adapt_box(comm, exact)
rows = []
for level in levels:
    errors = solution_errors(level.problem, exact, level.solution)
    rows.append(
        {**level.record(), "error": errors["energy"], "mismatch": errors["contact_mismatch"]}
    )
last = levels[-1]
msh = last.domain.mesh
n = msh.topology.index_map(3).size_local
mids = dmesh.compute_midpoints(msh, 3, np.arange(n, dtype=np.int32))
cells = comm.gather(mids, root=0)
b = last.problem.boundary  # the same on every rank
faces = np.column_stack([b.nodes[b.triangles].mean(axis=1), b.triangle_tags])
if comm.rank == 0:
    cells = np.concatenate(cells)
    cells = cells[np.lexsort((cells[:, 2], cells[:, 1], cells[:, 0]))]
    faces = faces[np.lexsort((faces[:, 2], faces[:, 1], faces[:, 0]))]
    out = {"rows": rows, "cells": cells.tolist(), "faces": faces.tolist()}
    Path(sys.argv[1]).write_text(json.dumps(out))
