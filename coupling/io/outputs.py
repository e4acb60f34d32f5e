"""Outputs of a run: summary.json, fields.npz, solution.xdmf and PNG plots.

fields.npz holds, in the input numbering of the mesh nodes (the same for any number of
ranks, :mod:`fem_py.dofs.numbering`), ``x`` (N, 2), ``u`` (N,) and ``triangles`` (n_cells,
3); along Gamma, counter-clockwise from the first polygon vertex, ``boundary_x`` (n, 2),
``boundary_u``, the gap ``phi`` (0 on Gamma_t), ``ue`` = u + phi - u0, ``active`` (bool:
Signorini node in contact), ``signorini`` (bool: node carrying a phi unknown), all (n,);
``pressure``, rho du_h/dn at the nodes (the contact pressure on Gamma_s); ``dn_ue``, the
coefficients of du_e/dn in the flux space (n nodal values for "p1", n
panel values for "p0", panel i = [node i, node i+1]); and the scalars ``a`` and
``flux_space`` that ``fembem exterior`` needs; with ``[output] indicators``, ``indicators``
(n_cells,), the estimator's eta_T per cell in the order of ``triangles`` (sum of squares
eta^2, coupling.adapt.estimator).

An elastic run's fields are vectors (docs/guide/elasticity.md) and its figures those of
:mod:`coupling.io.elastic_figures` (deformed.png, signorini.png, exterior.png,
history.png).

Every file is written atomically (:mod:`coupling.io.atomic`), so an interrupted run
never leaves a half-written file under its final name. Rank 0 writes every file, from
what is gathered there (:mod:`coupling.io.xdmf` for solution.xdmf/.h5).
"""
from __future__ import annotations

import dataclasses
import json
import time
import sys
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Callable, Mapping

import numpy as np
from mpi4py import MPI

from coupling.io.atomic import atomic_write
from coupling.io.levels import LEVEL_FILES, write_levels
from coupling.io.figure_data import FigureInputs
from coupling.io.figure_worker import FigureWorker, FigureWorkerError
from coupling.io.body_figure_data import BODY_PLOT_FILES, section, surface_inputs
from coupling.io.elastic_figure_data import ELASTIC_PLOT_FILES, elastic_inputs, exterior_section
from coupling.io.plots import (
    PLOT_FILES,
    boundary_figure_inputs,
    exterior_samples,
    figure_inputs,
    history_arrays,
    write_pngs,
)
from coupling.io.xdmf import gather_xdmf_inputs, owned_cell_tags, write_solution_xdmf
from coupling.io.quantities import (
    boundary_flux,
    complementarity,
    elastic_boundary_fields,
    far_field_coefficient,
    net_force,
)
from coupling.options import OutputOptions, RunConfig
from fem_py.dofs import gather_cells, gather_p1, gather_p1_and_cells
from fem_py.mesh import mesh_facts
from fem_py.memory import release_free_memory
from fem_py.parallel import broadcast_from_root

