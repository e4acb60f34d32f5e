"""Peer benchmark: the project's solvers against PETSc's VI and bound-constrained solvers.

Is PGPM faster than PETSc's own solvers on the same discrete problem (2.3), and how far
is it from the cost of one linear solve? Every solver solves the same problem on the
same mesh (the square [-1/4, 1/4]^2, structured, d/h = 4, Signorini arc = bottom side,
carstensen material), for two data sets:

* ``manufactured``: ``coupling.manufactured.square_contact`` (exact solution known);
* ``load``: f = 2, t0 = -1, u0 = 0.1 x, a = 0 (no exact solution).

Solvers (``coupling.baselines`` sets them all up):

    (a) PGPM + substructuring preconditioner (the paper's method)
    (b) PGPM + identity (small sizes only), APGPM and SSN (the default method) + substructuring
    (c) PETSc SNES vinewtonrsls on the optimality system, with several linear solvers,
        from x = 0 and grid-sequenced (coarser levels first, each solution prolonged)
    (d) PETSc TAO BLMVM, BQNLS (J_h and gradient), BNLS and BNTR (with the Hessian)
    (e) yardstick: one P1 Poisson solve, CG + GAMG to rtol 1e-8

Each size runs in its own worker process (``--worker``); inside it every solver gets
its own window for wall time and peak memory (the Linux high-water mark VmHWM is reset
through /proc/self/clear_refs before each solver). Solutions are compared with PGPM's.

    .venv/bin/python bench/peers.py [--quick] [--json] [--sizes 100,250,500,1000]
                                    [--solvers pgpm,ssn,...] [--out DIR]
                                    [--budget SECONDS] [--report-from FILE]

``--quick`` (sizes 100 and 200, a handful of solvers) prints the table and writes
results only when ``--out`` is given; the full run writes ``bench/results.md``,
``bench/peers.png`` and the raw records ``bench/results.json``, from which
``--report-from`` rewrites the first two without rerunning. Exit code 0, or 1 when a
worker process crashed. Serial: under mpirun it exits with code 2 and a message.
Run times and the measurements behind the tolerances: docs/design/baselines.md.

This file is the runner (worker, driver, entry point); the solver table is in
``peers_solvers.py``, the targets in ``peers_targets.py`` and the report in
``peers_report.py``, next to it.
"""
from __future__ import annotations

import argparse
import ctypes
import gc
import json
import os
import platform
import resource
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any, Callable

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
RECORD = "@@record "

if str(HERE) not in sys.path:  # bench/ is not a package: its siblings by path
    sys.path.insert(0, str(HERE))

from peers_report import plot, print_table, report  # noqa: E402
from peers_solvers import (  # noqa: E402
    BY_NAME,
    DEEP_MIN_DOFS,
    FULL_SIZES,
    NEWTON_TOL,
    PROBLEMS,
    QUICK_SIZES,
    SOLVERS,
    TOL_PHI,
    TOL_U,
    Solver,
)
from peers_targets import targets  # noqa: E402


# ============================================================================ worker
def _status_kb(key: str) -> float:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith(key + ":"):
                return float(line.split()[1])
    raise KeyError(key)


class MemoryWindow:
    """Peak resident memory of a code section: VmHWM after resetting it (Linux >= 4.0)
    to the current RSS; falls back to the process-wide ru_maxrss elsewhere."""

    def __enter__(self) -> "MemoryWindow":
        # hand memory freed by earlier solvers back to the OS first, so that the
        # baseline is the live memory and the increase is this solver's own
        gc.collect()
        try:
            ctypes.CDLL("libc.so.6").malloc_trim(0)
        except (OSError, AttributeError):
            pass
        try:
            with open("/proc/self/clear_refs", "w") as fh:
                fh.write("5")
            self.base = _status_kb("VmRSS") / 1024
            self.exact = True
        except OSError:
            self.base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
            self.exact = False
        return self

    def __exit__(self, *exc) -> None:
        peak = (
            _status_kb("VmHWM")
            if self.exact
            else resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        ) / 1024
        self.peak, self.delta = peak, max(peak - self.base, 0.0)


