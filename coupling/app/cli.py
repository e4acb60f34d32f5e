"""Command line ``fembem``: ``solve``, ``info``, ``evaluate``, ``exterior`` and
``check-jacobian`` (docs/guide/cli.md).

Exit codes (:mod:`coupling.app.ending`, docs/guide/exit-codes.md): 0 success, 1 a check
failed (check-jacobian) or an internal error (a bug: one line, the traceback with
--debug), 2 bad input (one line on stderr naming the
configuration key or file and the fix; a traceback only with --debug), 3 the solver did
not converge (outputs are still written), 130 and 143 interrupted by SIGINT (Ctrl-C) and
SIGTERM (one line on stderr; the output folder is left as it was); under mpirun an
interrupt ends with mpirun's own exit code, 1, and the line "interrupted".

Under mpirun every rank runs the same command on MPI.COMM_WORLD. The inputs are
validated identically on every rank before the first collective call, errors raised
inside collective steps are broadcast by them (fem_py.parallel, coupling.io), and
only rank 0 prints, so a bad input ends every rank with exit code 2 and one message.
An exception raised on some ranks only (a bug, or a resource failing on one rank) would
leave the others waiting in a collective call: a failing rank waits a moment for every
rank to fail alike, and otherwise prints its one line (naming the rank) and leaves at
once without MPI's finalisation, which makes mpirun end every other rank
(:func:`coupling.app.ending.end_with_error`). An unexpected exception (not bad input) is
one line and exit code 1, its traceback with --debug.
"""
from __future__ import annotations

import argparse
import contextlib
import json
import os
import signal
import sys
import time
import traceback
from pathlib import Path
from typing import Any

import numpy as np

from coupling.app.ending import (
    EXIT_CHECK_FAILED,
    EXIT_INTERRUPTED,
    EXIT_NOT_CONVERGED,
    EXIT_OK,
    end_with_error,
    error_line,
)


class Interrupted(BaseException):
    """SIGINT or SIGTERM arrived (a BaseException, like KeyboardInterrupt, so that no
    ``except Exception`` swallows it; the output folder is cleaned up on the way out)."""

    def __init__(self, signum: int):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


class InterruptHandler:
    """The SIGINT/SIGTERM handler of one command: it reports the interrupt at once (before
    any clean-up: mpirun may stop forwarding output soon after it forwards a signal) and
    raises :class:`Interrupted`. Once the output folder is staged (``staging``), the
    first rank to claim it reports (another rank may be stuck in a collective call);
    before, rank 0 does."""

    def __init__(self) -> None:
        self._staging: Path | None = None
        self.watchdog: Any = None  # coupling.app.watchdog.SignalWatchdog, when running

    @property
    def staging(self) -> Path | None:
        return self._staging

    @staging.setter
    def staging(self, path: Path) -> None:
        self._staging = path
        if self.watchdog is not None:
            self.watchdog.staging(path)

    def __call__(self, signum: int, frame: object) -> None:
        for s in EXIT_INTERRUPTED:  # a second signal must not interrupt the clean-up
            signal.signal(s, signal.SIG_IGN)
        if self.staging is not None:
            from coupling.io.atomic import claim

            report = claim(self.staging)
        else:
            report = _rank() == 0
        if report:
            print(f"fembem: {interrupt_line(signum)}", file=sys.stderr, flush=True)
        if self.watchdog is not None:
            self.watchdog.reported()  # also when another rank reports: once is enough
        raise Interrupted(signum)


def _world_size() -> int:
    """The number of MPI ranks, without starting MPI if it is not started yet."""
    if "mpi4py.MPI" in sys.modules:
        return sys.modules["mpi4py.MPI"].COMM_WORLD.size
    return int(os.environ.get("OMPI_COMM_WORLD_SIZE", os.environ.get("PMI_SIZE", "1")))


def interrupt_line(signum: int) -> str:
    """The line that reports an interrupt: the signal by name in a serial run; under
    mpirun only "interrupted", since mpirun turns the user's Ctrl-C into a SIGTERM to
    every rank (and itself exits with code 1)."""
    how = "interrupted" if _world_size() > 1 else f"interrupted by {signal.Signals(signum).name}"
    return f"{how}; no output of this run was kept"


