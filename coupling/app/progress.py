"""Progress lines of a solve: a monitor for :func:`coupling.solvers.solve`."""
from __future__ import annotations

import sys
from typing import TextIO

from mpi4py import MPI

from coupling.solvers.records import IterationRecord

__all__ = ["ProgressMonitor"]


class ProgressMonitor:
    """Print every ``every``-th iteration (and the first) on rank 0 of ``comm``."""

    def __init__(self, comm: MPI.Comm, *, every: int = 25, stream: TextIO = sys.stdout):
        self.comm, self.every, self.stream = comm, every, stream

    def __call__(self, record: IterationRecord) -> None:
        if self.comm.rank != 0 or not (record.iteration % self.every == 0 or record.iteration == 1):
            return
        inner = (
            f"cg = {record.cg_iterations}"
            if record.line_search is not None
            else f"projection = {record.projection_iterations}"
        )
        print(
            f"  it {record.iteration:5d}  J_h = {record.energy:.12e}  "
            f"step = {record.step_norm:.3e}  contact = {record.contact}  {inner}",
            file=self.stream,
            flush=True,
        )

    def stage(self, what: str) -> None:
        """One line naming the stage that starts."""
        if self.comm.rank == 0:
            print(f"fembem: {what}", file=self.stream, flush=True)

    def problem(self, problem, options, arc_lengths, facts: dict) -> None:
        """The size of the assembled problem and its mesh (``facts``:
        :func:`fem_py.mesh.facts.mesh_facts`), the material, the Signorini arcs and the
        method about to run."""
        m = problem.material
        partition = (
            f"{facts['subdomains']} subdomains of mean diameter "
            f"{facts['subdomain_diameter']:.4g}, "
            if "subdomains" in facts
            else ""
        )
        self.stage(
            f"{problem.n_dofs} dofs, {problem.boundary.n_gamma} on "
            f"Gamma, {problem.n_signorini} Signorini unknowns, {partition}h from "
            f"{facts['h_min']:.4g} to {facts['h_max']:.4g}"
        )
        if facts.get("signorini_areas"):
            areas = ", ".join(f"{s:.4g}" for s in facts["signorini_areas"])
            self.stage(f"Signorini faces of area {areas}")
        self.stage(f"material {m.name}: alpha = {m.alpha:.4g}, beta = {m.beta:.4g}")
        if len(arc_lengths):
            lengths = ", ".join(f"{s:.4g}" for s in arc_lengths)
            self.stage(f"Signorini arcs of length {lengths}")
        self.stage(f"solving with {options.method}")

    def level(self, record) -> None:
        """One line per level of a nested solve."""
        self.stage(
            f"level of {record.dofs} dofs: {record.iterations} iterations, "
            f"{record.cg_iterations} CG, {record.time:.2f} s"
        )

    def adapt_level(self, level) -> None:
        """One line per level of the adaptive loop."""
        r = level.record()
        self.stage(
            f"adaptive level {r['level']}: {r['dofs']} dofs, estimator {r['estimator']:.4g}, "
            f"{r['iterations']} iterations, {r['marked']} cells marked, {r['time']:.2f} s"
            + (f", error {r['error']:.4g}" if "error" in r else "")
        )

    def finished(self, solution) -> None:
        """A note when J_h increased during the solve (tau was halved)."""
        if solution.energy_increases and self.comm.rank == 0:
            print(
                f"  note: J_h increased {solution.energy_increases} times; tau was halved "
                f"to {solution.tau:.3e}",
                file=self.stream,
                flush=True,
            )