def _relative(a: np.ndarray, b: np.ndarray) -> float:
    scale = np.linalg.norm(b)
    return float(np.linalg.norm(a - b) / scale) if scale > 0 else float(np.linalg.norm(a))


def _coarser_levels(
    problem, cells: int, hierarchy: str, data: Callable[[Any], dict[str, Any]]
) -> list[Callable[[], Any]]:
    """Builders of the coarser levels of the benchmark's square for a grid-sequenced
    peer, coarsest first, from :func:`coupling.app.from_config.coarser_configs`:
    ``nested`` h doubled with the subdomains d = 4h kept (one coarser level at 2h: the
    peer's fastest hierarchy, 18.4 s at 10^6 against 38.9 s on the 4h levels of
    ``[solver] nested``, docs/design/baselines.md), ``deep`` h doubled down to
    DEEP_MIN_DOFS dofs (on 2 x 2 subdomains); ``data(mesh)`` gives f, t0, u0, a on a level's mesh.
    """
    from coupling.app.config import parse_config
    from coupling.app.from_config import coarser_configs, domain_from_config
    from coupling.manufactured import square_contact
    from coupling.problem import SignoriniProblem

    shape = square_contact()
    h = shape.width / cells
    d = 4 * h if hierarchy == "nested" else shape.width / 2
    config = parse_config(
        {
            "geometry": {
                "shape": shape.shape,
                "h": h,
                "subdomain_size": d,
                "center": list(shape.center),
                "width": shape.width,
                "structured": True,
                "signorini": [[list(a), list(b)] for a, b in shape.signorini],
            }
        }
    )
    dofs = problem.V.dofmap.index_map.size_global
    if hierarchy == "nested":
        levels = coarser_configs(config, dofs, coarsening=2, keep_subdomains=True)
    else:
        levels = coarser_configs(config, dofs, coarsening=2, min_dofs=DEEP_MIN_DOFS)

    def builder(level_config: dict) -> Callable[[], Any]:
        def build():
            domain = domain_from_config(problem.comm, level_config)
            values = data(domain.mesh)
            return SignoriniProblem(
                domain,
                problem.material,
                f=values["f"],
                u0=values["u0"],
                t0=values["t0"],
                a=values["a"],
                boundary_operator=problem.boundary_operator,
            )

        return build

    return [builder(c) for c in levels]


def _run_one(solver: Solver, problem, budget: float, reference, coarser=None) -> Any:
    from coupling import baselines

    if solver.budget is not None:
        budget = min(budget, solver.budget)
    opts = dict(solver.options)
    if solver.kind == "project":
        return baselines.solve_project(problem, opts.pop("method"), budget=budget, **opts)
    if solver.kind == "snes":
        return baselines.solve_snes_vi(problem, rtol=NEWTON_TOL, budget=budget, **opts)
    if solver.kind == "snes-sequenced":
        levels = coarser(opts.pop("hierarchy"))
        return baselines.solve_snes_vi_sequenced(
            problem, levels, rtol=NEWTON_TOL, budget=budget, **opts
        )
    if solver.kind == "tao":
        stop = None
        if opts.pop("oracle", False) and reference is not None:
            u_ref, phi_ref = reference

            def stop(u, phi):  # the accuracy test of the benchmark, as a stopping rule
                return _relative(u, u_ref) <= TOL_U and _relative(phi, phi_ref) <= TOL_PHI

        return baselines.solve_tao(
            problem, opts.pop("kind"), gttol=NEWTON_TOL, budget=budget, stop=stop, **opts
        )
    raise ValueError(f"unknown solver kind {solver.kind!r}")