def _rank() -> int:
    """This process's MPI rank, without starting MPI if it is not started yet."""
    if "mpi4py.MPI" in sys.modules:
        return sys.modules["mpi4py.MPI"].COMM_WORLD.rank
    return int(os.environ.get("OMPI_COMM_WORLD_RANK", os.environ.get("PMI_RANK", "0")))


def _say(message: str) -> None:
    """One line on stderr, from rank 0 only."""
    if _rank() == 0:
        print(f"fembem: {message}", file=sys.stderr, flush=True)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="fembem",
        description="Nonlinear FEM-BEM coupling with Signorini contact, solved by the "
        "preconditioned projection-gradient method with a substructuring preconditioner "
        "(Hu & Yu, Sci China Math 2010). Run under mpirun for MPI.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    def common(p: argparse.ArgumentParser) -> None:
        p.add_argument(
            "--set",
            action="append",
            default=[],
            metavar="SECTION.KEY=VALUE",
            help="override a configuration key (TOML value; repeatable)",
        )
        p.add_argument("--debug", action="store_true", help="show tracebacks on errors")

    solve = sub.add_parser(
        "solve",
        help="solve the problem of a TOML configuration",
        description="Solve the coupled problem described by CONFIG "
        "and write summary.json, fields.npz, solution.xdmf and plots.",
    )
    solve.add_argument("config", metavar="CONFIG.toml")
    solve.add_argument("--out", metavar="DIR", help="output folder (default: [output] dir)")
    solve.add_argument(
        "--force",
        action="store_true",
        help="write into a non-empty DIR, replacing the files of an earlier "
        "run and deleting those this run does not write",
    )
    solve.add_argument("--quiet", action="store_true", help="no progress lines")
    common(solve)

    info = sub.add_parser(
        "info",
        help="the size of a run without running it",
        description="Validate CONFIG and print, without solving, the sizes of its problem "
        "(dofs, on Gamma, Signorini unknowns, subdomains of a planar domain, the mesh size; "
        "in closed form for the structured square and L-shape and the box, otherwise "
        "estimated before meshing and the mesh built and counted when it fits in memory), "
        "the choices the run will make (solver, preconditioner, S_h dense or a hierarchical "
        "matrix with its tolerance, the coarser levels of a nested solve) and the estimated "
        "peak memory of `fembem solve`. --json prints every field: dofs, boundary_dofs, "
        "signorini_dofs, subdomains, h_min, h_max, dim, components, memory_estimate_bytes, "
        "memory_available_bytes, mpi_ranks, sizes, domain, method, preconditioner, "
        "boundary_operator, hmatrix_tol, nested_levels (their h), adaptive_steps.",
    )
    info.add_argument("config", metavar="CONFIG.toml")
    info.add_argument("--json", action="store_true", help="print the report as JSON")
    common(info)

    def result_reader(name: str, help: str, description: str, out: str) -> None:
        reader = sub.add_parser(name, help=help, description=description)
        reader.add_argument("result_dir", metavar="RESULT_DIR")
        reader.add_argument("--points", required=True, metavar="FILE.csv")
        reader.add_argument("--out", metavar="FILE.csv", help=f"{out} (default: stdout)")
        reader.add_argument("--debug", action="store_true", help="show tracebacks on errors")

    result_reader(
        "exterior",
        "u_e at exterior points from a finished run",
        "Evaluate the exterior solution u_e at the points of a CSV file (two columns x, y; "
        "three, x, y, z, for a 3D run; an optional header line) by the representation "
        "formula, from the fields.npz of RESULT_DIR. An elastic run: the displacement "
        "ue_x,ue_y(,ue_z) and the stress sigma_xx,sigma_yy,sigma_xy (3D: xx,yy,zz,xy,yz,zx) "
        "of the medium.",
        "write x,y,ue (x,y,z,ue) here",
    )
    result_reader(
        "evaluate",
        "u_h and u_e at any points from a finished run",
        "Evaluate the solution at the points of a CSV file (two columns x, y; three for a "
        "3D run; an optional header line) from the fields.npz of RESULT_DIR: each row "
        "x,y(,z),where,u,ue with "
        "where = inside (u = u_h), boundary (u_h and the trace u_e) or outside (u_e by the "
        "representation formula); a value that does not apply is empty; an elastic run's "
        "u and ue have d columns, u_x,u_y(,u_z). A point closer to "
        "Gamma than 1e-11 times the diameter of its bounding box is on Gamma (boundary); "
        "x,y are echoed as given.",
        "write the table here",
    )

    check = sub.add_parser(
        "check-jacobian",
        help="compare the UFL and handwritten Jacobians (Taylor test)",
        description="Assemble both Jacobians of the interior energy at "
        "several smooth random states; exit 0 when they agree to 1e-10 "
        "relative and the Taylor remainder slope is 2 +- 0.1, else 1.",
    )
    check.add_argument("config", metavar="CONFIG.toml")
    check.add_argument("--json", action="store_true", help="print the report as JSON")
    common(check)

    return parser


