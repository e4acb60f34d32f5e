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
    Solver(
        "snes-substructuring",
        "SNES VI, CG + substructuring",
        "c",
        "snes",
        {"linear_solver": "substructuring"},
        selection=True,
        quick=True,
    ),
    Solver(
        "snes-mumps-cholesky",
        "SNES VI, MUMPS Cholesky (AMD)",
        "c",
        "snes",
        {"linear_solver": "mumps-cholesky"},
        selection=True,
        quick=True,
    ),
    Solver(
        "snes-mumps-cholesky-auto",
        "SNES VI, MUMPS Cholesky (default ordering)",
        "c",
        "snes",
        {"linear_solver": "mumps-cholesky-auto"},
        max_cells=250,
        selection=True,
        problems=_SELECTION,
    ),
    Solver(
        "snes-mumps",
        "SNES VI, MUMPS LU (AMD)",
        "c",
        "snes",
        {"linear_solver": "mumps"},
        max_cells=250,
        selection=True,
        problems=_SELECTION,
    ),
    Solver(
        "snes-hypre",
        "SNES VI, CG + BoomerAMG",
        "c",
        "snes",
        {"linear_solver": "hypre"},
        max_cells=250,
        selection=True,
        problems=_SELECTION,
    ),
    Solver(
        "snes-gamg",
        "SNES VI, CG + GAMG",
        "c",
        "snes",
        {"linear_solver": "gamg"},
        max_cells=250,
        selection=True,
        problems=_SELECTION,
    ),
    Solver(
        "snes-petsc-lu",
        "SNES VI, PETSc LU (nd)",
        "c",
        "snes",
        {"linear_solver": "petsc-lu"},
        max_cells=100,
        selection=True,
        problems=_SELECTION,
    ),
    # grid-sequenced SNES VI: "nested" doubles h with the subdomains kept
    # (coupling.app.from_config.coarser_configs, keep_subdomains: one coarser level at
    # d = 4h; the peer's fastest, faster than the project's own 4h levels); "deep" doubles
    # h down to about 1e3 dofs, on coarse partitions of 2 x 2 subdomains (which only B
    # would need)
    Solver(
        "snes-seq-substructuring",
        "SNES VI grid-sequenced, CG + substructuring",
        "c",
        "snes-sequenced",
        {"linear_solver": "substructuring", "hierarchy": "nested"},
        sequenced_selection=True,
        quick=True,
    ),
    Solver(
        "snes-seq-mumps-cholesky",
        "SNES VI grid-sequenced, MUMPS Cholesky (AMD)",
        "c",
        "snes-sequenced",
        {"linear_solver": "mumps-cholesky", "hierarchy": "nested"},
        max_cells=250,
        sequenced_selection=True,
        problems=_SELECTION,
    ),
    Solver(
        "snes-seq-mumps-cholesky-deep",
        "SNES VI grid-sequenced to 1e3 dofs, MUMPS Cholesky (AMD)",
        "c",
        "snes-sequenced",
        {"linear_solver": "mumps-cholesky", "hierarchy": "deep"},
        sequenced_selection=True,
        quick=True,
    ),
    Solver(
        "snes-seq-hypre-deep",
        "SNES VI grid-sequenced to 1e3 dofs, CG + BoomerAMG",
        "c",
        "snes-sequenced",
        {"linear_solver": "hypre", "hierarchy": "deep"},
        max_cells=250,
        sequenced_selection=True,
        problems=_SELECTION,
    ),
    Solver(
        "snes-seq-gamg-deep",
        "SNES VI grid-sequenced to 1e3 dofs, CG + GAMG",
        "c",
        "snes-sequenced",
        {"linear_solver": "gamg", "hierarchy": "deep"},
        max_cells=250,
        sequenced_selection=True,
        problems=_SELECTION,
    ),
    Solver("tao-blmvm", "TAO BLMVM", "d", "tao", {"kind": "blmvm", "oracle": True}, budget=120.0),
    Solver("tao-bqnls", "TAO BQNLS", "d", "tao", {"kind": "bqnls", "oracle": True}, budget=120.0),
    Solver(
        "tao-bnls",
        "TAO BNLS, MUMPS Cholesky",
        "d",
        "tao",
        {"kind": "bnls", "linear_solver": "mumps-cholesky"},
        quick=True,
    ),
    Solver(
        "tao-bntr",
        "TAO BNTR, MUMPS Cholesky",
        "d",
        "tao",
        {"kind": "bntr", "linear_solver": "mumps-cholesky"},
    ),
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