def _profile_pgpm(problem, u: np.ndarray, phi: np.ndarray, repeat: int = 5) -> dict[str, float]:
    """Wall time of the parts of one PGPM iteration at the state (u, phi) [s]: the best
    of ``repeat`` calls each (the least disturbed by other load), with the B and the
    projection of PGPM's solve (default options, built here)."""
    from dolfinx import fem

    from coupling.options import SolverOptions
    from coupling.preconditioners import build_preconditioner
    from coupling.solvers.solution import build_projection
    from coupling.timing import best_of

    def best(fn) -> float:
        return best_of(fn, repeat)

    options = SolverOptions(flux_space=problem.flux_space, jacobian=problem.jacobian)
    f, pre = problem.functional, build_preconditioner(problem, options)
    projection = build_projection(pre, options)
    u_fun = fem.Function(problem.V)
    u_fun.x.array[:] = u
    grad = problem.forms.create_vector()
    g_u = np.ones(u.size)
    g_phi = np.ones(phi.size)
    parts = {
        "residual assembly DG(u)": best(lambda: problem.forms.assemble_residual(u_fun, grad)),
        "energy assembly G(u)": best(lambda: problem.forms.energy(u_fun)),
        "S_h product (+ trace T u)": best(lambda: f.S @ f.boundary_block(u_fun.vector, phi)),
        "B_Omega^-1 (local solves, edges, coarse)": best(lambda: pre.apply_omega(g_u)),
        "M_s^-1": best(lambda: pre.apply_signorini(g_phi)),
        "projection (exact)": best(lambda: projection(phi - 1e-3 * g_phi, phi)),
    }
    grad.destroy()
    pre.destroy()
    return parts


def worker(spec: dict[str, Any]) -> None:
    """Run the solvers of one mesh size; print one JSON record per solve."""
    from mpi4py import MPI

    from coupling import baselines
    from coupling.manufactured import square_contact
    from coupling.problem import SignoriniProblem
    from fem_py.forms import make_material
    from fem_py.mesh import GeometrySpec, build_domain

    comm = MPI.COMM_WORLD
    cells, budget = int(spec["cells"]), float(spec["budget"])

    def emit(record: dict[str, Any]) -> None:
        print(RECORD + json.dumps(record), flush=True)

    manufactured = square_contact()
    h = manufactured.width / cells
    tic = time.perf_counter()
    domain = build_domain(
        comm,
        GeometrySpec(
            manufactured.shape,
            h=h,
            subdomain_size=4 * h,
            center=manufactured.center,
            width=manufactured.width,
            signorini=manufactured.signorini,
            structured=True,
        ),
    )
    mesh_time = time.perf_counter() - tic
    material = make_material("carstensen")

    base = {"cells": cells}
    for name, solver_names in spec["jobs"].items():
        tic = time.perf_counter()

        def data_on(mesh, name=name):
            if name == "manufactured":
                return manufactured.data(mesh, material)
            return {k: PROBLEMS[name][k] for k in ("f", "t0", "u0", "a")}

        data = data_on(domain.mesh)
        # the shared set-up: forms, S_h, loads (every solver builds its own B); the dense
        # S_h at every size, as the PETSc peers assemble it into their Hessian
        problem = SignoriniProblem(
            domain,
            material,
            f=data["f"],
            u0=data["u0"],
            t0=data["t0"],
            a=data["a"],
            boundary_operator="dense",
        )
        shared = time.perf_counter() - tic
        info = {
            **base,
            "problem": name,
            "dofs": problem.V.dofmap.index_map.size_global,
            "n_gamma": problem.boundary.n_gamma,
            "n_signorini": problem.n_signorini,
        }
        emit(
            {
                **info,
                "type": "setup",
                "mesh": mesh_time,
                "shared": shared,
                "timings": dict(problem.timings),
            }
        )
        reference = None

        def coarser(hierarchy: str, data_on=data_on) -> list[Callable[[], Any]]:
            return _coarser_levels(problem, cells, hierarchy, data_on)

        for solver in (BY_NAME[n] for n in solver_names):
            record = {**info, "type": "solve", "solver": solver.name}
            try:
                with MemoryWindow() as memory:
                    result = _run_one(solver, problem, budget, reference, coarser)
            except Exception as err:  # reported, never dropped
                emit(
                    {
                        **record,
                        "converged": False,
                        "status": "error",
                        "reason": f"{type(err).__name__}: {err}",
                    }
                )
                continue
            record.update(
                converged=bool(result.converged),
                reason=result.reason,
                iterations=result.iterations,
                linear_iterations=result.linear_iterations,
                evaluations=result.evaluations,
                setup=result.setup,
                solve=result.solve,
                total=result.setup + result.solve,
                peak_mb=memory.peak,
                delta_mb=memory.delta,
                exact_memory=memory.exact,
                details=result.details,
            )
            if solver.name == "ssn" and reference is None and result.converged:
                # PGPM skipped on this mesh: the default method is the reference
                reference, record["reference"] = (result.u, result.phi), True
            if solver.name == "pgpm":
                reference = (result.u, result.phi)
                if spec.get("profile"):
                    parts = _profile_pgpm(problem, result.u, result.phi)
                    record["profile"] = {
                        **parts,
                        "one PGPM iteration (measured)": result.solve / max(result.iterations, 1),
                    }
            if reference is not None:
                record["du"] = _relative(result.u, reference[0])
                record["dphi"] = _relative(result.phi, reference[1])
            emit(record)
    if spec["poisson"]:
        record = {
            **base,
            "type": "solve",
            "problem": "poisson",
            "solver": "poisson",
            "dofs": domain.mesh.topology.index_map(0).size_global,
        }
        from fem_py.boundary import BoundaryMap
        from fem_py.dofs import p1_space

        V = p1_space(domain.mesh)
        boundary = BoundaryMap(V, domain)
        with MemoryWindow() as memory:
            result = baselines.poisson_yardstick(V, boundary.dofs)
        record.update(
            converged=bool(result.converged),
            reason=result.reason,
            iterations=result.iterations,
            linear_iterations=result.linear_iterations,
            setup=result.setup,
            solve=result.solve,
            total=result.setup + result.solve,
            peak_mb=memory.peak,
            delta_mb=memory.delta,
            exact_memory=memory.exact,
            dofs=V.dofmap.index_map.size_global,
        )
        emit(record)