def _problem_inputs(args: argparse.Namespace) -> Any:
    """The validated :class:`coupling.options.RunConfig` of ``args``: schema, data
    expressions and material.

    Everything here is cheap and identical on every rank, so a bad input fails fast and
    on all ranks alike (no rank waits in a collective call for another).
    """
    from coupling.app.config import check_data_and_material, load_config

    config = load_config(args.config, args.set)
    check_data_and_material(config)
    return config


def _with_geometry_key(build, *args):
    """Call ``build(*args)``; a geometry error is re-raised naming its [geometry] key."""
    from coupling.app.config import geometry_error

    try:
        return build(*args)
    except ValueError as err:
        named = geometry_error(err)
        if named is err:
            raise
        raise named from None


def _solve(args: argparse.Namespace, interrupts: InterruptHandler) -> int:
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    config = _problem_inputs(args)
    from coupling.app.from_config import estimated_size, planned_size
    from coupling.app.sizing import check_memory, equation_size
    from coupling.io.figure_worker import FigureWorker

    # the geometry and the size refused before anything is built: checks alike on every
    # rank, made before rank 0 alone starts the figure process (which competes for the
    # cores), so that every rank meets a bad input at the same moment (coupling.app.ending)
    size = _with_geometry_key(planned_size, config)
    # closed form, else estimated from the area and h
    rough = size if size is not None else _with_geometry_key(estimated_size, config)
    if rough is not None:
        check_memory(
            equation_size(rough, config),
            comm.size,
            plots=config.output.plots,
            boundary_operator=config.solver.boundary_operator,
        )
    # the figure process starts next, to import matplotlib while the run imports and
    # computes; it is ended on every way out of the run
    worker = (
        FigureWorker(body=config.geometry.dim == 3)
        if config.output.plots and comm.rank == 0
        else None
    )
    with worker if worker is not None else contextlib.nullcontext():
        return _solve_config(args, interrupts, comm, config, worker, size)


