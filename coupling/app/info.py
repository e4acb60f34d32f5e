"""``fembem info``: the size of a run and the choices it will make, without running it.

:func:`info_report` gathers every field (``--json`` prints them all): the sizes of the
domain (:class:`fem_py.mesh.DomainSize`, in closed form, estimated before meshing, or
counted on the mesh), the memory estimate and what is available, and what ``"auto"``
settles to for this size: the preconditioner, the boundary operator S_h (dense, or the
H-matrix and its tolerance) and the coarser levels of a nested solve.
:func:`info_lines` says the same for a reader, in units, with only the lines that apply.
"""
from __future__ import annotations

import dataclasses
from typing import Any

from coupling.options import RunConfig, hmatrix_tol_for

__all__ = ["info_report", "info_lines"]


def info_report(comm: Any, config: RunConfig, *, size: Any, how: str) -> dict[str, Any]:
    """Every field of ``fembem info`` for a validated ``config`` whose domain has the sizes
    ``size`` (``how``: how they were found), on ``comm.size`` ranks."""
    from coupling.app.from_config import coarser_configs, kernel_of
    from coupling.app.sizing import equation_size, memory_available, memory_estimate
    from coupling.distributed import boundary_operator_kind
    from coupling.preconditioners import preconditioner_kind

    solver, dim = config.solver, size.dim
    elastic = config.problem.equation == "elasticity"
    kernel = kernel_of(config)
    components = dim if elastic else 1
    operator = boundary_operator_kind(
        solver.boundary_operator, size.boundary_dofs, dim, kernel=kernel
    )
    adaptive = config.adapt.steps > 0
    size = equation_size(size, config)
    levels = coarser_configs(config, size.dofs) if solver.nested and not adaptive else []
    return {
        "equation": config.problem.equation,
        **dataclasses.asdict(size),
        "memory_estimate_bytes": memory_estimate(
            size, comm.size, plots=config.output.plots, boundary_operator=solver.boundary_operator
        ),
        "memory_available_bytes": memory_available(),
        "mpi_ranks": comm.size,
        "sizes": how,
        "domain": config.geometry.mesh or config.geometry.shape,
        "method": solver.method,
        "preconditioner": preconditioner_kind(solver.preconditioner, dim, components),
        "boundary_operator": operator,
        "hmatrix_tol": (
            hmatrix_tol_for(size.boundary_dofs // components, dim)
            if operator == "hmatrix"
            else None
        ),
        "nested_levels": [float(c.geometry.h) for c in levels],
        "adaptive_steps": config.adapt.steps,
    }


def _bytes(n: float) -> str:
    """``n`` bytes in MB or GB, three digits."""
    return f"{n / 1e9:.3g} GB" if n >= 1e9 else f"{n / 1e6:.3g} MB"


def info_lines(report: dict[str, Any], config: RunConfig) -> list[str]:
    """The report of :func:`info_report` as lines for a reader: counts with thousands
    separators, memory in MB or GB, the lines that apply to this domain and run."""
    from coupling.app.from_config import kernel_of
    from coupling.distributed import hmatrix_crossover

    dim = report["dim"]
    where = "a body in R^3" if dim == 3 else "a planar domain"
    how = report["sizes"]
    how = f"in {how}" if how == "closed form" else how
    lines = [f"domain          {report['domain']} ({where}); sizes {how}"]
    if report["equation"] == "elasticity":
        lines.append(f"equation        elasticity: {dim} displacement components per node")
    lines.append(
        f"unknowns        {report['dofs']:,} dofs, {report['boundary_dofs']:,} on Gamma, "
        f"{report['signorini_dofs']:,} "
        + ("gap unknowns" if report["equation"] == "elasticity" else "with a gap unknown")
        + " (Signorini)"
    )
    if dim == 2:
        lines.append(f"subdomains      {report['subdomains']:,}")
    h_min, h_max = report["h_min"], report["h_max"]
    edge = "edge" if dim == 3 else "facet"
    lines.append(f"mesh size       {edge}s from {h_min:.4g} to {h_max:.4g}")
    auto = " (auto)" if config.solver.preconditioner == "auto" else ""
    lines.append(
        f"solver          {report['method']}, preconditioner {report['preconditioner']}{auto}"
    )
    elastic = report["equation"] == "elasticity"
    crossover = hmatrix_crossover(dim, kernel_of(config))
    unit = "boundary nodes" if elastic else "boundary dofs"
    why = (
        f"auto: the H-matrix from {crossover:,} {unit} on"
        if config.solver.boundary_operator == "auto"
        else "as set"
    )
    if report["boundary_operator"] == "hmatrix":
        lines.append(
            f"S_h             hierarchical matrix, tolerance {report['hmatrix_tol']:.2g} ({why})"
        )
    else:
        lines.append(f"S_h             dense {report['boundary_dofs']:,}^2 matrix ({why})")
    if report["nested_levels"]:
        hs = ", ".join(f"{h:.4g}" for h in report["nested_levels"])
        count = len(report["nested_levels"])
        lines.append(
            f"nested          first on {count} coarser mesh{'es' if count > 1 else ''} (h = {hs})"
        )
    if report["adaptive_steps"]:
        a = config.adapt
        lines.append(
            f"adaptive        up to {a.steps} refinements (theta {a.theta:g}, at most "
            f"{a.max_dofs:,} dofs)"
        )
    ranks = report["mpi_ranks"]
    lines.append(
        f"memory          about {_bytes(report['memory_estimate_bytes'])} at its peak on "
        f"{ranks} rank{'s' if ranks > 1 else ''} ({_bytes(report['memory_available_bytes'])} "
        "available)"
    )
    return lines
