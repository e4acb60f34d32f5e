"""The command line of the peer benchmark (``python -m bench.peers``, ``make bench``)."""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from bench import peers
from bench.peers.report import print_table, report
from bench.peers.runner import BENCH, run
from bench.peers.solvers import BY_NAME, FULL_SIZES, QUICK_SIZES
from bench.peers.tables import plot
from bench.peers.targets import targets
from bench.peers.worker import worker
from bench.speed import cell_sizes


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``python -m bench.peers`` and ``make bench`` (see :mod:`bench.peers`)."""
    parser = argparse.ArgumentParser(
        prog="python -m bench.peers", description=peers.__doc__.splitlines()[0]
    )
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
                "the peer benchmark is serial (each solver in one process, "
                "PETSc peers on PETSC_COMM_SELF); run it without mpirun",
                file=sys.stderr,
            )
        return 2
    if args.worker:
        worker(json.loads(args.worker))
        return 0
    if args.sizes:
        cell_sizes(parser, args.sizes)
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
    out = Path(args.out) if args.out else (None if args.quick else BENCH)
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        command = (
            "python -m bench.peers"
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