def _solve_config(
    args: argparse.Namespace,
    interrupts: InterruptHandler,
    comm: Any,
    config: Any,
    worker: Any,
    size: Any,
) -> int:
    """``fembem solve`` of the validated ``config`` (the figure process ``worker`` started;
    ``size``: :func:`coupling.app.from_config.planned_size`, None for a gmsh mesh)."""
    plots, kind = config.output.plots, config.solver.boundary_operator
    from coupling.app.advice import arc_warnings, material_warnings
    from coupling.app.from_config import domain_from_config, problem_on_domain
    from coupling.app.progress import ProgressMonitor
    from coupling.app.run import run_solver
    from coupling.app.sizing import check_memory, equation_size, size_of_domain
    from fem_py.mesh import mesh_facts
    from coupling.io.atomic import staged_output_dir
    from coupling.io.outputs import RunOutputs
    from coupling.timing import process_seconds

    out = Path(args.out if args.out is not None else config.output.dir)
    # the run is written beside ``out`` and moved into place once complete
    monitor = None if args.quiet else ProgressMonitor(comm)
    with staged_output_dir(comm, out, force=args.force) as staging, RunOutputs(
        comm, staging, config.output, tol=config.solver.tol, worker=worker
    ) as outputs:
        interrupts.staging = staging  # from here the first rank to claim it reports
        startup = process_seconds()
        if monitor is not None:
            monitor.stage("building the mesh and assembling the problem")
        tic = time.perf_counter()
        domain = _with_geometry_key(domain_from_config, comm, config)
        mesh_time = time.perf_counter() - tic
        if size is None:  # a gmsh mesh: refuse before the boundary matrices are formed
            check_memory(
                equation_size(size_of_domain(domain), config),
                comm.size,
                plots=plots,
                boundary_operator=kind,
            )
        problem, options, timings = problem_on_domain(domain, config)
        timings = {"mesh": mesh_time, **timings}
        facts = mesh_facts(domain)  # collective
        # the length of each entry of geometry.signorini, a closed "all" whole (as in
        # summary.json); only an arc given by two points has ends the user may have swapped
        arc_lengths = facts.get("signorini_lengths", [])  # none in 3D (faces, not arcs)
        entries = config.geometry.signorini
        chosen_ends = [] if entries == "all" else [not isinstance(e, str) for e in entries]
        gamma = float(problem.boundary.lumped_mass.sum())
        for line in material_warnings(problem.material) + arc_warnings(
            arc_lengths, [not ends for ends in chosen_ends], gamma
        ):
            _say(f"warning: {line}")
        if monitor is not None:
            monitor.problem(problem, options, arc_lengths, facts)
        adaptive = config.adapt.steps > 0

        def after_solve(problem: Any, solution: Any, levels: list[dict] | None) -> None:
            outputs.start(problem, solution, levels=levels, adaptive=adaptive)

        run = run_solver(comm, config, domain, problem, timings, monitor, after_solve=after_solve)
        result = run.solution
        if monitor is not None:
            monitor.finished(result)
            monitor.stage(f"writing outputs to {out}")
        outputs.finish(
            timings={"startup": startup, **run.timings},
            total=process_seconds,
            config=config,
            levels=run.levels,
            adaptive=adaptive,
            estimator=run.estimator,
            error=run.error,
            indicators=run.indicators,
            facts=facts if run.problem.domain is domain else None,
        )
    if comm.rank == 0 and not args.quiet:
        print(f"fembem: {final_line(result, run.levels, adaptive)}; outputs in {out}")
    return EXIT_OK if result.converged else EXIT_NOT_CONVERGED


def final_line(result: Any, levels: list[dict] | None, adaptive: bool) -> str:
    """The last line of ``fembem solve``: whether the final solve converged, after how many
    iterations, and, for a run over several levels (nested, or ``adaptive``), the
    iterations of each level and their total."""
    state = "converged" if result.converged else "did NOT converge"
    if not levels or len(levels) < 2:
        return f"{state} after {result.iterations} iterations ({result.reason})"
    counts = [int(r["iterations"]) for r in levels]
    kind = "adaptive" if adaptive else "nested"
    return (
        f"{state} after {result.iterations} iterations on the final level ({result.reason}); "
        f"{sum(counts)} iterations in all over {len(counts)} {kind} levels "
        f"({' + '.join(map(str, counts))})"
    )


def _info(args: argparse.Namespace, interrupts: InterruptHandler) -> int:
    from mpi4py import MPI

    from coupling.app.from_config import domain_from_config, estimated_size, planned_size
    from coupling.app.info import info_lines, info_report
    from coupling.app.sizing import equation_size, memory_available, memory_estimate
    from coupling.app.sizing import size_of_domain

    comm = MPI.COMM_WORLD
    config = _problem_inputs(args)
    size = _with_geometry_key(planned_size, config)
    how = "closed form"
    if size is None:
        size = _with_geometry_key(estimated_size, config)
        how = "estimated from the size of Omega and h: the mesh would not fit in memory"
        if (
            size is None
            or memory_estimate(
                equation_size(size, config),
                comm.size,
                plots=config.output.plots,
                boundary_operator=config.solver.boundary_operator,
            )
            <= memory_available()
        ):  # a mesh that cannot fit is not built to be counted
            size = size_of_domain(_with_geometry_key(domain_from_config, comm, config))
            how = "from the mesh"
    report = info_report(comm, config, size=size, how=how)
    if comm.rank == 0:
        if args.json:
            print(json.dumps(report, indent=2))
        else:
            print("\n".join(info_lines(report, config)))
    return EXIT_OK


