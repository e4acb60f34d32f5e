"""The distributed H-matrix S_h (bem_cpp.steklov_poincare(..., comm=COMM_WORLD)) against
the serial operator built on every rank: products (1-D and 2-D), flux, CG iterations,
bytes per rank, sameness across ranks. argv[1]: the .npz rank 0 writes; argv[2]: n;
argv[3]: shape ("circle" or "lshape", n nodes; "sphere": the icosphere |x| = 0.8 of level n);
argv[4]: flux space; argv[5] (optional): the kernel, "laplace" (default) or "lame" (E = 2,
nu = 0.3: the plane-strain S_h, 2 n dofs; on the sphere the 3D one, 3 dofs per vertex)."""
import sys
from pathlib import Path

import numpy as np
from mpi4py import MPI

import bem_cpp
from bem_cpp.surfaces import icosphere

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from test_bem_polygons import circle, l_shape  # noqa: E402

comm = MPI.COMM_WORLD
out, n, shape, flux = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
kernel = {"laplace": "laplace", "lame": ("lame", 2.0, 0.3)}[(sys.argv[5:] or ["laplace"])[0]]
if shape == "sphere":
    X, T = icosphere(n, 0.8)
    tol = 1e-8
else:
    X, T = {"circle": circle, "lshape": l_shape}[shape](n), None
    tol = 1e-10
kw = dict(compression="hmatrix", tol=tol, kernel=kernel, triangles=T)
serial = bem_cpp.steklov_poincare(X, flux, **kw)
S = bem_cpp.steklov_poincare(X, flux, comm=comm, **kw)
z = np.random.default_rng(7).standard_normal((S.shape[0], 3))
y, y_serial = S @ z[:, 0], serial @ z[:, 0]
iterations = (S.last_iterations, serial.last_iterations)
Y, Y_serial = S @ z, serial @ z
F, F_serial = S.flux(z), serial.flux(z)
same = [np.array_equal(a, comm.bcast(a, root=0)) for a in (y, Y, F)]
bytes_per_rank = comm.gather(S.nbytes, root=0)
same_everywhere = comm.allreduce(all(same), op=MPI.LAND)
if comm.rank == 0:
    np.savez(
        out,
        y=y,
        y_serial=y_serial,
        Y=Y,
        Y_serial=Y_serial,
        F=F,
        F_serial=F_serial,
        iterations=iterations,
        bytes_per_rank=bytes_per_rank,
        serial_bytes=serial.nbytes,
        same_everywhere=same_everywhere,
        shape=S.shape,
    )
