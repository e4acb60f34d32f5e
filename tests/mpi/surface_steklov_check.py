"""Under mpirun: the 3D H-matrix S_h distributed over the ranks against the serial one on
every rank, its products and the blocks of W_h read from it
(tests/test_mpi_surface_steklov.py). Arguments: output .npz, icosphere level."""
from __future__ import annotations

import sys

import numpy as np
from mpi4py import MPI

import bem_cpp
from bem_cpp.surfaces import icosphere

comm = MPI.COMM_WORLD
X, T = icosphere(int(sys.argv[2]), 0.8)
x = np.c_[np.sin(3 * X[:, 0]) + X[:, 2], X[:, 1] ** 2]
distributed = bem_cpp.steklov_poincare(X, triangles=T, compression="hmatrix", comm=comm)
y = distributed @ x
iterations = distributed.last_iterations
serial = bem_cpp.steklov_poincare(X, triangles=T, compression="hmatrix")
y_serial = serial @ x
# W_h on the nodes of the cap z > 0.4 (a patch, as Gamma_s), read from the H-matrices
cap = np.flatnonzero(X[:, 2] > 0.4)
block, block_serial = distributed.hypersingular_block(cap), serial.hypersingular_block(cap)
# the same block from operators whose blocks are held in single precision
kw = dict(triangles=T, compression="hmatrix", tol=1e-5)
single = bem_cpp.steklov_poincare(X, comm=comm, **kw).hypersingular_block(cap).entries
single_serial = bem_cpp.steklov_poincare(X, **kw).hypersingular_block(cap).entries
same = comm.allgather(y.tobytes() + block.tobytes() + single.tobytes())
bytes_per_rank = comm.allgather(distributed.nbytes)
if comm.rank == 0:
    np.savez(
        sys.argv[1],
        y=y,
        y_serial=y_serial,
        block=block,
        block_serial=block_serial,
        single=single,
        single_serial=single_serial,
        block_integrated=bem_cpp.hypersingular(X, triangles=T, block=cap),
        iterations=[iterations, serial.last_iterations],
        same_everywhere=all(s == same[0] for s in same),
        bytes_per_rank=bytes_per_rank,
        serial_bytes=serial.nbytes,
    )
