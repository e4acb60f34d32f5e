"""Work done once, on rank 0, for every rank: the one home of "compute on rank 0, then
broadcast the result or the error".

Serial set-up steps (gmsh, the boundary walk, the coarse structure, S_h) run on rank 0
while the other ranks wait in a polled non-blocking barrier (they sleep instead of
spinning in MPI, so rank 0 may use every core). An exception raised on rank 0 is raised
on every rank, so no rank is left waiting in a collective call. Also the gathers of
rank-local results (to rank 0, or arrays to every rank).
"""
from __future__ import annotations

import os
import time
from typing import Callable, TypeVar

import numpy as np
from mpi4py import MPI

__all__ = [
    "run_on_root",
    "broadcast_from_root",
    "array_from_root",
    "gather_to_root",
    "allgather_arrays",
    "threads_per_rank",
]

T = TypeVar("T")


def threads_per_rank(comm: MPI.Comm) -> int:
    """BLAS/OpenMP threads for each rank: the cores of the node shared by its ranks, at
    most ``OMP_NUM_THREADS`` when the environment sets it (the user's limit holds).

    An application running under mpirun (the ``fembem`` command, the benchmarks) limits
    the thread pools to this, ``threadpoolctl.threadpool_limits(threads_per_rank(comm))``,
    so that P ranks on P cores do not run P threads each (docs/design/parallel.md).
    """
    node = comm.Split_type(MPI.COMM_TYPE_SHARED)
    ranks_here = node.size
    node.Free()
    cores = max(1, len(os.sched_getaffinity(0)) // ranks_here)
    limit = os.environ.get("OMP_NUM_THREADS", "").strip()
    return min(cores, int(limit)) if limit.isdigit() and int(limit) > 0 else cores


def run_on_root(
    comm: MPI.Comm,
    compute: Callable[[], T],
    *,
    error_prefix: str | None = None,
    all_cores: bool = False,
) -> T | None:
    """``compute()`` on rank 0; its result there, None on the other ranks (collective).

    Parameters
    ----------
    comm
        The communicator whose rank 0 computes.
    compute
        Called on rank 0 only.
    error_prefix
        When given, an exception of ``compute`` is raised on every rank as
        ``RuntimeError(f"{error_prefix}: {type}: {message}")``; otherwise the exception
        itself is raised on every rank (it must be picklable, as built-in ones are).
    all_cores
        Let rank 0 use every core of the process's affinity for its thread pools while
        the other ranks wait (dense algebra such as S_h).
    """
    result, error = None, None
    if comm.rank == 0:
        try:
            if all_cores:
                from threadpoolctl import threadpool_limits

                with threadpool_limits(limits=len(os.sched_getaffinity(0))):
                    result = compute()
            else:
                result = compute()
        except Exception as err:  # noqa: BLE001 - raised on every rank below
            error = (
                RuntimeError(f"{error_prefix}: {type(err).__name__}: {err}")
                if error_prefix is not None
                else err
            )
    if comm.size > 1:
        barrier = comm.Ibarrier()
        while not barrier.Test():
            time.sleep(0.002)
        error = comm.bcast(error, root=0)
    if error is not None:
        raise error
    return result


def broadcast_from_root(
    comm: MPI.Comm, compute: Callable[[], T], *, error_prefix: str | None = None
) -> T:
    """``compute()`` evaluated on rank 0 (:func:`run_on_root`) and sent to every rank
    (pickled: for small results and structures of arrays)."""
    result = run_on_root(comm, compute, error_prefix=error_prefix)
    return comm.bcast(result, root=0) if comm.size > 1 else result


def array_from_root(
    comm: MPI.Comm, compute: Callable[[], np.ndarray], *, all_cores: bool = False
) -> np.ndarray:
    """A dense float array computed once on rank 0 (:func:`run_on_root`) and broadcast
    to every rank as a buffer (no pickling: for large arrays)."""
    if comm.size == 1:
        return np.asarray(compute(), dtype=float)
    result = run_on_root(
        comm, lambda: np.ascontiguousarray(compute(), dtype=float), all_cores=all_cores
    )
    shape = comm.bcast(result.shape if comm.rank == 0 else None, root=0)
    if comm.rank != 0:
        result = np.empty(shape)
    comm.Bcast(result, root=0)
    return result


def gather_to_root(comm: MPI.Comm, obj: T) -> list[T] | None:
    """``comm.gather(obj, root=0)``, without pickling a copy on one rank: [obj] there."""
    return [obj] if comm.size == 1 else comm.gather(obj, root=0)


def allgather_arrays(comm: MPI.Comm, arrays: tuple[np.ndarray, ...]) -> tuple[np.ndarray, ...]:
    """Each int64 array of ``arrays`` (all of one length on a rank) concatenated over the
    ranks in rank order, on every rank (``Allgatherv``, no pickling; in serial the
    arrays themselves)."""
    if comm.size == 1:
        return arrays
    counts = np.array(comm.allgather(len(arrays[0])))
    out = []
    for a in arrays:
        whole = np.empty(int(counts.sum()), dtype=np.int64)
        comm.Allgatherv(np.ascontiguousarray(a, dtype=np.int64), (whole, counts))
        out.append(whole)
    return tuple(out)
