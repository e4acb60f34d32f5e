"""The driver of the peer benchmark: one worker process per mesh size, smallest first,
and the machine the benchmark ran on."""
from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any, Callable

from bench.peers.solvers import (
    BY_NAME,
    FULL_SIZES,
    PROBLEMS,
    QUICK_SIZES,
    SOLVERS,
    TOL_PHI,
    TOL_U,
    Solver,
)
from bench.peers.targets import targets
from bench.peers.worker import RECORD

ROOT = Path(__file__).resolve().parents[2]  # the source tree
BENCH = ROOT / "bench"  # results.md, results.json and peers.png of the full run


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
    cmd = [sys.executable, "-m", "bench.peers", "--worker", json.dumps(spec)]
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
