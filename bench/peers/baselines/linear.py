"""The linear solvers of the Newton systems of the baselines (SNES VI, TAO BNLS/BNTR):
their PETSc options, the project's B restricted to the inactive set as a PCSHELL, and
the PETSc options database handled under a unique prefix per solve."""
from __future__ import annotations

import itertools
import time
from typing import Any, Callable

import numpy as np
import scipy.linalg
from petsc4py import PETSc

from coupling.preconditioners import Preconditioner

__all__ = [
    "LINEAR_SOLVERS",
    "KRYLOV_RTOL",
    "new_prefix",
    "set_options",
    "clear_options",
    "InactiveSetShell",
    "RebuiltPC",
    "linear_options",
    "python_pc",
    "count_krylov",
]

#: Linear solvers of the Newton systems (SNES VI, TAO BNLS/BNTR): the KSP type and the
#: PETSc options of its PC. The AMG preconditioners are rebuilt from scratch for every
#: reduced system (a PCPYTHON wrapper, :class:`RebuiltPC`): SNES VI changes the size of
#: the system with the active set, and PETSc 3.18's GAMG then fails in PCSetUp
#: ("Cannot change local size of Amat after use"). ``substructuring`` is the project's
#: B restricted to the inactive set (:class:`InactiveSetShell`). MUMPS uses the AMD
#: ordering (ICNTL(7) = 0) rather than its automatic choice in this build (PORD; METIS
#: and SCOTCH are absent; docs/design/baselines.md); ``mumps-cholesky-auto`` keeps it.
LINEAR_SOLVERS: dict[str, dict[str, Any]] = {
    "mumps": {
        "ksp_type": "preonly",
        "pc": {"pc_type": "lu", "pc_factor_mat_solver_type": "mumps", "mat_mumps_icntl_7": 0},
    },
    "mumps-cholesky": {
        "ksp_type": "preonly",
        "pc": {"pc_type": "cholesky", "pc_factor_mat_solver_type": "mumps", "mat_mumps_icntl_7": 0},
    },
    "mumps-cholesky-auto": {
        "ksp_type": "preonly",
        "pc": {"pc_type": "cholesky", "pc_factor_mat_solver_type": "mumps"},
    },
    "petsc-lu": {
        "ksp_type": "preonly",
        "pc": {
            "pc_type": "lu",
            "pc_factor_mat_solver_type": "petsc",
            "pc_factor_mat_ordering_type": "nd",
        },
    },
    "gamg": {"ksp_type": "cg", "rebuild": True, "pc": {"pc_type": "gamg"}},
    "hypre": {
        "ksp_type": "cg",
        "rebuild": True,
        "pc": {"pc_type": "hypre", "pc_hypre_type": "boomeramg"},
    },
    "substructuring": {"ksp_type": "cg", "pc": {}},
}
#: Relative tolerance of the iterative (CG) Newton solves (chosen by measurement:
#: docs/design/baselines.md).
KRYLOV_RTOL = 1e-6

_prefixes = itertools.count()


def new_prefix(kind: str) -> str:
    """A PETSc options prefix no other solve uses: ``peers_<kind>_<n>_``."""
    return f"peers_{kind}_{next(_prefixes)}_"


def set_options(prefix: str, options: dict[str, Any]) -> None:
    """Put ``options`` into the PETSc options database under ``prefix``."""
    db = PETSc.Options()
    for key, value in options.items():
        db[f"{prefix}{key}"] = value


def clear_options(prefix: str, options: dict[str, Any]) -> None:
    """Remove ``options`` (set by :func:`set_options`) from the database."""
    db = PETSc.Options()
    for key in options:
        db.delValue(f"{prefix}{key}")