def _read_points(path: Path, dim: int = 2) -> tuple[np.ndarray, list[str]]:
    """The (m, dim) points of a CSV file of x,y rows (x,y,z for a body in R^3; an optional
    header line), and each row as written there (echoed in the output as given)."""
    names = "x,y,z"[: 2 * dim - 1]
    count = {2: "two", 3: "three"}[dim]
    if not path.is_file():
        raise FileNotFoundError(
            f"--points: file {str(path)!r} not found; give a CSV file of {names} rows"
        )
    lines = [ln for ln in path.read_text().splitlines() if ln.strip()]
    if lines and not lines[0].lstrip()[0] in "+-.0123456789":
        lines = lines[1:]
    try:
        points = np.array([[float(v) for v in ln.split(",")] for ln in lines], dtype=float)
    except ValueError:
        raise ValueError(f"--points {path}: every row must be {count} numbers {names}") from None
    if points.ndim != 2 or points.shape[1] != dim or not np.isfinite(points).all():
        raise ValueError(f"--points {path}: every row must be {count} finite numbers {names}")
    return points, [",".join(v.strip() for v in ln.split(",")) for ln in lines]


def _result_points(args: argparse.Namespace) -> tuple[dict, np.ndarray, list[str], str]:
    """fields.npz of the result folder of ``evaluate`` or ``exterior``, the points of
    ``--points`` in its dimension, each row as given, and the CSV header of the points."""
    from coupling.io.outputs import load_fields

    fields = load_fields(Path(args.result_dir))
    dim = fields["x"].shape[1]
    points, given = _read_points(Path(args.points), dim)
    return fields, points, given, "x,y,z"[: 2 * dim - 1]


#: The stress components of the exterior table of an elastic run, by the dimension.
STRESS_COMPONENTS = {2: ("xx", "yy", "xy"), 3: ("xx", "yy", "zz", "xy", "yz", "zx")}


def _names(name: str, values: np.ndarray) -> list[str]:
    """The CSV columns of ``values`` (m,) or (m, d): ``name``, or name_x, name_y(, name_z)."""
    return [name] if values.ndim == 1 else [f"{name}_{c}" for c in "xyz"[: values.shape[1]]]


def _number(v: float) -> str:
    """A CSV cell: empty for NaN (a value that does not apply), else 17 digits."""
    return "" if np.isnan(v) else f"{v:.17g}"


def _rows(given: list[str], *columns: np.ndarray) -> str:
    """The CSV rows: each point as given, then the values of ``columns`` ((m,) or (m, k))."""
    blocks = [np.asarray(c, dtype=float).reshape(len(given), -1) for c in columns]
    table = np.hstack(blocks) if blocks else np.zeros((len(given), 0))
    return "".join(",".join([xy, *map(_number, row)]) + "\n" for xy, row in zip(given, table))


def _exterior(args: argparse.Namespace, interrupts: InterruptHandler) -> int:
    from coupling.io.evaluation import exterior_from_fields, exterior_stress_from_fields

    fields, points, given, header = _result_points(args)
    try:
        ue = exterior_from_fields(fields, points)
        columns, names = [ue], _names("ue", ue)
        if "exterior" in fields:  # elasticity: the medium's stress too
            sigma, stress_names = _stress_columns(exterior_stress_from_fields(fields, points))
            columns.append(sigma)
            names += stress_names
    except ValueError as err:  # a point inside Omega or on Gamma
        raise ValueError(f"--points {args.points}: {err}") from None
    _write_table(",".join([header, *names]) + "\n" + _rows(given, *columns), args.out)
    return EXIT_OK


def _write_table(table: str, out: str | None) -> None:
    """A CSV table to ``out`` (atomically) or stdout, from rank 0 (every rank computed it)."""
    from coupling.io.atomic import atomic_write

    if _rank() == 0:
        if out:
            atomic_write(Path(out), lambda p: p.write_text(table))
        else:
            sys.stdout.write(table)


