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
    (c) PETSc SNES vinewtonrsls on the optimality system, with several linear solvers
    (d) PETSc TAO BLMVM, BQNLS (J_h and gradient), BNLS and BNTR (with the Hessian)
    (e) yardstick: one P1 Poisson solve, CG + GAMG to rtol 1e-8

Each size runs in its own worker process (``--worker``); inside it every solver gets
its own window for wall time and peak memory (the Linux high-water mark VmHWM is reset
through /proc/self/clear_refs before each solver). Solutions are compared with PGPM's.

    .venv/bin/python bench/peers.py [--quick] [--json] [--sizes 100,250,500,1000]
                                    [--out DIR] [--budget SECONDS] [--report-from FILE]

``--quick`` (sizes 100 and 200, a handful of solvers) prints the table and writes
results only when ``--out`` is given; the full run writes ``bench/results.md``,
``bench/peers.png`` and the raw records ``bench/results.json``, from which
``--report-from`` rewrites the first two without rerunning. Exit code 0, or 1 when a
worker process crashed. Serial: under mpirun it exits with code 2 and a message.
Run times and the measurements behind the tolerances: docs/design/baselines.md.
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
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
RECORD = "@@record "

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
    """One benchmarked solver: ``kind`` selects the ``coupling.baselines`` entry point."""

    name: str
    label: str
    group: str
    kind: str  # "project", "snes", "tao", "poisson"
    options: dict = field(default_factory=dict)
    max_cells: int | None = None  # not run on finer meshes
    budget: float | None = None  # cap on the per-solve budget
    selection: bool = False  # part of the SNES VI linear-solver selection
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
FULL_SIZES = (100, 250, 500, 1000)
QUICK_SIZES = (100, 200)
#: SNES rtol and TAO gttol of the Newton-type peers: Newton converges quadratically,
#: so the last step lands far below them (docs/design/baselines.md).
NEWTON_TOL = 1e-10


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