class InactiveSetShell:
    """PCSHELL context: the substructuring B restricted to the inactive set,
    diag(B_Omega^{-1}, (omega M_s)[I, I]^{-1}) (as in :mod:`coupling.solvers.ssn`).

    ``inactive()`` returns the indices (into x) of the reduced system, which must be
    all of u followed by the free phi; the M_s block is refactored whenever it changes.
    """

    def __init__(
        self, preconditioner: Preconditioner, n_u: int, inactive: Callable[[], np.ndarray]
    ):
        self.preconditioner = preconditioner
        self.n_u = n_u
        self.inactive = inactive
        self.metric = np.asarray(preconditioner.signorini_metric)
        self._free = None
        self._factor = None
        self.applications = 0
        self.time_setup = 0.0
        self.time_apply = 0.0

    def setUp(self, pc: PETSc.PC) -> None:
        start = time.perf_counter()
        idx = np.asarray(self.inactive(), dtype=np.int64)
        size = pc.getOperators()[0].getSize()[0]
        if idx.size != size or not np.array_equal(idx[: self.n_u], np.arange(self.n_u)):
            raise RuntimeError(
                f"inactive set of size {idx.size} does not match the reduced "
                f"system of size {size} with all u unknowns first"
            )
        free = idx[self.n_u :] - self.n_u
        if self._free is None or not np.array_equal(free, self._free):
            self._free = free
            block = self.metric[np.ix_(free, free)]
            self._factor = scipy.linalg.cho_factor(block) if free.size else None
        self.time_setup += time.perf_counter() - start

    def apply(self, pc: PETSc.PC, x: PETSc.Vec, y: PETSc.Vec) -> None:
        start = time.perf_counter()
        self.applications += 1
        values = x.array_r
        out = y.array
        out[: self.n_u] = self.preconditioner.apply_omega(values[: self.n_u])
        if self._factor is not None:
            out[self.n_u :] = scipy.linalg.cho_solve(self._factor, values[self.n_u :])
        self.time_apply += time.perf_counter() - start


class RebuiltPC:
    """PCPYTHON context: a PC of the given options, built from scratch at every set-up
    (every new reduced Newton system), applied as is."""

    def __init__(self, prefix: str):
        self.prefix = prefix
        self.inner: PETSc.PC | None = None

    def setUp(self, pc: PETSc.PC) -> None:
        if self.inner is not None:
            self.inner.destroy()
        self.inner = PETSc.PC().create(PETSc.COMM_SELF)
        self.inner.setOptionsPrefix(self.prefix)
        self.inner.setOperators(*pc.getOperators())
        self.inner.setFromOptions()
        self.inner.setUp()

    def apply(self, pc: PETSc.PC, x: PETSc.Vec, y: PETSc.Vec) -> None:
        self.inner.apply(x, y)

    def destroy(self, pc: PETSc.PC | None = None) -> None:
        if self.inner is not None:
            self.inner.destroy()
            self.inner = None


def linear_options(
    prefix: str, ksp_prefix: str, name: str, krylov_rtol: float, *, ksp_type: str | None = None
) -> dict[str, Any]:
    """Options (without ``prefix``) of the KSP with options prefix ``prefix + ksp_prefix``
    for the linear solver ``name``; a rebuilt PC reads its options under ``inner_``."""
    spec = LINEAR_SOLVERS[name]
    out: dict[str, Any] = {
        f"{ksp_prefix}ksp_type": ksp_type or spec["ksp_type"],
        f"{ksp_prefix}ksp_rtol": krylov_rtol,
        f"{ksp_prefix}ksp_max_it": 2000,
    }
    pc_prefix = f"{ksp_prefix}inner_" if spec.get("rebuild") else ksp_prefix
    out.update({f"{pc_prefix}{k}": v for k, v in spec["pc"].items()})
    return out


def python_pc(ksp: PETSc.KSP, prefix: str, name: str, shell: Any) -> None:
    """Install the PCPYTHON context of the linear solver ``name`` (if it has one) on
    ``ksp`` after its set-from-options (no pc_type option, so a KSP reset keeps it)."""
    context = (
        shell
        if name == "substructuring"
        else (RebuiltPC(prefix + "inner_") if LINEAR_SOLVERS[name].get("rebuild") else None)
    )
    if context is not None:
        ksp.getPC().setType("python")
        ksp.getPC().setPythonContext(context)


def count_krylov(ksp: PETSc.KSP) -> list[int]:
    """Attach a monitor to ``ksp`` that counts its Krylov iterations (returns the
    counter; a direct solve, KSP ``preonly``, counts none)."""
    counter = [0]

    def monitor(k: PETSc.KSP, its: int, _rnorm: float) -> None:
        if its > 0 and k.getType() != "preonly":
            counter[0] += 1

    ksp.setMonitor(monitor)
    return counter