__all__ = [
    "DATA_FILES",
    "RunOutputs",
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
    :func:`coupling.io.quantities.boundary_flux` (boundary order). The far field's leading
    coefficient is ``b`` (of log|x|) in 2D, ``c`` (of 1/|x|) in 3D."""
    if problem.components > 1:
        on_gamma = elastic_boundary_fields(problem, result, pressure)
        signorini = problem.boundary.signorini
        far_name, far_value = "force", net_force(problem, result)
        normal = on_gamma["pressure"]
        scale = float(np.abs(normal).max(initial=0.0))
        contact = complementarity(on_gamma["phi"][signorini], normal[signorini], scale)
    else:
        far_name, far_value = far_field_coefficient(problem, result)
        scale = float(np.abs(pressure).max(initial=0.0))
        contact = complementarity(result.phi, pressure[problem.boundary.signorini], scale)
    return {
        "equation": problem.equation,
        "converged": bool(result.converged),
        "reason": result.reason,
        "iterations": int(result.iterations),
        "energy": float(result.energy),
        "dofs": problem.n_dofs,
        "boundary_dofs": int(problem.boundary.dofs.size),
        "signorini_dofs": int(problem.n_signorini),
        "contact_nodes": int(np.count_nonzero(result.contact)),
        "tau": float(result.tau),
        "C0_estimate": float(result.C0),
        "energy_increases": int(result.energy_increases),
        "complementarity": contact,
        far_name: far_value,
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
    surface = getattr(boundary, "triangles", None)  # 3D: Gamma_h's triangles
    if problem.components > 1:
        return dict(
            **({} if surface is None else {"boundary_triangles": surface}),
            boundary_x=boundary.nodes,
            dn_ue=np.asarray(result.flux).reshape(-1, problem.components),
            **elastic_boundary_fields(problem, result, pressure),
        )
    n = boundary.n_gamma
    phi, active, signorini = np.zeros(n), np.zeros(n, bool), np.zeros(n, bool)
    phi[boundary.signorini] = result.phi
    active[boundary.signorini] = result.contact
    signorini[boundary.signorini] = True
    return dict(
        **({} if surface is None else {"boundary_triangles": surface}),
        boundary_x=boundary.nodes,
        boundary_u=result.boundary_u,
        phi=phi,
        ue=result.ue,
        dn_ue=result.flux,
        pressure=pressure,
        active=active,
        signorini=signorini,
    )


class RunOutputs:
    """The outputs of one run, written in two phases around the run's last computation
    (the a posteriori estimator).

    :meth:`start`, right after the solve, gathers u_h, computes the boundary flux and
    hands the rest to background work on rank 0: fields.npz and solution.xdmf/.h5 (file
    writes), the samples of u_e (bem_cpp), all in threads, and the figures, drawn by
    the figure process ``worker`` (:class:`coupling.io.figure_worker.FigureWorker`) when
    one is given, from u_h rasterised here (an elastic run: the deformed body's stress
    rasterised here, the samples of u_e in a thread,
    :mod:`coupling.io.elastic_figure_data`). :meth:`finish` waits for the background
    work, writes the figures and, last, summary.json. Without a worker the figures are
    drawn in :meth:`finish`, in this process; so they are too, with a warning, if the
    worker fails.

    Use as a context manager: leaving it (on an error or KeyboardInterrupt too) ends the
    figure process and waits for the threads, so no file is left half-written.

    Parameters
    ----------
    comm
        The run's communicator (every method is collective).
    out
        The output folder.
    options
        The ``[output]`` section: write solution.xdmf/.h5 (``xdmf``), draw the figures
        (``plots``; a body's slice.png by the plane ``slice``), add the estimator's eta_T
        (given to :meth:`finish`) to fields.npz (``indicators``: it is then written there
        rather than by :meth:`start`).
    tol
        The solver tolerance (drawn in history.png).
    worker
        The figure process (rank 0), or None.
    """

    def __init__(
        self,
        comm: MPI.Comm,
        out: Path,
        options: OutputOptions,
        *,
        tol: float,
        worker: FigureWorker | None = None,
    ):
        self.comm, self.out, self.tol = comm, Path(out), tol
        self.xdmf, self.plots, self.indicators = options.xdmf, options.plots, options.indicators
        self.slice = options.slice  # the plane of a body's slice.png
        self.worker = worker if self.plots and comm.rank == 0 else None
        #: seconds spent in :meth:`start` and :meth:`finish` (summary.json's ``outputs``)
        self.seconds = 0.0
        # a thread for each job that may run at once: fields.npz, solution.xdmf/.h5, u_e's
        # samples, the early figures' send, the figures' inputs and the figure process's
        # answer (with three, the answer waited in the queue for fields.npz to be written);
        # for an elastic run the early figures' inputs and send, u_e's samples, the
        # figures' inputs and the answer, beside fields.npz and solution.xdmf/.h5
        self._pool = ThreadPoolExecutor(max_workers=6) if comm.rank == 0 else None
        self._jobs: dict[str, Future] = {}

    def start(
        self, problem, result, levels: list[dict] | None = None, adaptive: bool = False
    ) -> None:
        """Gather the run's result and start the background work (collective). ``levels``:
        the records of a run over several levels (nested, or ``adaptive``), coarsest first
        (``result`` the final level's), drawn in history.png."""
        runs = dict(levels=levels, adaptive=adaptive)
        tic = time.perf_counter()
        release_free_memory()  # the solve's freed memory, before the outputs' (fem_py.memory)
        self._problem, self._result = problem, result
        solid, elastic = problem.domain.dim == 3, problem.components > 1
        self._pressure = boundary_flux(problem, result)
        if self.comm.rank == 0:
            on_gamma = dict(
                boundary_fields(problem, result, self._pressure),
                a=np.array(problem.a),
                flux_space=np.array(problem.flux_space),
                # elasticity: the medium (E, nu) of the exterior field's kernel
                **({"exterior": np.array(problem.kernel[1:])} if problem.components > 1 else {}),
            )
            if (
                self.plots and not solid and not elastic
            ):  # u_e's samples and, in the figure process,
                # boundary.png and history.png while u_h is gathered and rasterised here
                samples = self._pool.submit(exterior_samples, on_gamma)
                if self.worker is not None:
                    early = boundary_figure_inputs(
                        on_gamma,
                        result.history,
                        tol=self.tol,
                        stop_measure=result.stop_measure,
                        **runs,
                    )
                    self._jobs["early"] = self._pool.submit(self.worker.send, early)
        cell_tags = owned_cell_tags(problem.domain) if self.xdmf else None
        gathered = gather_p1_and_cells(result.u, cell_tags)
        release_free_memory()  # and the gather's sort buffers (1.3 GB at 128^3 cubes)
        if self.xdmf:
            cells, cell_tags = (None, None) if gathered is None else gathered[2:]
            xdmf_tags = gather_xdmf_inputs(problem, cells, cell_tags)
        if self.comm.rank == 0:
            x, u, cells, _ = gathered
            self._mesh = (x, cells)  # triangles, or tetrahedra for a body
            self._fields = dict(x=x, u=u, **{"cells" if solid else "triangles": cells}, **on_gamma)
            if not self.indicators:
                self._jobs["data"] = self._pool.submit(_write_fields, self.out, self._fields)
            if self.plots and elastic:  # in threads: the stress of the deformed body,
                # sent to the figure process, which draws it, Gamma_s and the history while
                # u_e's samples are computed (bem_cpp releases the GIL)
                history = history_arrays(result.history, result.stop_measure, **runs)
                early = self._pool.submit(self._elastic_early, problem.material, history)
                exterior = self._pool.submit(
                    exterior_section, self._fields, problem.kernel, self.slice
                )
                self._jobs["inputs"] = self._pool.submit(
                    lambda: early.result()._replace(exterior=exterior.result())
                )
                if self.worker is not None:
                    self._jobs["pngs"] = self._pool.submit(
                        self.worker.render_rest, self._jobs["inputs"].result
                    )
            elif self.plots and solid:  # the section's u_e and u_h in a thread, while the
                # figure process draws those on Gamma and the history
                history = history_arrays(result.history, result.stop_measure, **runs)
                surface = surface_inputs(self._fields, history, tol=self.tol)
                self._jobs["inputs"] = self._pool.submit(
                    lambda: surface._replace(section=section(self._fields, self.slice))
                )
                if self.worker is not None:  # sent from here at once: the figure
                    # process draws the figures on Gamma from them meanwhile
                    self.worker.send(surface)
                    self._jobs["pngs"] = self._pool.submit(
                        self.worker.render_rest, self._jobs["inputs"].result
                    )
            elif self.plots:
                inputs = figure_inputs(
                    self._fields,
                    result.history,
                    tol=self.tol,
                    stop_measure=result.stop_measure,
                    **runs,
                )
                self._jobs["inputs"] = self._pool.submit(_with_samples, inputs, samples)
                if self.worker is not None:  # sent from here at once, as a body's surface
                    self._jobs["early"].result()
                    self.worker.send(self._jobs["inputs"].result())
                    self._jobs["pngs"] = self._pool.submit(self.worker.answer)
            if self.xdmf:  # after the figures' jobs, which the figure process waits for
                self._jobs["xdmf"] = self._pool.submit(
                    write_solution_xdmf, self.out, self._fields, xdmf_tags, on_gamma
                )
        self.seconds += time.perf_counter() - tic

    def finish(
        self,
        *,
        timings: Mapping[str, float],
        config: RunConfig | None = None,
        total: Callable[[], float] | None = None,
        levels: list[dict] | None = None,
        adaptive: bool = False,
        estimator: float | None = None,
        error: float | None = None,
        indicators: np.ndarray | None = None,
        facts: dict | None = None,
    ) -> list[str]:
        """Write the rest and summary.json, last (collective; after :meth:`start`).

        ``timings`` are the seconds per stage of the run so far, to which summary.json
        adds ``outputs`` (:attr:`seconds`) and, when ``total`` (a clock of the whole
        process) is given, ``total`` read just before summary.json is written.
        ``config`` (the run's configuration) is stored in summary.json. ``levels``
        (one record per level) go to summary.json and to adapt.csv / adapt.png
        (``adaptive``) or levels.csv (a nested solve, :mod:`coupling.io.levels`);
        ``estimator`` (eta) and ``error`` (|u_h - u|_1 against ``[data] exact``) to
        summary.json; ``indicators``, eta_T^2 of the owned cells (local cell order), as
        ``indicators`` = eta_T in fields.npz, in the order of ``triangles`` (when the
        options ask for them); ``facts``
        (:func:`fem_py.mesh.facts.mesh_facts` of the problem's domain, computed here when
        not given) to summary.json.

        Returns
        -------
        list of str
            The names of the files written (the same on every rank).
        """
        tic = time.perf_counter()
        problem, result, out = self._problem, self._result, self.out
        wanted = self.indicators and indicators is not None
        cells = gather_cells(problem.V, np.sqrt(indicators)) if wanted else None
        facts = mesh_facts(problem.domain) if facts is None else facts  # collective

        def write_gathered() -> list[str]:  # rank 0
            names = []
            if self.xdmf:
                self._jobs["xdmf"].result()  # its error, if any
                names += ["solution.xdmf", "solution.h5"]
            if self.indicators:  # fields.npz waited for them
                if cells is not None:
                    self._fields["indicators"] = cells
                self._jobs["data"] = self._pool.submit(_write_fields, out, self._fields)
            if self.plots:
                names += write_pngs(out, self._pngs())
            self._jobs["data"].result()  # its error, if any
            names.append("fields.npz")
            if levels:
                names += write_levels(
                    out,
                    levels,
                    adaptive=adaptive,
                    plot=self.plots,
                    mesh=self._mesh,
                )
            self.seconds += time.perf_counter() - tic
            stages = {**timings, "outputs": self.seconds}
            if total is not None:
                stages["total"] = total()
            record = {**summary(problem, result, stages, self._pressure), **facts}
            if estimator is not None:  # the global a posteriori estimator eta
                record["estimator"] = estimator
            if error is not None:  # the energy error against the exact solution
                record["error"] = error
            if levels is not None:  # a nested or adaptive solve: one record per level
                record["levels"] = levels
            if config is not None:
                record["preconditioner"] = _preconditioner_run(config, problem)
                record["config"] = config.as_dict()
            record["files"] = sorted(names + ["summary.json"])
            # last, so that a summary.json names a complete set of files
            atomic_write(
                out / "summary.json",
                lambda p: p.write_text(json.dumps(record, indent=2, default=str)),
            )
            names.append("summary.json")
            every = DATA_FILES + PLOT_FILES + BODY_PLOT_FILES + ELASTIC_PLOT_FILES + LEVEL_FILES
            for name in set(every) - set(names):
                (out / name).unlink(missing_ok=True)
            return names

        return broadcast_from_root(self.comm, write_gathered)  # a write error ends every rank

    def _elastic_early(self, material, history: dict):
        """The inputs of an elastic run's figures but exterior.png
        (:func:`coupling.io.elastic_figure_data.elastic_inputs`), sent to the figure
        process when there is one (rank 0, in a thread)."""
        early = elastic_inputs(self._fields, material, history, tol=self.tol)
        if self.worker is not None:
            self.worker.send(early)
        return early

    def _pngs(self) -> dict[str, bytes]:
        """The figures: the worker's, or drawn here (also when the worker failed)."""
        if "pngs" in self._jobs:
            try:
                return self._jobs["pngs"].result()
            except FigureWorkerError as err:
                print(
                    f"warning: the figure process failed ({err}); drawing the figures here",
                    file=sys.stderr,
                )
        from coupling.io.figures import render

        return render(self._jobs["inputs"].result())

    def __enter__(self) -> RunOutputs:
        return self

    def __exit__(self, *exc) -> None:
        if self.worker is not None:
            self.worker.close()  # a render still waiting for it returns
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)


def _with_samples(inputs: FigureInputs, samples: Future) -> FigureInputs:
    """``inputs`` with the exterior samples of ``samples`` (once computed)."""
    points, ue = samples.result()
    return inputs._replace(exterior_points=points, exterior_ue=ue)


def _preconditioner_run(config: RunConfig, problem) -> str:
    """The preconditioner the run used: ``[solver] preconditioner`` with ``"auto"``
    resolved for Omega's dimension and the equation (substructuring in 2D, amg in 3D and
    for elasticity; :func:`coupling.preconditioners.preconditioner_kind`)."""
    from coupling.preconditioners import preconditioner_kind

    return preconditioner_kind(config.solver.preconditioner, problem.domain.dim, problem.components)


def _write_fields(out: Path, fields: dict) -> None:
    atomic_write(out / "fields.npz", lambda p: np.savez(p, **fields))  # p: .npz


def write_outputs(
    comm: MPI.Comm,
    out: Path,
    problem,
    result,
    *,
    tol: float,
    xdmf: bool,
    plots: bool,
    **finish,
) -> list[str]:
    """Write summary.json, fields.npz and, on request, solution.xdmf/.h5 and the plots,
    in this process (:class:`RunOutputs` in one go; ``finish``: the keywords of
    :meth:`RunOutputs.finish`).

    Collective. Files of an earlier run in ``out`` that this run does not write (plots
    when ``plots`` is false now, ...) are removed, so the folder never mixes two runs.

    Returns
    -------
    list of str
        The names of the files written (the same on every rank).
    """
    options = OutputOptions(xdmf=xdmf, plots=plots, indicators=finish.get("indicators") is not None)
    with RunOutputs(comm, out, options, tol=tol) as run:
        run.start(problem, result)
        return run.finish(**finish)


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