# ============================================================================ driver
def _status(record: dict[str, Any]) -> str:
    if record.get("status"):
        return record["status"]
    if record.get("converged"):
        agrees = record.get("du", 0.0) <= TOL_U and record.get("dphi", 0.0) <= TOL_PHI
        return "ok" if agrees else "inaccurate"
    return "budget" if "budget" in str(record.get("reason", "")) else "failed"


def _run_worker(
    spec: dict[str, Any], timeout: float, log: Callable[[str], None]
) -> list[dict[str, Any]]:
    """Run one worker process; return its records (plus an error record on a crash)."""
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", json.dumps(spec)]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True, cwd=ROOT, env=env)
    timer = threading.Timer(timeout, proc.kill)
    timer.start()
    records = []
    try:
        for line in proc.stdout:
            if not line.startswith(RECORD):
                continue
            record = json.loads(line[len(RECORD) :])
            if record["type"] == "solve":
                record["status"] = _status(record)
                log(
                    f"  N = {record['dofs']:>8d}  {record['problem']:12s} {record['solver']:22s} "
                    f"{record.get('total', 0.0):8.2f} s  {record['status']}"
                )
            records.append(record)
    finally:
        proc.wait()
        timer.cancel()
    if proc.returncode != 0:
        records.append(
            {
                "type": "crash",
                "cells": spec["cells"],
                "reason": f"worker exited with code {proc.returncode}"
                + (" (killed after the time limit)" if proc.returncode < 0 else ""),
            }
        )
    return records


def _plan(args) -> tuple[tuple[int, ...], list[Solver]]:
    sizes = (
        tuple(int(s) for s in args.sizes.split(","))
        if args.sizes
        else (QUICK_SIZES if args.quick else FULL_SIZES)
    )
    solvers = [s for s in SOLVERS if s.quick] if args.quick else list(SOLVERS)
    if args.solvers:  # the accuracy reference: PGPM, or SSN where PGPM is not run
        chosen = set(args.solvers.split(","))
        solvers = [s for s in SOLVERS if s.name in chosen]
    return tuple(sorted(set(sizes))), solvers


