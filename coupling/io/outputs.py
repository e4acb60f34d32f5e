"""Outputs of a run: summary.json, fields.npz, solution.xdmf and PNG plots.

fields.npz holds, in the input numbering of the mesh nodes (the same for any number of
ranks, :mod:`fem_py.numbering`), ``x`` (N, 2), ``u`` (N,) and ``triangles`` (n_cells,
3); along Gamma, counter-clockwise from the first polygon vertex, ``boundary_x`` (n, 2),
``boundary_u``, the gap ``phi`` (0 on Gamma_t), ``ue`` = u + phi - u0, ``active`` (bool:
Signorini node in contact), ``signorini`` (bool: node carrying a phi unknown), all (n,);
``pressure``, rho du_h/dn at the nodes (the contact pressure on Gamma_s); ``dn_ue``, the
coefficients of du_e/dn in the flux space (n nodal values for "p1", n
panel values for "p0", panel i = [node i, node i+1]); and the scalars ``a`` and
``flux_space`` that ``fembem exterior`` needs; with ``[output] indicators``, ``indicators``
(n_cells,), the estimator's eta_T per cell in the order of ``triangles`` (sum of squares
eta^2, coupling.adapt.estimator).

Every file is written atomically (:mod:`coupling.io.atomic`), so an interrupted run
never leaves a half-written file under its final name. Rank 0 writes the gathered
files; the XDMF file is written collectively.
"""
from __future__ import annotations

import dataclasses
import json
import os
import shutil
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Callable, Mapping

import numpy as np
from mpi4py import MPI

from coupling.io.atomic import atomic_write
from coupling.io.levels import LEVEL_FILES, write_levels
from coupling.io.plots import PLOT_FILES, exterior_samples, write_plots
from coupling.io.quantities import boundary_flux, complementarity, log_coefficient
from fem_py.mesh_facts import mesh_facts
from fem_py.numbering import gather_cells, gather_p1
from fem_py.parallel import broadcast_from_root

__all__ = [
    "DATA_FILES",
    "write_outputs",
    "boundary_fields",
    "gather_p1",
    "load_fields",
    "load_summary",
    "summary",
]

#: The files of a run besides the plots (coupling.plots.PLOT_FILES).
DATA_FILES = ("summary.json", "fields.npz", "solution.xdmf", "solution.h5")


def summary(problem, result, timings: Mapping[str, float], pressure: np.ndarray) -> dict:
    """The contents of summary.json (without ``config`` and ``files``); ``pressure`` is
    :func:`coupling.io.quantities.boundary_flux` (boundary order)."""
    return {
        "converged": bool(result.converged),
        "reason": result.reason,
        "iterations": int(result.iterations),
        "energy": float(result.energy),
        "dofs": int(problem.V.dofmap.index_map.size_global),
        "boundary_dofs": int(problem.boundary.dofs.size),
        "signorini_dofs": int(problem.n_signorini),
        "contact_nodes": int(np.count_nonzero(result.contact)),
        "tau": float(result.tau),
        "C0_estimate": float(result.C0),
        "energy_increases": int(result.energy_increases),
        "complementarity": complementarity(result.phi, pressure[problem.boundary.signorini]),
        "b": log_coefficient(problem, result),
        "mpi_ranks": int(problem.comm.size),
        "timings": {k: float(v) for k, v in timings.items()},
        "history": [dataclasses.asdict(r) for r in result.history],
    }


def boundary_fields(problem, result, pressure: np.ndarray) -> dict[str, np.ndarray]:
    """The boundary arrays of fields.npz, all in the counter-clockwise boundary order.

    ``phi`` is the gap on every node (0 on Gamma_t and at arc end points), ``active``
    marks the Signorini nodes in contact (phi_h = 0), ``signorini`` the nodes that carry
    a phi unknown (interior nodes of the Signorini arcs), ``pressure`` the flux
    rho du_h/dn (:func:`coupling.io.quantities.boundary_flux`; the contact pressure on
    Gamma_s).
    """
    boundary = problem.boundary
    n = boundary.n_gamma
    phi, active, signorini = np.zeros(n), np.zeros(n, bool), np.zeros(n, bool)
    phi[boundary.signorini] = result.phi
    active[boundary.signorini] = result.contact
    signorini[boundary.signorini] = True
    return dict(
        boundary_x=boundary.nodes,
        boundary_u=result.boundary_u,
        phi=phi,
        ue=result.ue,
        dn_ue=result.flux,
        pressure=pressure,
        active=active,
        signorini=signorini,
    )


