"""C^{-1} over the ranks through its interface (coupling.preconditioners.interface_coarse)
against a direct solve of the whole C, on a grid of square subdomains whose ranks meet
along a jagged interface; writes the worst relative differences to the JSON file in
argv[1]."""
import json
import sys

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from mpi4py import MPI

import coupling.preconditioners.interface_coarse as interface_coarse
from coupling.preconditioners.interface_coarse import (
    InterfaceCoarseFactor,
    RedundantCoarseFactor,
    coarse_factor,
    vertex_rank_range,
)

comm = MPI.COMM_WORLD
nc = 24  # subdomains per side; vertex (i, j) is i * (nc + 1) + j
rng = np.random.default_rng(3)  # the same numbers on every rank


def vertex(i, j):
    return i * (nc + 1) + j


# ranks by rows of subdomains, the boundaries between them shifted column by column
row, col = np.divmod(np.arange(nc * nc), nc)
subdomain_rank = np.minimum((row + (col % 3)) * comm.size // (nc + 2), comm.size - 1)
corners = np.stack(
    [vertex(row, col), vertex(row, col + 1), vertex(row + 1, col + 1), vertex(row + 1, col)], 1
)
n_v = (nc + 1) ** 2
# C: random positive couplings between the corners of each subdomain, plus a shift
pairs = np.array([(a, b) for a in range(4) for b in range(a + 1, 4)])
i, j = corners[:, pairs[:, 0]].ravel(), corners[:, pairs[:, 1]].ravel()
w = rng.uniform(0.5, 1.5, i.size)
off = sp.coo_matrix((w, (i, j)), shape=(n_v, n_v))
off = (off + off.T).tocsr()
C = (sp.diags(np.asarray(off.sum(axis=1)).ravel() + 0.1) - off).tocsr()
# the coarse edges with the subdomains on their two sides (-1 outside)
edges, sides = [], []
for r in range(nc + 1):
    for c in range(nc):  # horizontal edge from (r, c) to (r, c + 1)
        edges.append((vertex(r, c), vertex(r, c + 1)))
        sides.append((r * nc + c if r < nc else -1, (r - 1) * nc + c if r > 0 else -1))
        edges.append((vertex(c, r), vertex(c + 1, r)))  # vertical, from (c, r) to (c + 1, r)
        sides.append((c * nc + r if r < nc else -1, c * nc + r - 1 if r > 0 else -1))
ranks = vertex_rank_range(np.array(edges), np.array(sides), subdomain_rank, n_v)
lowest, highest = ranks
shared = lowest != highest
inside = ~shared & (lowest == comm.rank)

b = rng.standard_normal(n_v)
split = rng.dirichlet(np.ones(comm.size), n_v)  # S's values split over all ranks
mine = np.where(inside, b, 0.0) + np.where(shared, b * split[:, comm.rank], 0.0)
expected = spla.spsolve(C.tocsc(), b)
scale = np.abs(expected).max()

factor = coarse_factor(comm, C, ranks)
x = factor.solve(mine)
local = inside | shared
redundant = RedundantCoarseFactor(comm, C).solve(mine)
interface_coarse.INTERFACE_COARSE_MAX_VERTICES = int(shared.sum()) - 1  # one too many
beyond = coarse_factor(comm, C, ranks)
# every corner of this rank's subdomains is inside or shared
needed = np.zeros(n_v, dtype=bool)
needed[corners[subdomain_rank == comm.rank].ravel()] = True
report = {
    "factor": type(factor).__name__,
    "interface": float(np.abs(x[local] - expected[local]).max() / scale),
    "zero_elsewhere": bool(np.all(x[~local] == 0.0)),
    "redundant": float(np.abs(redundant - expected).max() / scale),
    "beyond_the_limit": type(beyond).__name__,
    "corners_local": bool(np.all(local[needed])),
    "shared": int(shared.sum()),
    "inside": int(inside.sum()),
}
reports = comm.gather(report)
if comm.rank == 0:
    total = sum(r["inside"] for r in reports) + reports[0]["shared"]
    with open(sys.argv[1], "w") as f:
        json.dump({"ranks": reports, "vertices": n_v, "covered": total}, f)
factor.destroy()
assert isinstance(factor, InterfaceCoarseFactor) or comm.size == 1