def run(args: argparse.Namespace, log: Callable[[str], None]) -> dict[str, Any]:
    """Run the sizes one worker process each, smallest first. A solver that failed (or
    ran out of budget) on one mesh is not run on finer ones, nor one whose time on the
    previous mesh, scaled linearly with N (no solver here does better), exceeds its
    budget; both appear as ``skipped`` records with the reason."""
    sizes, solvers = _plan(args)
    budget = args.budget if args.budget else (60.0 if args.quick else 300.0)
    records: list[dict[str, Any]] = []
    skip: dict[tuple[str, str], str] = {}  # (problem, solver) -> why it is not run
    start = time.perf_counter()
    machine = machine_info()
    for i, cells in enumerate(sizes):
        jobs: dict[str, list[str]] = {p: [] for p in PROBLEMS}
        for solver in solvers:
            if solver.kind == "poisson" or (solver.max_cells and cells > solver.max_cells):
                continue
            for p in solver.problems:
                if (p, solver.name) in skip:
                    records.append(
                        {
                            "type": "solve",
                            "cells": cells,
                            "problem": p,
                            "solver": solver.name,
                            "converged": False,
                            "status": "skipped",
                            "reason": skip[p, solver.name],
                        }
                    )
                else:
                    jobs[p].append(solver.name)
        spec = {
            "cells": cells,
            "budget": budget,
            "profile": cells == sizes[-1],
            "poisson": any(s.kind == "poisson" for s in solvers),
            "jobs": {p: names for p, names in jobs.items() if names},
        }
        count = sum(len(n) for n in spec["jobs"].values())
        log(f"cells = {cells}: {count} solves, budget {budget:g} s each")
        timeout = 1200 + 2 * budget * count
        new = _run_worker(spec, timeout, log)
        records.extend(new)
        next_cells = sizes[i + 1] if i + 1 < len(sizes) else None
        for r in new:
            if r["type"] != "solve" or r["solver"] == "poisson":
                continue
            key = (r["problem"], r["solver"])
            cap = min(budget, BY_NAME[r["solver"]].budget or budget)
            if r["status"] in ("budget", "failed", "error"):
                skip[key] = f"{r['status']} at N = {r['dofs']}"
            elif next_cells and r.get("total"):
                predicted = r["total"] * (next_cells + 1) ** 2 / r["dofs"]
                if predicted > cap:
                    skip[key] = (
                        f"{r['total']:.0f} s at N = {r['dofs']}, so over the "
                        f"{cap:g} s budget here even with linear scaling"
                    )
    return {
        "machine": machine,
        "records": records,
        "sizes": list(sizes),
        "budget": budget,
        "quick": bool(args.quick),
        "solvers": args.solvers,
        "wall_time": time.perf_counter() - start,
        "tol_u": TOL_U,
        "tol_phi": TOL_PHI,
        "targets": targets(records),
    }


