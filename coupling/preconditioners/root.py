"""A preconditioner set up on rank 0 from gathered matrices, applied to distributed arrays.

The u block of the iterations lives in a distributed PETSc vector whose owned entries
are the contiguous global range [r0, r1) of each rank, in rank order. A preconditioner
built from global (gathered) matrices is set up on rank 0 only; each application
gathers the owned entries of the residual there (one Gatherv), applies B^{-1} and
returns each rank its slice (one Scatterv). The small Signorini block is replicated:
rank 0 applies it and broadcasts. With one rank the wrapper is not used.

This keeps every iterate independent of the number of ranks. It is not the
distributed substructuring preconditioner (whole subdomains per rank,
:mod:`coupling.preconditioners.distributed`): the work of B stays on rank 0.
"""
from __future__ import annotations

from typing import Callable

import numpy as np
from mpi4py import MPI

from fem_py.parallel import run_on_root

__all__ = ["RootPreconditioner"]


class RootPreconditioner:
    """A preconditioner set up on rank 0 and applied to distributed owned arrays.

    Parameters
    ----------
    comm
        Communicator of the mesh.
    n_owned
        Number of u entries owned by this rank.
    build
        Called on rank 0 only; returns the serial preconditioner (the interface of
        :class:`coupling.preconditioners.base.Preconditioner`) for the gathered problem.
    """

    def __init__(self, comm: MPI.Comm, n_owned: int, build: Callable[[], object]):
        self.comm = comm
        self._counts = np.array(comm.allgather(n_owned))
        self._offsets = np.concatenate([[0], np.cumsum(self._counts)[:-1]])
        self._inner = run_on_root(comm, build)  # an error is raised on every rank
        metric, lam = (
            (self._inner.signorini_metric, self._inner.lambda_max_signorini)
            if comm.rank == 0
            else (None, None)
        )
        self.signorini_metric = comm.bcast(metric, root=0)
        self.lambda_max_signorini = comm.bcast(lam, root=0)
        self.n_signorini = self.signorini_metric.shape[0]

    def _root_apply(self, method: str, owned: np.ndarray) -> np.ndarray:
        full = np.empty(int(self._counts.sum())) if self.comm.rank == 0 else None
        self.comm.Gatherv(
            np.ascontiguousarray(owned, dtype=float),
            [full, self._counts, self._offsets, MPI.DOUBLE],
            root=0,
        )
        result = getattr(self._inner, method)(full) if self.comm.rank == 0 else None
        out = np.empty(self._counts[self.comm.rank])
        self.comm.Scatterv([result, self._counts, self._offsets, MPI.DOUBLE], out, root=0)
        return out

    def _root_signorini(self, method: str, phi: np.ndarray) -> np.ndarray:
        result = getattr(self._inner, method)(phi) if self.comm.rank == 0 else None
        return self.comm.bcast(result, root=0)

    def apply_omega(self, g: np.ndarray) -> np.ndarray:
        return self._root_apply("apply_omega", g)

    def matvec_omega(self, u: np.ndarray) -> np.ndarray:
        return self._root_apply("matvec_omega", u)

    def apply_signorini(self, g: np.ndarray) -> np.ndarray:
        return self._root_signorini("apply_signorini", g)

    def matvec_signorini(self, phi: np.ndarray) -> np.ndarray:
        return self.signorini_metric @ phi

    def destroy(self) -> None:
        if self._inner is not None:
            self._inner.destroy()
