"""Solvers of the discrete problem (2.3), each its own loop, and the :func:`solve` that
chooses one.

- :mod:`~coupling.solvers.records`: the record of a step, the outcome of a run, B norms;
- :mod:`~coupling.solvers.loop`: the context every iteration reads and the ending of its
  steps and of the run, written once;
- :mod:`~coupling.solvers.projection`: P_s, the M_s projection onto {phi >= 0} (3.19)-(3.20);
- :mod:`~coupling.solvers.lanczos`: C0 and lambda_min in the B inner product (3.5);
- :mod:`~coupling.solvers.pgpm`: Algorithm 3.1, the paper's method;
- :mod:`~coupling.solvers.apgpm`: its accelerated variant (our extension);
- :mod:`~coupling.solvers.ssn`: semismooth Newton (our extension, the default);
- :mod:`~coupling.solvers.solution`: :func:`solve` and :class:`Solution`.
"""
from coupling.solvers.records import IterationRecord, RunResult
from coupling.solvers.solution import Solution, solve

__all__ = ["solve", "Solution", "IterationRecord", "RunResult"]