def _run_one(solver: Solver, problem, budget: float, reference) -> Any:
    from coupling import baselines

    if solver.budget is not None:
        budget = min(budget, solver.budget)
    opts = dict(solver.options)
    if solver.kind == "project":
        return baselines.solve_project(problem, opts.pop("method"), budget=budget, **opts)
    if solver.kind == "snes":
        return baselines.solve_snes_vi(problem, rtol=NEWTON_TOL, budget=budget, **opts)
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
    from fem_py.geometry import build_domain
    from fem_py.materials import make_material

    comm = MPI.COMM_WORLD
    cells, budget = int(spec["cells"]), float(spec["budget"])

    def emit(record: dict[str, Any]) -> None:
        print(RECORD + json.dumps(record), flush=True)

    manufactured = square_contact()
    h = manufactured.width / cells
    tic = time.perf_counter()
    domain = build_domain(
        comm,
        manufactured.shape,
        h=h,
        subdomain_size=4 * h,
        center=manufactured.center,
        width=manufactured.width,
        signorini=manufactured.signorini,
        structured=True,
    )
    mesh_time = time.perf_counter() - tic
    material = make_material("carstensen")

    base = {"cells": cells}
    for name, solver_names in spec["jobs"].items():
        tic = time.perf_counter()
        if name == "manufactured":
            data = manufactured.data(domain.mesh, material)
        else:
            data = {k: PROBLEMS[name][k] for k in ("f", "t0", "u0", "a")}
        # the shared set-up: forms, S_h, loads (every solver builds its own B)
        problem = SignoriniProblem(
            domain, material, f=data["f"], u0=data["u0"], t0=data["t0"], a=data["a"]
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
        for solver in (BY_NAME[n] for n in solver_names):
            record = {**info, "type": "solve", "solver": solver.name}
            try:
                with MemoryWindow() as memory:
                    result = _run_one(solver, problem, budget, reference)
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
        from fem_py.forms import p1_space

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


def _index(records):
    """{(problem, cells, solver): record} of the solve records and the Poisson times by cells."""
    table = {(r["problem"], r["cells"], r["solver"]): r for r in records if r["type"] == "solve"}
    poisson = {r["cells"]: r for r in records if r["type"] == "solve" and r["solver"] == "poisson"}
    return table, poisson


#: Relative difference of two wall times below which the benchmark calls them a tie
#: (the spread of repeat runs on a shared machine: docs/design/baselines.md).
TIE = 0.10


def targets(records: list[dict[str, Any]]) -> dict[str, Any]:
    """Target 1: the method (set-up + solve) faster than every PETSc peer (c, d) at
    N >= 2.5e5, a peer without a converged solve within its budget counting as slower;
    target 2: within 10x of the Poisson yardstick (e), at every size. Evaluated for (a)
    PGPM (the targets) and, for comparison, for the project's APGPM and SSN."""
    table, poisson = _index(records)
    out: dict[str, Any] = {}
    for method in ("pgpm", "apgpm", "ssn"):
        faster, within = [], []
        for (problem, cells, name), r in sorted(table.items()):
            if name != method or r["status"] != "ok":
                continue
            t_a = r["total"]
            if r["dofs"] >= 2.5e5:
                peers = [
                    (n2, q["total"])
                    for (p2, c2, n2), q in table.items()
                    if (p2, c2) == (problem, cells)
                    and BY_NAME[n2].group in ("c", "d")
                    and q["status"] == "ok"
                ]
                best = min(peers, key=lambda nt: nt[1], default=None)
                slower = [f"{n2} ({t:.1f} s)" for n2, t in peers if t <= t_a]
                faster.append(
                    {
                        "problem": problem,
                        "dofs": r["dofs"],
                        "time": t_a,
                        "met": not slower,
                        "faster_peers": slower,
                        "best_peer": best,
                        "tie": best is not None and abs(best[1] - t_a) <= TIE * t_a,
                    }
                )
            if cells in poisson and poisson[cells].get("converged"):
                ratio = t_a / poisson[cells]["total"]
                within.append(
                    {"problem": problem, "dofs": r["dofs"], "ratio": ratio, "met": ratio <= 10.0}
                )
        out[method] = {"faster_than_peers": faster, "within_10x_poisson": within}
    return out


# ============================================================================ report
def _fmt(value, spec: str = ".2f", missing: str = "-") -> str:
    return missing if value is None else format(value, spec)


def markdown_table(
    result: dict[str, Any], problem: str, names: Sequence[str] | None = None
) -> list[str]:
    table, poisson = _index(result["records"])
    lines = [
        "| N | solver | status | its | lin. its | setup [s] | solve [s] | total [s] "
        "| / (a) | / (e) | peak [MB] | +peak [MB] | du | dphi |",
        "|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for cells in result["sizes"]:
        a = table.get((problem, cells, "pgpm"))
        e = poisson.get(cells)
        for solver in SOLVERS:
            if names is not None and solver.name not in names:
                continue
            key = ("poisson" if solver.kind == "poisson" else problem, cells, solver.name)
            r = table.get(key)
            if r is None:
                continue
            total = r.get("total")
            ratio_a = total / a["total"] if total and a and a.get("total") else None
            ratio_e = total / e["total"] if total and e and e.get("total") else None
            dofs = r.get("dofs") or (a or {}).get("dofs")
            status = (
                r["status"]
                if r["status"] in ("ok", "inaccurate")
                else (f"{r['status']}: {r.get('reason', '')}")
            )
            its = r.get("iterations")
            lines.append(
                f"| {_fmt(dofs, 'd')} | {solver.group}: {solver.label} | {status} "
                f"| {_fmt(its if its is not None and its >= 0 else None, 'd')} "
                f"| {_fmt(r.get('linear_iterations') or None, 'd')} "
                f"| {_fmt(r.get('setup'))} | {_fmt(r.get('solve'))} | {_fmt(total)} "
                f"| {_fmt(ratio_a)} | {_fmt(ratio_e, '.1f')} | {_fmt(r.get('peak_mb'), '.0f')} "
                f"| {_fmt(r.get('delta_mb'), '.0f')} | {_fmt(r.get('du'), '.1e')} "
                f"| {_fmt(r.get('dphi'), '.1e')} |"
            )
    return lines


#: The solvers of the main tables and the plot: all but the SNES VI linear-solver
#: candidates that were not kept.
MAIN = tuple(
    s.name
    for s in SOLVERS
    if not s.selection or s.name in ("snes-substructuring", "snes-mumps-cholesky")
)


def plot(result: dict[str, Any], path: Path) -> None:
    """Set-up + solve time against N, log-log, one panel per problem (failed solves as x)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    table, _ = _index(result["records"])
    problems = [p for p in PROBLEMS if any(k[0] == p for k in table)]
    fig, axes = plt.subplots(1, len(problems), figsize=(6.5 * len(problems), 5), squeeze=False)
    markers = dict(a="o", b="s", c="^", d="v", e="D")
    handles = {}
    for ax, problem in zip(axes[0], problems):
        for i, solver in enumerate(s for s in SOLVERS if s.name in MAIN):
            rows = [
                table.get(("poisson" if solver.kind == "poisson" else problem, c, solver.name))
                for c in result["sizes"]
            ]
            rows = [r for r in rows if r and r.get("total")]
            if not rows:
                continue
            color = "black" if solver.kind == "poisson" else plt.cm.tab10(i % 10)
            style = dict(
                marker=markers[solver.group],
                color=color,
                linestyle="--" if solver.kind == "poisson" else "-",
                linewidth=2.5 if solver.name == "pgpm" else 1.2,
            )
            ok = [r for r in rows if r["status"] == "ok"]
            if ok:
                ax.loglog([r["dofs"] for r in ok], [r["total"] for r in ok], **style)
            bad = [r for r in rows if r["status"] != "ok"]
            if bad:
                ax.loglog(
                    [r["dofs"] for r in bad],
                    [r["total"] for r in bad],
                    "x",
                    color=style["color"],
                    markersize=10,
                    markeredgewidth=2,
                )
            handles.setdefault(
                solver.name, Line2D([], [], label=f"{solver.group}: {solver.label}", **style)
            )
        ax.set_xlabel("N (dofs of u)")
        ax.set_ylabel("set-up + solve [s]")
        ax.set_title(PROBLEMS[problem]["label"])
        ax.grid(True, which="both", alpha=0.3)
    fig.legend(handles=list(handles.values()), fontsize=8, loc="center right")
    fig.suptitle("Peer benchmark: wall time vs N (x: not converged within the budget or failed)")
    fig.tight_layout(rect=(0, 0, 0.8, 1))
    fig.savefig(path, dpi=120)
    plt.close(fig)


def report(result: dict[str, Any], command: str) -> str:
    m = result["machine"]
    v = m["versions"]
    table, poisson = _index(result["records"])
    setups = {(r["problem"], r["cells"]): r for r in result["records"] if r["type"] == "setup"}
    out = [
        "# Peer benchmark: PGPM against PETSc's VI and bound-constrained solvers",
        "",
        f"Generated by `{command}` on {m['date']} in {result['wall_time'] / 60:.1f} min "
        "(do not edit by hand; rerun to update"
        + (
            f"; text and tables rewritten on {result['regenerated']} from this run's "
            "records, `bench/peers.py --report-from bench/results.json`"
            if result.get("regenerated")
            else ""
        )
        + ").",
        "",
        f"- Machine: {m['cpu']}, {m['cores']} cores (shared with other jobs; load average "
        f"{m['load']:.1f} at the start), {m['platform']}; one process, {m['threads']}.",
        f"- Versions: petsc4py {v.get('petsc4py')} (PETSc {v.get('PETSc')}), dolfinx "
        f"{v.get('dolfinx')}, numpy {v.get('numpy')}, scipy {v.get('scipy')}, python "
        f"{v.get('python')}; git commit {m['commit']}.",
        f"- Budget per solve: {result['budget']:g} s (120 s for BLMVM and BQNLS, 60 s for PGPM "
        "+ identity), checked at every evaluation of J_h or its derivatives. A solver that "
        "fails or runs out of budget is reported with its reason and not run on finer "
        "meshes; nor is one whose time on the previous mesh, scaled linearly with N (no "
        "solver here scales better), exceeds its budget (status `skipped`, with the reason).",
        "",
        "## What is measured",
        "",
        "The same discrete problem (2.3) - minimise J_h(u, phi) over phi >= 0 - on the square "
        "[-1/4, 1/4]^2 (structured mesh, `cells` squares per side, each split in two; "
        "subdomains of d = 4h; Signorini arc = bottom side; carstensen material rho(t) = "
        "2 + 1/(1+t)), for two data sets: `manufactured` (`square_contact`, exact solution "
        "known) and `load` (f = 2, t0 = -1, u0 = 0.1 x, a = 0; no exact solution, contact on "
        "most of the arc). All solvers start from x = 0.",
        "",
        "- (a) PGPM + substructuring preconditioner, the paper's method with the "
        "project's default options (tol = 1e-8 on ||xi_k+1 - xi_k||_B / ||xi_k+1||_B, exact "
        "projection, tau = 1/C0 from 20 Lanczos steps).",
        "- (b) PGPM + identity (Euclidean metric; smallest mesh and manufactured data "
        "only: its count grows like h^-2, Remark 2.1), APGPM and SSN with the "
        "substructuring preconditioner, same tol.",
        "- (c) PETSc SNES `vinewtonrsls` (reduced-space active-set Newton, `bt` line search "
        "on ||F||) on F = grad J_h with phi >= 0, Jacobian = the Hessian "
        "[[D^2G + T^T S T, T^T S E], [E^T S T, E^T S E]] assembled as one SeqAIJ matrix "
        "(the P1 pattern plus the dense boundary/Signorini block, pattern built once, "
        f"values refreshed in place). snes_rtol = {NEWTON_TOL:g}. Linear solvers: see the "
        "selection below; the CG-based ones stop at rtol 1e-6 (fastest of 1e-8, 1e-6, 1e-4 "
        "and Eisenstat-Walker, measured on SNES VI + CG/B at N = 6.2e4).",
        "- (d) PETSc TAO: `blmvm` and `bqnls` (J_h and gradient only) and `bnls`, `bntr` "
        f"(Hessian as in (c), STCG with a MUMPS Cholesky factor). gttol = {NEWTON_TOL:g} "
        "for BNLS/BNTR.",
        "- (e) yardstick: one linear solve on the same mesh, -Laplace w = 1 with w = 0 on "
        "Gamma, P1 stiffness, CG + GAMG to rtol 1e-8 (set-up = assembly + GAMG set-up).",
        "",
        f"Same accuracy: every solution is compared with PGPM's, du = ||u - u_a|| / ||u_a|| "
        f"and dphi = ||phi - phi_a|| / ||phi_a|| (Euclidean norms of the nodal vectors); "
        f"status `ok` means converged by the solver's own test and du <= {TOL_U:g}, "
        f"dphi <= {TOL_PHI:g}. PGPM's own error is what the Newton solvers (converged to "
        "round-off) show as du, dphi: about 1e-8 in u and 1e-6 in phi, so phi sets the "
        "tolerance. BLMVM and BQNLS cannot reach it by their own gradient test (they stall "
        "near 1e-6 in u, the objective's round-off level for their line search); they are "
        "stopped as soon as their iterate passes this accuracy test against PGPM's "
        "solution (an oracle: the most favourable stopping rule they could have).",
        "",
        "Times are wall-clock seconds: `setup` is the solver's own set-up (for (a)-(b) "
        "building B and the step estimate; for (c)-(d) the Hessian pattern and, for CG + "
        "substructuring, building B; PETSc's factorisations happen inside `solve`), `solve` "
        "the iteration, `total` = setup + solve. Not included, because all solvers share "
        "it: mesh, forms, S_h and loads (listed below). `/ (a)` and `/ (e)` are ratios of "
        "`total` to PGPM's and to the Poisson solve's, measured in the same run. `peak` is "
        "the process's peak resident memory during the solve (it includes the mesh and "
        "S_h), `+peak` its increase over the resident memory before the solver started "
        "(Linux VmHWM reset by /proc/self/clear_refs). `its` = outer iterations (PGPM "
        "steps, Newton steps, TAO iterations), `lin. its` = Krylov iterations summed.",
        "",
    ]
    # shared set-up
    out += [
        "### Shared set-up (not in the solver times)",
        "",
        "| N | problem | mesh [s] | forms + S_h + loads [s] | S_h [s] | n_Gamma | n_s |",
        "|---:|---|---:|---:|---:|---:|---:|",
    ]
    for (problem, cells), s in sorted(setups.items(), key=lambda kv: (kv[0][1], kv[0][0])):
        out.append(
            f"| {s['dofs']} | {problem} | {s['mesh']:.1f} | {s['shared']:.1f} "
            f"| {s['timings'].get('steklov_poincare', 0.0):.1f} | {s['n_gamma']} "
            f"| {s['n_signorini']} |"
        )
    out.append("")
    # linear solver selection
    selection = [s.name for s in SOLVERS if s.selection]
    out += [
        "## Linear solver for SNES VI",
        "",
        "All candidates on the manufactured problem up to N = 6.2e4 (PETSc's LU only at "
        "1e4); the finer meshes run the two kept for the main tables:",
        "",
    ]
    out += markdown_table(result, "manufactured", names=selection)
    out += ["", *_selection_text(result), ""]
    # main tables
    main = MAIN
    for problem in PROBLEMS:
        if not any(k[0] == problem for k in table):
            continue
        out += [f"## Results: {PROBLEMS[problem]['label']}", ""]
        out += markdown_table(result, problem, names=main)
        out.append("")
    out += ["![time vs N](peers.png)", "", "## Targets", ""]
    out += _targets_text(result)
    out += ["", *_profile_text(result), "", *_discussion(result)]
    crashes = [r for r in result["records"] if r["type"] == "crash"]
    if crashes:
        out += ["", "## Worker failures", ""]
        out += [f"- cells = {r['cells']}: {r['reason']}" for r in crashes]
    return "\n".join(out) + "\n"


def _selection_text(result) -> list[str]:
    table, _ = _index(result["records"])
    lines = []
    for cells in result["sizes"]:
        rows = [
            (n, table[("manufactured", cells, n)])
            for n in (s.name for s in SOLVERS if s.selection)
            if ("manufactured", cells, n) in table
        ]
        ok = sorted((r["total"], n) for n, r in rows if r["status"] == "ok")
        if len(rows) > 2 and ok:
            order = ", ".join(f"{BY_NAME[n].label.split(', ', 1)[1]} {t:.2f} s" for t, n in ok)
            lines.append(f"- N = {rows[0][1]['dofs']}: {order}.")

    def pick(name):
        return [
            table[k]
            for k in sorted(table, key=lambda k: k[1])
            if k[0] == "manufactured" and k[2] == name and table[k]["status"] == "ok"
        ]

    def per_step(rows):
        return ", ".join(f"{r['linear_iterations'] / max(r['iterations'], 1):.0f}" for r in rows)

    def speed(slow, fast):
        pairs = [
            (a["total"] / b["total"])
            for a in pick(slow)
            for b in pick(fast)
            if a["cells"] == b["cells"]
        ]
        if not pairs:
            return "-"
        lo, hi = f"{min(pairs):.1f}", f"{max(pairs):.1f}"
        return f"{lo}x" if lo == hi else f"{lo}-{hi}x"

    sub, amg, gamg = pick("snes-substructuring"), pick("snes-hypre"), pick("snes-gamg")
    lines += [
        "",
        "Choice: CG preconditioned by the project's substructuring preconditioner B "
        "restricted to the inactive set (PCSHELL: B_Omega^-1 on u, (omega M_s)[I, I]^-1 on "
        "the free phi; the inactive set from `SNES.getVIInactiveSet()` in the PC set-up) "
        "is the fastest wherever all candidates ran. Its CG count per Newton step stays "
        f"nearly constant as h -> 0 ({per_step(sub)} for N = "
        + ", ".join(str(r["dofs"]) for r in sub)
        + "; at fixed d/h, B is spectrally equivalent to "
        "the Hessian uniformly in h, Theorem 4.1) and it never factors "
        "the dense block. MUMPS is the best black-box choice and is kept as the second "
        "SNES peer: Cholesky is "
        f"{speed('snes-mumps', 'snes-mumps-cholesky')} faster than LU, and the AMD "
        "ordering (ICNTL(7) = 0) "
        f"{speed('snes-mumps-cholesky-auto', 'snes-mumps-cholesky')} faster than this "
        "build's default (PORD; METIS and SCOTCH are absent); the factor still pays for "
        "the dense n_Gamma x n_Gamma block at every Newton step. BoomerAMG needs "
        f"{per_step(amg)} CG iterations per Newton step and GAMG {per_step(gamg)}, but "
        "both are slower overall than CG + B ("
        f"{speed('snes-hypre', 'snes-substructuring')} and "
        f"{speed('snes-gamg', 'snes-substructuring')}): the AMG hierarchy is rebuilt for "
        "every reduced Newton system, on a matrix with n_Gamma-long dense rows (GAMG must "
        "be rebuilt: PETSc 3.18's GAMG cannot be set up again when SNES VI changes the size "
        "of the reduced system). PETSc's own LU "
        "(nested dissection) is "
        f"{speed('snes-petsc-lu', 'snes-mumps')} slower than MUMPS LU.",
    ]
    return lines


def _targets_text(result) -> list[str]:
    t = result["targets"]
    lines = []
    rows = t["pgpm"]["faster_than_peers"]
    if rows:
        met = all(r["met"] for r in rows)
        lines.append(
            f"1. (a) faster than every PETSc peer (c, d) at N >= 2.5e5: "
            f"**{'met' if met else 'not met'}**."
        )
        for r in rows:
            if r["met"]:
                detail = "faster than all"
            else:
                detail = "slower than " + ", ".join(r["faster_peers"])
            if r["tie"]:
                detail += (
                    f" (the fastest peer, {r['best_peer'][0]}, within {100 * TIE:.0f}%: "
                    "a tie on this shared machine)"
                )
            lines.append(f"   - {r['problem']}, N = {r['dofs']}: PGPM {r['time']:.1f} s, {detail}.")
    else:
        lines.append(
            "1. (a) faster than every peer at N >= 2.5e5: not measured (no size "
            ">= 2.5e5 in this run)."
        )
    rows = t["pgpm"]["within_10x_poisson"]
    if rows:
        met = all(r["met"] for r in rows)
        lines.append(
            f"2. (a) within 10x of the Poisson solve (e): **{'met' if met else 'not met'}** "
            "(ratios "
            + ", ".join(f"{r['problem']} N={r['dofs']}: {r['ratio']:.1f}" for r in rows)
            + ")."
        )
    for method, label in (("apgpm", "APGPM"), ("ssn", "SSN")):
        other = t.get(method)
        if not other:
            continue
        fast, within = other["faster_than_peers"], other["within_10x_poisson"]
        parts = []
        if fast:
            parts.append(
                "faster than every PETSc peer at N >= 2.5e5 in "
                f"{sum(r['met'] for r in fast)} of {len(fast)} cases"
            )
        if within:
            big = [r for r in within if r["dofs"] >= 2.5e5]
            parts.append(
                "within 10x of the Poisson solve in "
                f"{sum(r['met'] for r in within)} of {len(within)} cases (ratio "
                f"{min(r['ratio'] for r in within):.1f}-{max(r['ratio'] for r in within):.1f}"
                + (f"; {max(r['ratio'] for r in big):.1f} at most for N >= 2.5e5" if big else "")
                + ")"
            )
        if parts:
            lines.append(
                f"- For comparison, the project's {label} (b) with the same "
                f"preconditioner: {'; '.join(parts)}."
            )
    return lines


#: Profile entries that are not parts of a PGPM iteration: the measured total, and the
#: B_Omega product of earlier runs (PGPM carries B_Omega u along without a product).
_NOT_IN_ITERATION = ("one PGPM iteration (measured)", "B_Omega u (norm of the step)")


def _profile_text(result) -> list[str]:
    profiled = [r for r in result["records"] if r.get("profile")]
    if not profiled:
        return []
    lines = ["## Where the time goes", ""]
    for r in profiled:
        prof = r["profile"]
        unit = prof["residual assembly DG(u)"]
        lines += [
            f"PGPM, {r['problem']}, N = {r['dofs']}: {r['iterations']} iterations, "
            f"{1e3 * prof['one PGPM iteration (measured)']:.1f} ms each (best of 5 per "
            "part, at the final iterate):",
            "",
            "| part | ms | / residual assembly |",
            "|---|---:|---:|",
        ]
        for name, t in prof.items():
            if name not in _NOT_IN_ITERATION[1:]:
                lines.append(f"| {name} | {1e3 * t:.2f} | {t / unit:.2f} |")
        lines.append("")
    table, poisson = _index(result["records"])
    for r in profiled:
        snes = table.get((r["problem"], r["cells"], "snes-substructuring"))
        if snes and snes.get("details") and snes["status"] == "ok":
            d = snes["details"]
            rest = (
                snes["solve"]
                - d["time_function"]
                - d["time_jacobian"]
                - d["time_pc_apply"]
                - d["time_pc_setup"]
            )
            lines.append(
                f"SNES VI + CG/B, {r['problem']}, N = {r['dofs']}: {snes['iterations']} Newton "
                f"steps, {snes['linear_iterations']} CG iterations; of {snes['solve']:.1f} s: "
                f"residuals {d['time_function']:.1f} s, Hessian assembly "
                f"{d['time_jacobian']:.1f} s, B^-1 applications {d['time_pc_apply']:.1f} s "
                f"({d['pc_applications']}), PETSc itself (submatrix of the inactive set, "
                f"Hessian products, vector work) {rest:.1f} s."
            )
    return lines


def _discussion(result) -> list[str]:
    """What the numbers say and what would close the gaps (computed from the run)."""
    table, poisson = _index(result["records"])
    pgpm = [r for r in table.values() if r["solver"] == "pgpm" and r["status"] == "ok"]
    profiled = [r for r in result["records"] if r.get("profile") and r["solver"] == "pgpm"]
    if not pgpm or not profiled:
        return []
    its = [r["iterations"] for r in pgpm]
    r = max(profiled, key=lambda q: q["dofs"])
    prof = r["profile"]
    e = poisson.get(r["cells"])
    t_iter = prof["one PGPM iteration (measured)"]
    t_res, t_energy = prof["residual assembly DG(u)"], prof["energy assembly G(u)"]
    listed = sum(v for k, v in prof.items() if k not in _NOT_IN_ITERATION)
    lines = [
        "## Reading the numbers, and what would close the gaps",
        "",
        f"- PGPM's iteration count is h-independent, as the paper claims: {min(its)}-"
        f"{max(its)} iterations from N = {min(q['dofs'] for q in pgpm)} to "
        f"{max(q['dofs'] for q in pgpm)} on both problems. The PETSc peers without a good "
        "preconditioner do not have this: "
        "BLMVM and BQNLS need thousands of iterations already at N = 1e4, and PGPM with the "
        "identity metric does not converge within its budget at N = 1e4.",
        f"- One PGPM iteration costs {t_iter / t_res:.1f} residual assemblies at N = "
        f"{r['dofs']} ({1e3 * t_iter:.0f} ms): the residual DG(u) ({1e3 * t_res:.0f} ms) and "
        f"the energy G(u) ({1e3 * t_energy:.0f} ms) dominate; B^-1, the dense S_h product and "
        "the exact projection together are below one residual assembly, and "
        f"{1e3 * max(t_iter - listed, 0.0):.0f} ms are vector operations in Python. So "
        "the substructuring preconditioner is cheap; the cost is the ~170 nonlinear "
        "evaluations of J_h and its gradient.",
    ]
    increases = sum(q.get("details", {}).get("energy_increases", 0) for q in pgpm)
    if e and e.get("total"):
        units = e["total"] / t_res
        lean = r["setup"] + r["iterations"] * (t_iter - t_energy)
        lines.append(
            f"- The Poisson yardstick at this size costs {e['total']:.1f} s, about {units:.0f} "
            f"residual assemblies (assembly, GAMG set-up and {e['iterations']} CG iterations). "
            f"Ten of them are {10 * units:.0f} residual assemblies, while PGPM needs "
            f"{r['iterations'] * t_iter / t_res:.0f}: with a count of ~170 no iteration "
            "costing a residual assembly or more can meet the 10x target. Dropping the "
            "energy assembly from the step (J_h is only needed for the monotonicity check "
            f"that triggers backtracking, which fired {increases} times in this run: "
            "evaluate it every k steps or test descent with the gradient already computed) "
            "would bring this run to about "
            f"{lean:.0f} s, {lean / e['total']:.1f}x the Poisson solve. Fusing the energy "
            "into the residual kernel (one pass over the cells computes rho(|grad u|) once) "
            "is the alternative if J_h must be evaluated at every step."
        )
    big = max(q["cells"] for q in pgpm)
    at_big = {
        (q["problem"], q["solver"]): q
        for q in table.values()
        if q["cells"] == big and q.get("status") == "ok"
    }
    snes = [
        (p, at_big[p, "snes-substructuring"]["total"] / at_big[p, "pgpm"]["total"])
        for p in PROBLEMS
        if (p, "snes-substructuring") in at_big and (p, "pgpm") in at_big
    ]
    mem = [
        (at_big[p, "snes-substructuring"]["delta_mb"], at_big[p, "pgpm"]["delta_mb"])
        for p, _ in snes
    ]
    shrink = []
    for p in PROBLEMS:
        ratios = [
            (q["dofs"], q["total"] / table[p, q["cells"], "pgpm"]["total"])
            for q in sorted(table.values(), key=lambda q: q["cells"])
            if q["problem"] == p
            and q["solver"] == "snes-substructuring"
            and q.get("status") == "ok"
            and q["dofs"] >= 2.5e5
            and table.get((p, q["cells"], "pgpm"), {}).get("status") == "ok"
        ]
        if ratios:
            shrink.append(f"{p} " + ", ".join(f"{x:.2f} (N = {d})" for d, x in ratios))
    sub = [
        q
        for q in table.values()
        if q["solver"] == "snes-substructuring" and q.get("status") == "ok"
    ]
    newton = [q["iterations"] for q in sub]
    cg = [q["linear_iterations"] / max(q["iterations"], 1) for q in sub]
    fast = [
        q["total"] / table[q["problem"], q["cells"], "pgpm"]["total"]
        for q in table.values()
        if q["solver"] in ("apgpm", "ssn")
        and q.get("status") == "ok"
        and table.get((q["problem"], q["cells"], "pgpm"), {}).get("status") == "ok"
    ]
    mumps = [
        q["total"] / at_big[q["problem"], "pgpm"]["total"]
        for (p, n), q in at_big.items()
        if n in ("snes-mumps-cholesky", "tao-bnls", "tao-bntr") and (p, "pgpm") in at_big
    ]
    if snes:
        lines.append(
            "- Against SNES VI + CG/B the gap is the iteration count, not the preconditioner: "
            f"Newton needs {min(newton)}-{max(newton)} outer steps, each one Hessian assembly "
            f"and {min(cg):.0f}-{max(cg):.0f} CG iterations of a sparse product and one B^-1, "
            "instead of ~170 "
            "nonlinear evaluations. SNES pays for the dense S_h block as "
            f"{(r['n_gamma'] + r['n_signorini']) ** 2:.1e} AIJ entries at N = {r['dofs']} "
            "(every CG product and the inactive-set submatrix of every Newton step go "
            "through them; memory increase "
            + ", ".join(f"{a:.0f} MB vs PGPM's {b:.0f} MB" for a, b in mem)
            + "). SNES / PGPM time: "
            + "; ".join(shrink)
            + "."
        )
    if fast:
        lines.append(
            "- The project's own answers are in the tables: APGPM (Nesterov momentum in the "
            "B metric with restarts, ~55 iterations) and SSN (semismooth Newton with "
            "B-preconditioned CG on the inactive set, the dense block applied as a dense "
            "product, 11-12 outer steps; the default method) take "
            f"{min(fast):.2f}-{max(fast):.2f} of PGPM's time at every size; Targets above "
            "lists where they beat every PETSc peer and stay within 10x of the Poisson "
            "solve. PGPM (the paper's method) needs the cheaper iteration above to get near "
            "the 10x line."
        )
    if mumps:
        lines.append(
            "- MUMPS-based peers (SNES VI and TAO BNLS/BNTR) factor the reduced Hessian with "
            "its dense n_Gamma x n_Gamma block at every Newton step: "
            f"{min(mumps):.1f}-{max(mumps):.1f}x PGPM's time at N = {r['dofs']}, with the "
            "largest memory peaks. The first-order TAO methods (BLMVM, BQNLS) do not reach "
            "PGPM's accuracy by their own test and run out of budget early (tables)."
        )
    lines += [
        f"- Timing noise: the machine was shared (load average {result['machine']['load']:.1f} "
        "at the start on 2 cores). Two full runs of the same PGPM code during development "
        "differed by 2-5% at N = 1e6 and up to 16% at N = 2.5e5 (more for sub-second "
        f"solves), so differences within {100 * TIE:.0f}% of the fastest peer are marked "
        "as ties.",
    ]
    return lines


def print_table(result: dict[str, Any]) -> None:
    for problem in PROBLEMS:
        print(f"\n## {PROBLEMS[problem]['label']}\n")
        print("\n".join(markdown_table(result, problem)))
    print()
    print("\n".join(_targets_text(result)))


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
