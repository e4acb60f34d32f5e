"""coupling.distributed.RowBlocks on this communicator against the whole matrix: the
rows each rank keeps, the product, full(), and the one-line error for a wrong block.
Writes a JSON report (rank 0) to argv[1]."""
import json
import sys

import numpy as np
from mpi4py import MPI

from coupling.distributed import RowBlocks

comm = MPI.COMM_WORLD
n = 7  # not a multiple of 2 or 3: uneven row blocks
rng = np.random.default_rng(0)
A = rng.standard_normal((n, n))  # the same on every rank (same seed)
z = rng.standard_normal(n)
S = RowBlocks.from_root(comm, lambda: A.copy())
rows = comm.gather(S.block, root=0)
product = S @ z
full = S.full()
try:
    RowBlocks(comm, np.zeros((n, n)), n)
    error = None
except ValueError as err:
    error = str(err)
errors = comm.gather(error, root=0)
if comm.rank == 0:
    json.dump(
        {
            "row_counts": [len(r) for r in rows],
            "rows_equal": bool(np.array_equal(np.concatenate(rows), A)),
            # the same dot products, each computed by one rank: within the round-off bound of
            # a length-n dot product, n eps |A| |z|, of the serial product
            "product_within_roundoff": bool(
                np.all(np.abs(product - A @ z) <= n * np.finfo(float).eps * (np.abs(A) @ np.abs(z)))
            ),
            "full_equal": bool(np.array_equal(full, A)),
            "errors": errors,
        },
        open(sys.argv[1], "w"),
    )
