"""The H-matrix S_h on one rank against ``mpirun -n 2`` (distributed by rows,
``bem_cpp.steklov_poincare(..., comm=...)``; docs/design/hmatrix.md, "Under MPI").

Shapes: the circle and the L-shape with n nodes (2D), the box's surface with n squares a
side on each face (3D, ``box``: 6 n^2 + 2 vertices, the tolerance of
``coupling.options.hmatrix_tol`` as a run takes it). ``--layouts`` are ranks x threads a
rank (OpenMP and BLAS): ``1x1 2x1`` (the default) compare the ranks on one thread each,
``1x2`` beside ``2x1`` the threads of one rank against the ranks on the same two cores.

For each shape and n: set-up wall time (the slowest rank, after a barrier) and CPU time
(the largest of the ranks, and their sum: work a rank repeats shows in the sum), one product
``S @ z`` (best of --repeat, each between barriers; the slowest rank), the part of it
outside the collectives (the slowest rank; on a loaded machine a rank waits in a
collective for a descheduled partner), its CPU time (the largest of the ranks,
collectives included: the part of the product the load does not inflate), the number
of collectives, the CG iterations of
its V_h solve and the bytes each rank holds. One rank runs the serial operator
(symmetric storage of V_h, V0_h), two ranks the distributed one. ``uptime`` is printed
before and after: on the shared machine the load inflates wall times (not CPU times).

Run: .venv/bin/python bench/steklov_mpi.py [--sizes 4000 16000] [--shapes circle l-shape]
     [--repeat 5] [--layouts 1x1 2x1]
     .venv/bin/python bench/steklov_mpi.py --shapes box --sizes 32 64 --layouts 1x1 1x2 2x1
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bem_assembly import circle, l_shape  # noqa: E402

SHAPES = {"circle": circle, "l-shape": l_shape, "box": None}
TOL = 1e-10


def boundary(shape: str, n: int) -> tuple[np.ndarray, dict, float]:
    """The nodes, the surface's triangles (3D) and the H-matrix tolerance of ``shape``."""
    if shape != "box":
        return SHAPES[shape](n), {}, TOL
    from bem_cpp.surfaces import cube
    from coupling.options import hmatrix_tol

    X, T = cube(n, 0.5)
    return X, {"triangles": T}, hmatrix_tol(X)


class TimedComm:
    """The two calls of ``bem_cpp.mpi_collectives`` on an mpi4py communicator, timed."""

    def __init__(self, comm) -> None:
        self.comm, self.rank, self.size = comm, comm.rank, comm.size
        self.seconds, self.calls = 0.0, 0

    def _timed(self, f, *args, **kwargs):
        t0 = time.perf_counter()
        f(*args, **kwargs)
        self.seconds += time.perf_counter() - t0
        self.calls += 1

    def Allgatherv(self, *args, **kwargs) -> None:
        self._timed(self.comm.Allgatherv, *args, **kwargs)

    def Reduce_scatter(self, *args, **kwargs) -> None:
        self._timed(self.comm.Reduce_scatter, *args, **kwargs)

    def Allreduce(self, *args, **kwargs) -> None:
        self._timed(self.comm.Allreduce, *args, **kwargs)


def worker(n: int, shape: str, repeat: int) -> None:
    from mpi4py import MPI

    import bem_cpp

    comm = MPI.COMM_WORLD
    timed = TimedComm(comm)
    X, surface, tol = boundary(shape, n)
    comm.Barrier()
    t0, c0 = time.perf_counter(), time.process_time()
    S = bem_cpp.steklov_poincare(
        X, "p1", compression="hmatrix", tol=tol, comm=timed if comm.size > 1 else None, **surface
    )
    wall, setup_cpu = time.perf_counter() - t0, comm.gather(time.process_time() - c0)
    setup = comm.allreduce(wall, op=MPI.MAX)
    z = np.random.default_rng(0).standard_normal(len(X))
    best, work, cpu = np.inf, np.inf, np.inf
    for _ in range(repeat):
        comm.Barrier()
        timed.seconds, timed.calls = 0.0, 0
        t0, c0 = time.perf_counter(), time.process_time()
        S @ z
        wall, c = time.perf_counter() - t0, time.process_time() - c0
        best = min(best, comm.allreduce(wall, op=MPI.MAX))
        work = min(work, comm.allreduce(wall - timed.seconds, op=MPI.MAX))
        cpu = min(cpu, comm.allreduce(c, op=MPI.MAX))
    nbytes = comm.gather(S.nbytes, root=0)
    if comm.rank == 0:
        row = dict(
            n=len(X), shape=shape, ranks=comm.size, setup=setup, setup_cpu=setup_cpu,
            product=best, work=work, cpu=cpu, collectives=timed.calls, cg=S.last_iterations,
            nbytes=nbytes,
        )  # fmt: skip
        print(json.dumps(row), flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[4000, 16000])
    parser.add_argument("--shapes", nargs="+", default=list(SHAPES), choices=list(SHAPES))
    parser.add_argument(
        "--layouts", nargs="+", default=["1x1", "2x1"], help="ranks x threads a rank"
    )
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--worker", nargs=2, metavar=("N", "SHAPE"))
    args = parser.parse_args()
    if args.worker:
        worker(int(args.worker[0]), args.worker[1], args.repeat)
        return
    layouts = [tuple(int(k) for k in layout.split("x")) for layout in args.layouts]
    print(subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())
    print(
        "| shape | n | ranks x threads | set-up [s] | set-up CPU: largest, sum [s] "
        "| product [ms] | outside collectives [ms] | product CPU [ms] | collectives | CG "
        "| MB per rank |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for shape in args.shapes:
        for n in args.sizes:
            for p, threads in layouts:
                env = dict(os.environ, OMP_NUM_THREADS=str(threads))
                env["OPENBLAS_NUM_THREADS"] = str(threads)
                cmd = ["mpirun", "--allow-run-as-root", "--oversubscribe", "--bind-to", "none"]
                cmd += ["-n", str(p)]
                cmd += [sys.executable, __file__, "--worker", str(n), shape]
                cmd += ["--repeat", str(args.repeat)]
                out = subprocess.run(cmd, capture_output=True, text=True, env=env, check=True)
                r = json.loads(out.stdout.strip().splitlines()[-1])
                mb = " / ".join(f"{b / 1e6:.1f}" for b in r["nbytes"])
                cpu = r["setup_cpu"]
                print(
                    f"| {shape} | {r['n']:,} | {p} x {threads} | {r['setup']:.2f} "
                    f"| {max(cpu):.2f}, {sum(cpu):.2f} | {1e3 * r['product']:.1f} "
                    f"| {1e3 * r['work']:.1f} | {1e3 * r['cpu']:.1f} | {r['collectives']} "
                    f"| {r['cg']} | {mb} |",
                    flush=True,
                )
    print(subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())


if __name__ == "__main__":
    main()
