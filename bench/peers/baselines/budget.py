"""What every baseline shares: the wall-time budget, the result of a solve, and the
check that the problem is serial."""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
from petsc4py import PETSc

__all__ = ["BudgetExceeded", "Budget", "PeerResult", "BudgetedFunctional", "require_serial"]


class BudgetExceeded(RuntimeError):
    """A solver used up its wall-time budget (raised from inside a callback)."""


class Budget:
    """A wall-time budget of ``seconds`` from construction; :meth:`check` raises
    :class:`BudgetExceeded` once it is spent. ``None`` means no limit."""

    def __init__(self, seconds: float | None):
        self.seconds = seconds
        self.start = time.perf_counter()

    @property
    def spent(self) -> bool:
        return self.seconds is not None and time.perf_counter() - self.start > self.seconds

    def check(self) -> None:
        if self.spent:
            raise BudgetExceeded(f"not converged within the budget of {self.seconds:g} s")

    def run(
        self,
        solve: Callable[[], Any],
        reason_code: Callable[[], int],
        describe: Callable[[int], str],
    ) -> tuple[bool, str, float]:
        """Call ``solve()``; return (converged, reason, wall time). A PETSc error raised
        after the budget is spent (a callback's BudgetExceeded surfacing through PETSc)
        counts as running out of budget."""
        tic = time.perf_counter()
        try:
            solve()
            code = reason_code()
            converged, reason = code > 0, describe(code)
        except BudgetExceeded as err:
            converged, reason = False, str(err)
        except PETSc.Error as err:
            converged = False
            reason = (
                f"not converged within the budget of {self.seconds:g} s"
                if self.spent
                else f"PETSc error {err.ierr}"
            )
        return converged, reason, time.perf_counter() - tic


@dataclass
class PeerResult:
    """Outcome of one peer solve.

    ``u`` (N,) and ``phi`` (n_s,) are the final iterate (also when not converged);
    ``iterations`` the outer (Newton, quasi-Newton) steps; ``linear_iterations`` the
    Krylov iterations summed over all steps (0 for direct solves); ``setup`` and
    ``solve`` wall times in seconds; ``evaluations`` the objective/gradient calls.
    """

    u: np.ndarray
    phi: np.ndarray
    converged: bool
    reason: str
    iterations: int
    linear_iterations: int
    setup: float
    solve: float
    evaluations: int = 0
    details: dict[str, Any] = field(default_factory=dict)


class BudgetedFunctional:
    """J_h with a wall-time budget: every evaluation checks it and remembers the
    state it was called at (so that the last iterate survives a budget stop). It wraps
    the problem's functional for the methods that take it as an argument; the problem
    itself is not changed."""

    def __init__(self, inner: Any, budget: Budget):
        self._inner = inner
        self._budget = budget
        self.last: tuple[np.ndarray, np.ndarray] | None = None

    def __getattr__(self, name: str) -> Any:
        return getattr(self._inner, name)

    def _check(self, u_function: Any, phi: np.ndarray) -> None:
        self.last = (u_function.x.array.copy(), np.array(phi, dtype=float))
        self._budget.check()

    def value(self, u_function: Any, phi: np.ndarray) -> float:
        self._check(u_function, phi)
        return self._inner.value(u_function, phi)

    def gradient(self, u_function: Any, phi: np.ndarray, grad_u: PETSc.Vec) -> np.ndarray:
        self._check(u_function, phi)
        return self._inner.gradient(u_function, phi, grad_u)

    def value_and_gradient(
        self, u_function: Any, phi: np.ndarray, grad_u: PETSc.Vec
    ) -> tuple[float, np.ndarray]:
        self._check(u_function, phi)
        return self._inner.value_and_gradient(u_function, phi, grad_u)


def require_serial(comm: Any) -> None:
    """ValueError unless ``comm`` has one rank."""
    if comm.size > 1:
        raise ValueError(
            f"the PETSc peers are serial, got a communicator of {comm.size} ranks; "
            "run without mpirun"
        )
