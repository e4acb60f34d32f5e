"""The preamble the demos share: their command line, printing on rank 0, results.json,
the gmsh files of the demos that build their own body, the sweep of manufactured solves
over meshes and the outputs of a solve.

Every demo takes ``--cells N`` (its mesh size) and ``--out DIR`` (default
``out/<demo name>``) and writes the numbers it prints to DIR/results.json, which the
tests read (tests/test_demos.py). The communicator is an argument, as in the library:
each demo takes MPI.COMM_WORLD at its top level and passes it here.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any, Callable, Sequence

from mpi4py import MPI

__all__ = [
    "CELLS_HELP",
    "OUTPUTS_HELP",
    "begin_demo",
    "demo_parser",
    "solve_manufactured",
    "start_demo",
    "outcome",
    "rank0_print",
    "refinement_summary",
    "solve_row",
    "write_gmsh_file",
    "write_results",
    "write_solve_outputs",
]

#: ``--out`` of the demos that write the outputs of a solve (:func:`write_solve_outputs`)
OUTPUTS_HELP = "folder for the plots, fields and results.json"


#: ``--cells`` of a demo on the square of width 0.5 (the default)
CELLS_HELP = "cells per side of the square (h = 0.5/cells)"


def demo_parser(
    name: str, description: str, *, cells: int, cells_help: str = CELLS_HELP, out_help: str = ""
) -> argparse.ArgumentParser:
    """The parser of ``--cells`` (default ``cells``) and ``--out`` (default out/``name``);
    a demo adds its own arguments, then calls :func:`start_demo`."""
    parser = argparse.ArgumentParser(description=description)
    help_cells = f"{cells_help}; default {cells}"
    parser.add_argument("--cells", type=int, default=cells, help=help_cells)
    out_help = out_help or "folder for results.json"
    parser.add_argument("--out", type=Path, default=Path("out") / name, help=out_help)
    return parser


def begin_demo(
    comm: MPI.Comm,
    name: str,
    description: str,
    *,
    cells: int,
    cells_help: str = CELLS_HELP,
    out_help: str = "",
    max_dofs: int | None = None,
) -> tuple[argparse.Namespace, Callable[..., None]]:
    """The command line of a demo with the common arguments alone, parsed, and the demo
    started: :func:`demo_parser` (``--cells``, ``--out``), with ``max_dofs`` (the adaptive
    demos) ``--steps`` (adaptive refinements, default 12) and ``--max-dofs`` (the largest
    level, default ``max_dofs``) too, then :func:`start_demo`. A demo with arguments of its
    own builds its parser with :func:`demo_parser` and calls :func:`start_demo`."""
    parser = demo_parser(name, description, cells=cells, cells_help=cells_help, out_help=out_help)
    if max_dofs is not None:
        steps_help = "adaptive refinements (default 12)"
        parser.add_argument("--steps", type=int, default=12, help=steps_help)
        max_help = f"largest level (default {max_dofs})"
        parser.add_argument("--max-dofs", type=int, default=max_dofs, help=max_help)
    return start_demo(parser, comm)


def start_demo(
    parser: argparse.ArgumentParser, comm: MPI.Comm
) -> tuple[argparse.Namespace, Callable[..., None]]:
    """Parse the command line: (the arguments, ``print`` on rank 0 of ``comm``).

    Under ``mpirun`` an exception that ends one rank then aborts every rank of ``comm``
    once its traceback is printed (``MPI_Abort``, as ``python -m mpi4py`` does): the
    other ranks never wait for it in a collective."""
    if comm.size > 1:
        sys.excepthook = _aborting(comm, sys.excepthook)
    return parser.parse_args(), rank0_print(comm)


def _aborting(comm: MPI.Comm, hook: Callable[..., None]) -> Callable[..., None]:
    """``hook``, then ``comm.Abort(1)``."""

    def excepthook(*exc_info: Any) -> None:
        hook(*exc_info)
        sys.stderr.flush()
        comm.Abort(1)

    return excepthook


def rank0_print(comm: MPI.Comm) -> Callable[..., None]:
    """``print`` (flushed) on rank 0 of ``comm``; nothing on the other ranks."""

    def say(*items: Any) -> None:
        if comm.rank == 0:
            print(*items, flush=True)

    return say


def outcome(result, method: str) -> str:
    """ "converged after N iterations of METHOD" (or "NOT converged ...") for ``result``."""
    state = "converged" if result.converged else "NOT converged"
    return f"{state} after {result.iterations} iterations of {method}"


def solve_row(cells: int, result, **columns: Any) -> dict[str, Any]:
    """One row of a demo's table of solves on the square of width 0.5: the mesh (cells
    per side, h), whether and in how many steps ``result`` converged, and ``columns``."""
    row = dict(cells=cells, h=0.5 / cells, converged=bool(result.converged))
    return dict(row, iterations=int(result.iterations), **columns)


def refinement_summary(rows: list[dict[str, Any]], min_dofs: int) -> dict[str, Any]:
    """The ``rows`` of a refinement (adaptive or uniform; per level its ``dofs`` N, energy
    ``error``, ``estimator`` eta and efficiency ``index``) with their slopes, least-squares
    fits of log(error) and log(eta) against log(N) over the levels with N >= ``min_dofs``
    (None with fewer than two), and the band max/min of the efficiency index."""
    import numpy as np

    fit = [r for r in rows if r["dofs"] >= min_dofs]

    def slope(key: str) -> float | None:
        if len(fit) < 2:
            return None
        n, values = np.log([r["dofs"] for r in fit]), np.log([r[key] for r in fit])
        return float(np.polyfit(n, values, 1)[0])

    index = [r["index"] for r in rows]
    return dict(
        rows=rows,
        error_slope=slope("error"),
        estimator_slope=slope("estimator"),
        index_band=max(index) / min(index),
    )


def solve_manufactured(
    comm: MPI.Comm, solution, material, cells: Sequence[int], options
) -> tuple[list[dict[str, Any]], Any, Any]:
    """Solve the manufactured problem of ``solution`` (``coupling.manufactured``) with
    ``material`` and ``options`` on the meshes of ``cells`` cells per side in turn: (a row
    per mesh, the problem and the result of the last). A row is the :func:`solve_row` of
    the solve with its dofs (on Gamma too), contact and Signorini nodes, seconds (assembly
    and solve) and the errors of ``coupling.manufactured.solution_errors``. Collective."""
    import time

    import numpy as np

    from coupling.manufactured import manufactured_problem, solution_errors
    from coupling.solvers import solve

    rows = []
    for n in cells:
        tic = time.perf_counter()
        problem = manufactured_problem(comm, solution, material, cells=n)
        result = solve(problem, options)
        row = solve_row(
            n,
            result,
            dofs=problem.V.dofmap.index_map.size_global,
            boundary_dofs=problem.boundary.n_gamma,
            contact_nodes=int(np.count_nonzero(result.contact)),
            signorini_nodes=problem.n_signorini,
            seconds=time.perf_counter() - tic,
            **solution_errors(problem, solution, result),
        )
        rows.append(row)
    return rows, problem, result


def write_solve_outputs(
    comm: MPI.Comm, out: Path, problem, result, options, results: dict[str, Any]
) -> list[str]:
    """Write what ``fembem solve`` writes for ``result`` (``coupling.io.outputs``:
    summary.json with the seconds of every stage, fields.npz, solution.xdmf and the PNG
    figures) into ``out``, emptied first, and the demo's ``results`` (:func:`write_results`);
    return the file names. Collective."""
    from coupling.io.atomic import prepare_output_dir
    from coupling.io.outputs import write_outputs

    prepare_output_dir(comm, out, force=True)
    timings = {**problem.timings, **result.timings}
    files = write_outputs(
        comm, out, problem, result, tol=options.tol, timings=timings, xdmf=True, plots=True
    )
    return [*files, write_results(comm, out, results).name]


def write_results(comm: MPI.Comm, out: Path, results: dict[str, Any]) -> Path:
    """Write ``results`` as JSON to out/results.json on rank 0 of ``comm``, creating the
    folder; return the path (on every rank). Not collective."""
    path = Path(out) / "results.json"
    if comm.rank == 0:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(results, indent=2))
    return path


def write_gmsh_file(
    comm: MPI.Comm, path: Path, build: Callable[[Any, float], None], *, h: float, dim: int
) -> Path:
    """On rank 0: the gmsh model that ``build(gmsh, h)`` makes in a fresh gmsh session
    (``fem_py.mesh.gmsh_mesh.gmsh_session``; h the mesh size, for the point sizes of a
    built-in kernel's model), meshed in ``dim`` dimensions with cells of size at most ``h``
    on one thread (the same mesh on every run) and written to ``path``, its
    folder created; the other ranks wait for the file, and an exception there is raised on
    every rank (``fem_py.parallel.run_on_root``). Return ``path``. Collective."""
    from fem_py.mesh.gmsh_mesh import gmsh_session
    from fem_py.parallel import run_on_root

    def write() -> None:
        with gmsh_session() as gmsh:
            gmsh.option.setNumber("General.NumThreads", 1)
            build(gmsh, h)
            gmsh.option.setNumber("Mesh.MeshSizeMax", h)
            gmsh.model.mesh.generate(dim)
            Path(path).parent.mkdir(parents=True, exist_ok=True)
            gmsh.write(str(path))

    run_on_root(comm, write)
    return Path(path)
