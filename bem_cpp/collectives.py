"""The two collectives of a distributed bem_cpp operator, with mpi4py.

The compiled operator (``bem_cpp/include/bem/communicator.hpp``) does not link MPI: it
calls back into Python for an Allgatherv of row blocks and for the sum of partial sums,
both on (rows, k) blocks whose rows are split over the ranks by ``counts``.
"""
from __future__ import annotations

from typing import Any, Callable

import numpy as np
from numpy.typing import NDArray

Collective = Callable[[NDArray[np.float64], list[int]], NDArray[np.float64]]


def mpi_collectives(comm: Any) -> tuple[Collective, Collective]:
    """``(allgather, allreduce)`` on the mpi4py communicator ``comm``.

    ``allgather(local, counts)``: the (counts[rank], k) blocks of all ranks stacked in rank
    order, (sum(counts), k), the same on every rank (MPI_Allgatherv). ``allreduce(partial,
    counts)``: the sum over the ranks of the (sum(counts), k) blocks with the same bits on
    every rank. On 2 ranks an MPI_Allreduce: each entry is one addition, and IEEE
    addition is commutative. On more, MPI does not promise equal results on all ranks
    (the order of the additions may differ), so MPI_Reduce_scatter forms each entry on one
    rank (of the rows ``counts``) and MPI_Allgatherv copies it.
    """
    from mpi4py import MPI

    def layout(counts: list[int], k: int) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        c = np.asarray(counts, dtype=np.int64) * k
        return c, np.concatenate(([0], np.cumsum(c)[:-1]))

    def allgather(local: NDArray[np.float64], counts: list[int]) -> NDArray[np.float64]:
        k = local.shape[1]
        c, offsets = layout(counts, k)
        out = np.empty((int(sum(counts)), k))
        comm.Allgatherv(np.ascontiguousarray(local), [out, c, offsets, MPI.DOUBLE])
        return out

    def allreduce(partial: NDArray[np.float64], counts: list[int]) -> NDArray[np.float64]:
        partial = np.ascontiguousarray(partial)
        if comm.size <= 2:
            out = np.empty_like(partial)
            comm.Allreduce(partial, out, op=MPI.SUM)
            return out
        k = partial.shape[1]
        c, _ = layout(counts, k)
        own = np.empty((counts[comm.rank], k))
        comm.Reduce_scatter(partial, own, recvcounts=c, op=MPI.SUM)
        return allgather(own, counts)

    return allgather, allreduce
