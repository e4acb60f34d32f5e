"""The peer benchmark's definition: the data sets, the solver table, the sizes and the
agreement tolerances (shared by the runner, the worker and the report modules).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

#: Agreement with the PGPM solution (relative Euclidean norms of the nodal vectors).
#: PGPM stops at its default tol = 1e-8 (B-norm step); the margin over its own error
#: is in docs/design/baselines.md.
TOL_U, TOL_PHI = 1e-6, 1e-5

PROBLEMS: dict[str, dict[str, Any]] = {
    "manufactured": {"label": "manufactured (square_contact, carstensen)"},
    "load": {
        "label": "f = 2, t0 = -1, u0 = 0.1 x (carstensen)",
        "f": "2",
        "t0": "-1",
        "u0": "0.1*x",
        "a": 0.0,
    },
}


@dataclass(frozen=True)
class Solver:
    """One benchmarked solver: ``kind`` selects the ``bench.peers.baselines`` entry point."""

    name: str
    label: str
    group: str
    kind: str  # "project", "snes", "snes-sequenced", "tao", "poisson"
    options: dict = field(default_factory=dict)
    max_cells: int | None = None  # not run on finer meshes
    budget: float | None = None  # cap on the per-solve budget
    selection: bool = False  # part of the SNES VI linear-solver selection
    sequenced_selection: bool = False  # part of the grid-sequenced SNES VI selection
    quick: bool = False  # part of --quick
    problems: tuple[str, ...] = ("manufactured", "load")


_SELECTION = ("manufactured",)
#: The peers run on the coarser meshes and the manufactured data only.
_CANDIDATE = dict(max_cells=250, problems=_SELECTION)
#: The linear solvers of the SNES VI peers and their labels.
LINEAR_LABELS = {
    "substructuring": "CG + substructuring",
    "mumps-cholesky": "MUMPS Cholesky (AMD)",
    "mumps-cholesky-auto": "MUMPS Cholesky (default ordering)",
    "mumps": "MUMPS LU (AMD)",
    "hypre": "CG + BoomerAMG",
    "gamg": "CG + GAMG",
    "petsc-lu": "PETSc LU (nd)",
}


def _snes(linear_solver: str, **extra: Any) -> Solver:
    """SNES VI from x = 0 with ``linear_solver`` (the linear-solver selection)."""
    label = f"SNES VI, {LINEAR_LABELS[linear_solver]}"
    options = {"linear_solver": linear_solver}
    return Solver(f"snes-{linear_solver}", label, "c", "snes", options, selection=True, **extra)


def _sequenced(linear_solver: str, hierarchy: str, **extra: Any) -> Solver:
    """SNES VI grid-sequenced over the ``hierarchy`` ("nested" or "deep") of levels."""
    deep = hierarchy == "deep"
    name = f"snes-seq-{linear_solver}" + ("-deep" if deep else "")
    label = "SNES VI grid-sequenced" + (" to 1e3 dofs" if deep else "")
    label += f", {LINEAR_LABELS[linear_solver]}"
    options = {"linear_solver": linear_solver, "hierarchy": hierarchy}
    return Solver(name, label, "c", "snes-sequenced", options, sequenced_selection=True, **extra)


def _tao(kind: str, label: str, options: dict, **extra: Any) -> Solver:
    """TAO bound-constrained minimisation of J_h with the method ``kind``."""
    return Solver(f"tao-{kind}", f"TAO {label}", "d", "tao", {"kind": kind, **options}, **extra)


SOLVERS: tuple[Solver, ...] = (
    Solver("pgpm", "PGPM + substructuring", "a", "project", {"method": "pgpm"}, quick=True),
    Solver(
        "pgpm-identity",
        "PGPM + identity",
        "b",
        "project",
        {"method": "pgpm", "preconditioner": "identity", "max_iterations": 10**7},
        max_cells=100,
        budget=60.0,
        problems=_SELECTION,
    ),
    Solver("apgpm", "APGPM + substructuring", "b", "project", {"method": "apgpm"}, quick=True),
    Solver("ssn", "SSN + substructuring", "b", "project", {"method": "ssn"}, quick=True),
    _snes("substructuring", quick=True),
    _snes("mumps-cholesky", quick=True),
    _snes("mumps-cholesky-auto", **_CANDIDATE),
    _snes("mumps", **_CANDIDATE),
    _snes("hypre", **_CANDIDATE),
    _snes("gamg", **_CANDIDATE),
    _snes("petsc-lu", max_cells=100, problems=_SELECTION),
    # grid-sequenced SNES VI: "nested" doubles h with the subdomains kept
    # (coupling.app.from_config.coarser_configs, keep_subdomains: one coarser level at
    # d = 4h; the peer's fastest, faster than the project's own 4h levels); "deep" doubles
    # h down to about 1e3 dofs, on coarse partitions of 2 x 2 subdomains (which only B
    # would need)
    _sequenced("substructuring", "nested", quick=True),
    _sequenced("mumps-cholesky", "nested", **_CANDIDATE),
    _sequenced("mumps-cholesky", "deep", quick=True),
    _sequenced("hypre", "deep", **_CANDIDATE),
    _sequenced("gamg", "deep", **_CANDIDATE),
    _tao("blmvm", "BLMVM", {"oracle": True}, budget=120.0),
    _tao("bqnls", "BQNLS", {"oracle": True}, budget=120.0),
    _tao("bnls", "BNLS, MUMPS Cholesky", {"linear_solver": "mumps-cholesky"}, quick=True),
    _tao("bntr", "BNTR, MUMPS Cholesky", {"linear_solver": "mumps-cholesky"}),
    Solver("poisson", "Poisson, CG + GAMG (yardstick)", "e", "poisson", quick=True),
)
BY_NAME = {s.name: s for s in SOLVERS}
#: The grid-sequenced SNES VI peers run on every mesh (the candidates' fastest,
#: docs/design/baselines.md), against which target 3 is measured.
SEQUENCED_KEPT = ("snes-seq-substructuring", "snes-seq-mumps-cholesky-deep")
#: Coarsest level of the "deep" hierarchy [dofs] (coarser_configs' min_dofs).
DEEP_MIN_DOFS = 1000
FULL_SIZES = (100, 250, 500, 1000)
QUICK_SIZES = (100, 200)
#: SNES rtol and TAO gttol of the Newton-type peers: Newton converges quadratically,
#: so the last step lands far below them (docs/design/baselines.md).
NEWTON_TOL = 1e-10