def write_outputs(
    comm: MPI.Comm,
    out: Path,
    problem,
    result,
    *,
    tol: float,
    timings: Mapping[str, float],
    xdmf: bool,
    plots: bool,
    config: dict | None = None,
    total: Callable[[], float] | None = None,
    levels: list[dict] | None = None,
    adaptive: bool = False,
    estimator: float | None = None,
    error: float | None = None,
    indicators: np.ndarray | None = None,
    facts: dict | None = None,
) -> list[str]:
    """Write summary.json, fields.npz and, on request, solution.xdmf/.h5 and the plots.

    Collective. Files of an earlier run in ``out`` that this run does not write (plots
    when ``plots`` is false now, ...) are removed, so the folder never mixes two runs.
    ``tol`` is the solver tolerance (drawn in history.png), ``timings`` the seconds per
    stage of the run so far, to which summary.json adds ``outputs`` (this call) and, when
    ``total`` (a clock of the whole process) is given, ``total`` read just before
    summary.json, the last file, is written. ``config`` (the validated configuration)
    is stored in summary.json. ``levels`` (one record per level) go to summary.json and
    to adapt.csv / adapt.png (``adaptive``) or levels.csv (a nested solve,
    :mod:`coupling.io.levels`); ``estimator`` (eta) and ``error`` (|u_h - u|_1 against
    ``[data] exact``) to summary.json; ``indicators``, eta_T^2 of the owned cells (local
    cell order), as ``indicators`` = eta_T in fields.npz, in the order of ``triangles``;
    ``facts`` (:func:`fem_py.mesh_facts.mesh_facts` of ``problem.domain``, computed here
    when not given) to summary.json.

    Returns
    -------
    list of str
        The names of the files written (the same on every rank).
    """
    tic = time.perf_counter()
    out = Path(out)
    gathered = gather_p1(result.u)
    cells = None if indicators is None else gather_cells(problem.V, np.sqrt(indicators))
    pressure = boundary_flux(problem, result)
    facts = mesh_facts(problem.domain) if facts is None else facts  # collective
    on_gamma = dict(
        boundary_fields(problem, result, pressure),
        a=np.array(problem.a),
        flux_space=np.array(problem.flux_space),
    )
    fields = None
    if comm.rank == 0:
        x, u, triangles = gathered
        fields = dict(
            x=x,
            u=u,
            triangles=triangles,
            **on_gamma,
            **({} if cells is None else {"indicators": cells}),
        )
    # Rank 0 hands two jobs that release the GIL and make no MPI call to threads, both
    # started before the collective XDMF write (which holds the GIL): u_e on the
    # whole-plane grid (bem_cpp) and fields.npz (file writes). Leaving the block waits
    # for both, also on an error (KeyboardInterrupt included), so no file is left
    # half-written.
    with ThreadPoolExecutor(max_workers=2) as pool:
        exterior = data = None
        if comm.rank == 0:
            exterior = pool.submit(exterior_samples, on_gamma) if plots else None
            data = pool.submit(
                atomic_write, out / "fields.npz", lambda p: np.savez(p, **fields)  # p: .npz
            )
        written = []
        if xdmf:
            _write_xdmf(comm, out, problem, result)
            written += ["solution.xdmf", "solution.h5"]

        def write_gathered() -> list[str]:  # rank 0
            names = list(written)
            if plots:
                names += write_plots(out, fields, result.history, tol=tol, exterior=exterior.result)
            data.result()  # its error, if any
            names.append("fields.npz")
            if levels:
                names += write_levels(out, levels, adaptive=adaptive, plot=plots)
            stages = {**timings, "outputs": time.perf_counter() - tic}
            if total is not None:
                stages["total"] = total()
            record = {**summary(problem, result, stages, pressure), **facts}
            if estimator is not None:  # the global a posteriori estimator eta
                record["estimator"] = estimator
            if error is not None:  # the energy error against the exact solution
                record["error"] = error
            if levels is not None:  # a nested or adaptive solve: one record per level
                record["levels"] = levels
            if config is not None:
                record["config"] = config
            record["files"] = sorted(names + ["summary.json"])
            # last, so that a summary.json names a complete set of files
            atomic_write(
                out / "summary.json",
                lambda p: p.write_text(json.dumps(record, indent=2, default=str)),
            )
            names.append("summary.json")
            for name in set(DATA_FILES + PLOT_FILES + LEVEL_FILES) - set(names):
                (out / name).unlink(missing_ok=True)
            return names

        return broadcast_from_root(comm, write_gathered)  # a write error ends every rank


def _write_xdmf(comm: MPI.Comm, out: Path, problem, result) -> None:
    """solution.xdmf/.h5 written in a temporary subfolder, then moved (the .xdmf names
    its .h5 relatively, so both keep their final names)."""
    from dolfinx import io

    tmp = out / ".xdmf-tmp"
    if comm.rank == 0:
        tmp.mkdir(exist_ok=True)
    comm.barrier()
    with io.XDMFFile(comm, str(tmp / "solution.xdmf"), "w") as xdmf:
        xdmf.write_mesh(problem.domain.mesh)
        problem.domain.cell_tags.name = "subdomains"
        xdmf.write_meshtags(problem.domain.cell_tags)
        xdmf.write_function(result.u)
    comm.barrier()
    if comm.rank == 0:
        for name in ("solution.h5", "solution.xdmf"):
            os.replace(tmp / name, out / name)
        shutil.rmtree(tmp, ignore_errors=True)
    comm.barrier()


def load_summary(result_dir: Path) -> dict:
    """summary.json of a complete run: every file it lists is present (rank-independent).

    Raises
    ------
    FileNotFoundError
        The folder holds no complete run (no or unreadable summary.json, or a file that
        summary.json lists is missing), with a message that says so.
    """
    result_dir = Path(result_dir)
    path = result_dir / "summary.json"
    hint = "give the output folder of a finished `fembem solve` run"
    try:
        record = json.loads(path.read_text())
        files = list(record["files"])
    except FileNotFoundError:
        raise FileNotFoundError(
            f"{str(result_dir)!r} holds no complete run (summary.json not found, so fields.npz "
            f"is not read); {hint}"
        ) from None
    except (OSError, ValueError, KeyError, TypeError):
        raise FileNotFoundError(f"{str(path)!r} is not a complete summary; {hint}") from None
    missing = [name for name in files if not (result_dir / name).is_file()]
    if missing:
        raise FileNotFoundError(
            f"{str(result_dir)!r} is not a complete run ({missing[0]} listed in summary.json "
            f"is missing); {hint}"
        )
    return record


def load_fields(result_dir: Path) -> dict:
    """Read fields.npz of a complete run (:func:`load_summary`; rank-independent)."""
    load_summary(result_dir)
    with np.load(Path(result_dir) / "fields.npz") as data:
        return {k: data[k] for k in data.files}