def _evaluate(args: argparse.Namespace, interrupts: InterruptHandler) -> int:
    from coupling.app.from_config import run_material
    from coupling.io.evaluation import evaluate

    fields, points, given, header = _result_points(args)
    elastic = "exterior" in fields
    material = run_material(Path(args.result_dir), points.shape[1]) if elastic else None
    values = evaluate(fields, points, material)
    u, ue = values["u"], values["ue"]
    columns, names = [u, ue], [header, "where", *_names("u", u), *_names("ue", ue)]
    if "sigma" in values:  # elasticity: the body's stress inside, the medium's outside
        sigma, stress_names = _stress_columns(values["sigma"])
        columns.append(sigma)
        names += stress_names
    where = [f"{xy},{w}" for xy, w in zip(given, values["where"])]
    _write_table(",".join(names) + "\n" + _rows(where, *columns), args.out)
    return EXIT_OK


def _stress_columns(sigma: np.ndarray) -> tuple[np.ndarray, list[str]]:
    """The CSV columns of the stress tensors ``sigma`` (m, d, d): the components of
    :data:`STRESS_COMPONENTS` and their names sigma_xx, ..."""
    components = STRESS_COMPONENTS[sigma.shape[-1]]
    pairs = [("xyz".index(c[0]), "xyz".index(c[1])) for c in components]
    return np.stack([sigma[:, i, j] for i, j in pairs], axis=1), [f"sigma_{c}" for c in components]


def _check_jacobian(args: argparse.Namespace, interrupts: InterruptHandler) -> int:
    from mpi4py import MPI

    from coupling.app.from_config import domain_from_config, material_from_config
    from fem_py.forms import check_jacobian

    comm = MPI.COMM_WORLD
    config = _problem_inputs(args)
    domain = _with_geometry_key(domain_from_config, comm, config)
    report = check_jacobian(domain, material_from_config(config, domain.dim))
    if comm.rank == 0:
        if args.json:
            print(json.dumps(report, indent=2, default=float))
        else:
            for key, value in report.items():
                print(f"{key}: {value}")
    return EXIT_OK if report["passed"] else EXIT_CHECK_FAILED


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit code. SIGINT and SIGTERM end it with one
    line and exit code 130 or 143 wherever they arrive."""
    from coupling.app.watchdog import SignalWatchdog

    interrupts = InterruptHandler()
    previous = {s: signal.signal(s, interrupts) for s in EXIT_INTERRUPTED}
    import petsc4py

    # signals stay Python's (PETSc's handlers would print a crash report instead)
    petsc4py.init([sys.argv[0], "-no_signal_handler"])
    try:
        # a helper process ends the run if a signal finds it stuck in native code
        with SignalWatchdog({s: interrupt_line(s) for s in EXIT_INTERRUPTED}, _rank()) as dog:
            interrupts.watchdog = dog
            return _main(sys.argv[1:] if argv is None else list(argv), interrupts)
    except Interrupted as err:  # reported by the handler
        return EXIT_INTERRUPTED[err.signum]
    finally:
        interrupts.watchdog = None
        for s, handler in previous.items():
            signal.signal(s, handler)


def _main(argv: list[str], interrupts: InterruptHandler) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return EXIT_OK
    handler = {
        "solve": _solve,
        "info": _info,
        "exterior": _exterior,
        "evaluate": _evaluate,
        "check-jacobian": _check_jacobian,
    }[args.command]
    from mpi4py import MPI
    from threadpoolctl import threadpool_limits

    from fem_py.parallel import threads_per_rank

    comm = MPI.COMM_WORLD
    errors = comm.Dup() if comm.size > 1 else None  # only failing ranks meet on it
    try:
        with threadpool_limits(threads_per_rank(comm)):  # no oversubscription
            return handler(args, interrupts)
    except Exception as err:  # noqa: BLE001 - every exception ends every rank, one line
        code, message = error_line(err)
        if args.debug:
            if errors is None:
                raise
            traceback.print_exc()
        return end_with_error(errors, code, message)


if __name__ == "__main__":
    sys.exit(main())