def machine_info() -> dict[str, Any]:
    cpu = "unknown"
    try:
        with open("/proc/cpuinfo") as fh:
            cpu = next(
                line.split(":", 1)[1].strip() for line in fh if line.startswith("model name")
            )
    except (OSError, StopIteration):
        pass
    versions: dict[str, str] = {"python": platform.python_version()}
    try:
        import petsc4py
        from petsc4py import PETSc

        versions["petsc4py"] = petsc4py.__version__
        versions["PETSc"] = ".".join(map(str, PETSc.Sys.getVersion()))
    except ImportError:
        pass
    for module in ("dolfinx", "numpy", "scipy"):
        try:
            versions[module] = __import__(module).__version__
        except ImportError:
            pass
    commit = "unknown"
    try:
        commit = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"],
            capture_output=True,
            text=True,
            cwd=ROOT,
            check=True,
        ).stdout.strip()
        # modified or untracked sources (this benchmark itself may be untracked)
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--", "*.py", "*.cpp", "*.hpp"],
            capture_output=True,
            text=True,
            cwd=ROOT,
        ).stdout.strip()
        commit += " (with uncommitted changes)" if dirty else ""
    except (OSError, subprocess.CalledProcessError):
        pass
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "load": os.getloadavg()[0],
        "platform": platform.platform(),
        "versions": versions,
        "commit": commit,
        "threads": "OMP_NUM_THREADS=1, OPENBLAS_NUM_THREADS=1",
        "date": time.strftime("%Y-%m-%d %H:%M"),
    }


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``fembem bench`` and ``make bench`` (see the module docstring)."""
    parser = argparse.ArgumentParser(prog="fembem bench", description=__doc__.splitlines()[0])
    parser.add_argument(
        "--quick",
        action="store_true",
        help="sizes 100 and 200 cells per side, a handful of solvers (< 2 min)",
    )
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    parser.add_argument("--sizes", help="comma-separated cells per side, e.g. 100,250,500,1000")
    parser.add_argument(
        "--solvers",
        help="comma-separated solver names to run (the accuracy reference is PGPM, or SSN "
        "where PGPM does not run); "
        "default all (--quick: its handful)",
    )
    parser.add_argument(
        "--out",
        help="directory for results.md, peers.png and the raw "
        "results.json (default: bench/ for the full run, none "
        "for --quick)",
    )
    parser.add_argument(
        "--budget",
        type=float,
        help="wall-time budget per solve in seconds (default 300, --quick 60)",
    )
    parser.add_argument(
        "--report-from",
        metavar="FILE",
        help="rewrite results.md and peers.png from the output of an earlier "
        "--json run instead of running",
    )
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)

    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    if comm.size > 1:
        if comm.rank == 0:
            print(
                "fembem bench: the peer benchmark is serial (each solver in one process, "
                "PETSc peers on PETSC_COMM_SELF); run it without mpirun",
                file=sys.stderr,
            )
        return 2
    if args.worker:
        worker(json.loads(args.worker))
        return 0
    if args.sizes:
        try:
            sizes = [int(s) for s in args.sizes.split(",")]
        except ValueError:
            parser.error(f"--sizes must be comma-separated integers, got {args.sizes!r}")
        if any(s < 8 for s in sizes):
            parser.error("--sizes: at least 8 cells per side (subdomains of 4 cells)")
    if args.solvers:
        unknown = sorted(set(args.solvers.split(",")) - set(BY_NAME))
        if unknown:
            parser.error(f"--solvers: unknown {', '.join(unknown)}; known: {', '.join(BY_NAME)}")
    if args.budget is not None and not args.budget > 0:
        parser.error("--budget must be positive")

    def log(message: str) -> None:
        print(message, file=sys.stderr, flush=True)

    if args.report_from:
        result = json.loads(Path(args.report_from).read_text())
        result["regenerated"] = time.strftime("%Y-%m-%d %H:%M")
        args.quick = result["quick"]
        default = QUICK_SIZES if args.quick else FULL_SIZES
        args.sizes = (
            None if result["sizes"] == list(default) else ",".join(map(str, result["sizes"]))
        )
        args.solvers = result.get("solvers")
        result["targets"] = targets(result["records"])
    else:
        result = run(args, log)
    out = Path(args.out) if args.out else (None if args.quick else HERE)
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        command = (
            "fembem bench"
            + (" --quick" if args.quick else "")
            + (f" --sizes {args.sizes}" if args.sizes else "")
            + (f" --solvers {args.solvers}" if getattr(args, "solvers", None) else "")
        )
        (out / "results.md").write_text(report(result, command))
        if not args.report_from:  # the raw records, for --report-from
            (out / "results.json").write_text(json.dumps(result, indent=1) + "\n")
        plot(result, out / "peers.png")
        log(f"wrote {out / 'results.md'} and {out / 'peers.png'}")
    if args.json:
        print(json.dumps(result, indent=1))
    else:
        print_table(result)
    return 1 if any(r["type"] == "crash" for r in result["records"]) else 0


if __name__ == "__main__":
    sys.exit(main())
