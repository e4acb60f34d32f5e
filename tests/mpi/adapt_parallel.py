"""The adaptive loop on the ranks of COMM_WORLD (tests/test_mpi_adapt.py): per level the
records and errors, and the sorted cell midpoints and subdomain tags of the last mesh,
written as JSON to argv[1] by rank 0. argv[2]: "corner" (L-shape corner singularity) or
"contact" (coupling.manufactured.square_contact)."""
import json
import sys
from pathlib import Path

import numpy as np
from dolfinx import mesh as dmesh
from mpi4py import MPI

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from test_adapt import builder_of, corner_solution  # noqa: E402

from coupling.adapt import AdaptOptions, adapt  # noqa: E402
from coupling.manufactured import solution_errors, square_contact  # noqa: E402
from coupling.options import SolverOptions  # noqa: E402
from fem_py.forms import make_material  # noqa: E402
from fem_py.mesh import GeometrySpec, build_domain  # noqa: E402

comm = MPI.COMM_WORLD
case = sys.argv[2]
if case == "corner":
    exact, material, zero_f, shape, steps = (
        corner_solution(),
        make_material("linear"),
        True,
        "lshape",
        5,
    )
else:
    exact, material, zero_f, shape, steps = (
        square_contact(),
        make_material("carstensen"),
        False,
        "square",
        3,
    )
domain = build_domain(
    comm,
    GeometrySpec(shape, h=1 / 16, subdomain_size=1 / 8, signorini=exact.signorini, structured=True),
)
levels = adapt(
    builder_of(exact, material, zero_f=zero_f),
    domain,
    SolverOptions(),
    AdaptOptions(steps=steps, theta=0.5),
)
rows = []
for level in levels:
    errors = solution_errors(level.problem, exact, level.solution)
    rows.append(
        {**level.record(), "error": errors["energy"], "mismatch": errors["contact_mismatch"]}
    )
last = levels[-1].domain
n = last.mesh.topology.index_map(2).size_local
mids = dmesh.compute_midpoints(last.mesh, 2, np.arange(n, dtype=np.int32))[:, :2]
tags = np.zeros(n)
tags[last.cell_tags.indices[last.cell_tags.indices < n]] = last.cell_tags.values[
    last.cell_tags.indices < n
]
cells = comm.gather(np.column_stack([mids, tags]), root=0)
if comm.rank == 0:
    cells = np.concatenate(cells)
    cells = cells[np.lexsort((cells[:, 1], cells[:, 0]))]
    Path(sys.argv[1]).write_text(json.dumps({"rows": rows, "cells": cells.tolist()}))
