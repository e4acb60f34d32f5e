"""What every iteration shares: the record of one step, the outcome of a run, and the
B inner product of the stopping rule (docs/method.md (3.18): B = B_Omega + B_s).

    ||xi||_B^2 = u^T B_Omega u + phi^T M_s phi,

u distributed (owned entries, one Allreduce), phi replicated.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

__all__ = [
    "IterationRecord",
    "RunResult",
    "Monitor",
    "global_dot",
    "b_norm2",
    "relative_step",
    "set_owned",
    "History",
]


@dataclass(frozen=True)
class IterationRecord:
    """One outer step of any method; every field means one thing for every method.

    Attributes
    ----------
    iteration
        The outer step k (1, 2, ...; the PGPM warm steps of ssn included).
    energy
        J_h(xi_k) after the step.
    step_norm
        The relative B-norm step of the stopping rule: ||xi_k - y_{k-1}||_B / ||xi_k||_B
        (y = the point the step was taken from: xi_{k-1} for PGPM and ssn, the
        extrapolated point for APGPM).
    contact
        Number of Signorini nodes with phi = 0.
    tau
        The gradient step length tau (1/C0, halved by backtracking) of the method.
    projection_iterations
        Inner iterations of the projection P_s in this step (0 in a Newton step).
    cg_iterations
        CG iterations of the Newton step (0 in a gradient step).
    line_search
        The length taken along the Newton direction (1 = full step, 0 = replaced by a
        PGPM step); None in a gradient step.
    """

    iteration: int
    energy: float
    step_norm: float
    contact: int
    tau: float
    projection_iterations: int = 0
    cg_iterations: int = 0
    line_search: float | None = None


Monitor = Callable[[IterationRecord], None]


@dataclass
class RunResult:
    """Outcome of an iterative solve (u is left in the Function passed in)."""

    phi: np.ndarray
    converged: bool
    reason: str
    iterations: int
    energy: float
    tau: float
    history: list[IterationRecord] = field(default_factory=list)
    energy_increases: int = 0
    #: the relative B-norm the stopping rule tested when it stopped the run, when that is
    #: not the last record's ``step_norm`` (ssn stopping at the PGPM step from xi_k)
    stop_measure: float | None = None


class History(list):
    """The records of a run; :meth:`add` also passes each one to the monitor."""

    def __init__(self, monitor: Monitor | None = None):
        super().__init__()
        self.monitor = monitor

    def add(self, record: IterationRecord) -> None:
        self.append(record)
        if self.monitor is not None:
            self.monitor(record)

    def step(
        self, iteration: int, energy: float, step_norm: float, phi: np.ndarray, tau: float, **counts
    ) -> None:
        """Record one outer step (the contact count read off phi) and pass it to the
        monitor; ``counts``: the inner iteration fields of :class:`IterationRecord`."""
        contact = int(np.count_nonzero(phi <= 0.0))
        self.add(IterationRecord(iteration, energy, step_norm, contact, tau, **counts))


def global_dot(comm: MPI.Comm, a: np.ndarray, b: np.ndarray) -> float:
    """a^T b over the owned entries of every rank (one Allreduce)."""
    return comm.allreduce(float(a @ b), op=MPI.SUM)


def b_norm2(
    comm: MPI.Comm, u: np.ndarray, b_u: np.ndarray, phi: np.ndarray, m_phi: np.ndarray
) -> float:
    """u^T (B_Omega u) + phi^T (M_s phi), given the products B_Omega u and M_s phi."""
    return global_dot(comm, u, b_u) + phi @ m_phi


def relative_step(step2: float, norm2: float) -> float:
    """sqrt(step2 / norm2), the relative step of the stopping rule (0 when norm2 = 0)."""
    return float(np.sqrt(max(step2, 0.0) / norm2)) if norm2 > 0 else 0.0


def set_owned(u_function, owned: np.ndarray) -> None:
    """Copy owned values into the dolfinx Function and refresh its ghosts."""
    u = u_function.vector
    u.array[:] = owned
    u.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
