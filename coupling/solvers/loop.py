"""What the loops of every method share: the context an iteration reads, and the ending
of an outer step (record it, test the stopping rule, stop) and of the run (release the
work objects, build the result), written once.

The stopping rules all compare a relative B-norm step with ``tol`` (docs/method.md (3.18):
||xi||_B^2 = u^T B_Omega u + phi^T M_s phi); what the step is differs by method.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterator

import numpy as np

from coupling.solvers.projection import SignoriniProjection
from coupling.solvers.records import History, IterationRecord, Monitor, RunResult, relative_step

__all__ = ["IterationContext", "Loop"]


@dataclass(frozen=True)
class IterationContext:
    """What an iteration reads and never changes, except the iterate u it is started
    from and leaves its answer in.

    Attributes
    ----------
    functional
        J_h (:class:`coupling.functional.CoupledFunctional`, or one that wraps it).
    preconditioner
        B: ``apply_omega`` (B_Omega^{-1}), ``matvec_omega`` (B_Omega), ``apply_signorini``
        (M_s^{-1}), ``matvec_signorini`` (M_s) on owned entries, and ``signorini_metric``.
    projection
        P_s in the M_s metric (3.19)-(3.20).
    u
        dolfinx Function holding u_0 on entry and u_h on exit.
    tol
        The relative tolerance of the stopping rule.
    max_iterations
        Outer steps at most.
    monitor
        Called with each :class:`~coupling.solvers.records.IterationRecord`.
    backtrack
        When a gradient step would increase J_h, halve tau and redo it.
    forms
        The interior forms (``create_matrix``, ``assemble_jacobian``): the Jacobians of
        the Newton steps (ssn only).
    matrix
        The caller's P1 matrix for those Jacobians (``coupling.preconditioners.create_matrix``:
        a ``fem_py.forms.P1Matrix`` or a PETSc Mat; default: a new P1Matrix).
    """

    functional: Any
    preconditioner: Any
    projection: SignoriniProjection
    u: Any
    tol: float
    max_iterations: int
    monitor: Monitor | None = None
    backtrack: bool = True
    forms: Any = None
    matrix: Any = None

    @property
    def comm(self):
        """The communicator of the problem (that of ``functional``)."""
        return self.functional.comm


class Loop:
    """The bookkeeping of an outer iteration: the steps k = ``first``, ...,
    ``max_iterations`` (ending after the first one that meets the stopping rule), the
    records, the count of energy increases and the result.

    Parameters
    ----------
    context
        The iteration's context (``tol``, ``max_iterations``, ``monitor``).
    rule
        The stopping rule, as the reason of a converged run (``{tol:g}`` is filled in).
    first
        The first step's number (after the PGPM steps that started an ssn run).
    history
        Records of earlier steps of the same run (already passed to the monitor).
    increases
        Energy increases of those earlier steps.
    """

    def __init__(
        self,
        context: IterationContext,
        rule: str,
        *,
        first: int = 1,
        history: list[IterationRecord] | None = None,
        increases: int = 0,
    ):
        self.tol, self.max_iterations, self.rule = context.tol, context.max_iterations, rule
        self.history = History(context.monitor)
        self.bounded = context.projection.bounded  # the entries whose 0 is contact
        self.history.extend(history or [])
        self.first = first
        self.iterations = first - 1
        self.increases = increases
        self.converged = False
        self.reason = f"reached max_iterations = {context.max_iterations}"
        #: the relative B-norm the stopping rule tested when :meth:`stop` ended the run
        #: by a rule other than the last record's ``step_norm``
        self.stop_measure: float | None = None

    def steps(self) -> Iterator[int]:
        """The step numbers k, until the stopping rule holds or the cap is reached."""
        for k in range(self.first, self.max_iterations + 1):
            self.iterations = k
            yield k
            if self.converged:
                return

    def end_step(
        self,
        k: int,
        energy: float,
        step2: float,
        norm2: float,
        phi: np.ndarray,
        tau: float,
        *,
        settled: bool = True,
        **counts,
    ) -> float:
        """Record step k (relative step sqrt(step2 / norm2)) and stop by the loop's rule
        when it is at most ``tol`` and ``settled``; ``counts`` are the inner iteration
        fields of the record. Returns the relative step."""
        relative = relative_step(step2, norm2)
        self.history.step(k, energy, relative, phi[self.bounded], tau, **counts)
        if relative <= self.tol and settled:
            self.stop(self.rule, k)
        return relative

    def stop(self, rule: str, iterations: int, measure: float | None = None) -> None:
        """End the run as converged after ``iterations`` steps by ``rule``, which tested
        ``measure`` (None: the last record's ``step_norm``)."""
        self.converged, self.iterations, self.stop_measure = True, iterations, measure
        self.reason = rule.format(tol=self.tol)

    def result(self, phi: np.ndarray, energy: float, tau: float, release=()) -> RunResult:
        """Destroy the PETSc objects of ``release``; the :class:`RunResult` of the run."""
        for obj in release:
            obj.destroy()
        outcome = (self.converged, self.reason, self.iterations, energy, tau)
        return RunResult(
            phi, *outcome, list(self.history), self.increases, stop_measure=self.stop_measure
        )
