"""Strong scaling of the whole solve from P = 1 to P = 2 ranks (issues 7 and 67).

The manufactured contact problem on the square (carstensen material, d/h = 4) with
about 10^6 dofs (``--shape square``, the default), or on the box with ``--cells`` cubes
per side (``--shape box``, 64: 274,625 dofs; ``coupling.manufactured.box_contact``), is
solved once per rank count, each in its own ``mpirun -n P`` process with
``threads_per_rank`` threads a rank (the cores shared by the ranks, as ``fembem``
runs); rank 0 reports the time of every phase (the slowest rank's, as every phase ends
in a collective):

- setup: the mesh (generated on rank 0 and distributed, whole subdomains per rank),
  the coarse structure, the interior forms, the boundary map and the loads;
- S_h: the Steklov-Poincare operator (2D: the dense matrix computed on rank 0 with every
  core and scattered by rows; 3D: the H-matrices, each rank its rows);
- factorisations: the preconditioner set-up (the P1 matrix's pattern, which the Jacobians
  then share as in ``solve``, A_II per rank, the coarse matrix);
- iterations: the step estimate and the solver iterations;
- outputs: u_e on Gamma and its exterior normal derivative (one V_h solve on rank 0).

The machine's own ceilings are measured in the same run, with the same ``mpirun`` and
rank counts (:func:`ceiling_worker`): a memory-bound kernel (a STREAM-like triad on
arrays far larger than the caches) and a compute-bound one (transcendental functions on
an array that stays in L1/L2), each splitting a fixed amount of work over the ranks.
The two bracket what a phase of the solve can gain from P = 1 to 2: memory-bound work
(sparse assembly, sparse triangular solves and products, the dense S_h product) scales
like the triad, compute-bound work (quadrature of a nonlinear material) like the second.
The triad is timed twice: its peak (the best single triad of 10) and sustained
(``SUSTAINED_SWEEPS`` triads back to back, seconds long like a phase of the solve, with
each rank's own time: on a VM the vCPUs' speeds differ over seconds, and a run that
synchronises its ranks goes at the slower one's pace).
The workload's own ceiling is measured beside them (:func:`independent_parts`): for each
P > 1, P serial solves of about 1/P of the dofs (cells / P^(1/d) per side) at the same
time, one thread each, with no
communication and nothing computed twice; the slowest part's phases are a row of the
phase table. No P-rank solve can beat them, so when they fall short of the triad no code
could meet issue 33's target in that run (how often that happened on the 2-core VMs:
docs/design/parallel.md, "The eleventh session").

Every rank count is run ``--repeat`` times, alternating between the rank counts, and the
run with the smallest total is reported for each (the machine is shared: other load
only ever adds time). Prints a table of times and speed-ups (issue 7's target: at least
1.6x from P = 1 to 2 at 10^6 dofs), the totals of every run, and each speed-up beside
the ceilings with the verdict on issue 33's target (at or above the peak triad) and on
whether the independent parts reached it; writes them to ``--output`` (markdown) if
given.

    .venv/bin/python bench/strong_scaling.py [--shape square] [--cells 1000] [--ranks 1 2]
                                             [--method ssn pgpm] [--repeat 3]
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PHASES = ("setup", "S_h", "factorisations", "iterations", "outputs", "total")
#: The manufactured solutions of ``--shape`` (coupling.manufactured), by name.
SHAPES = ("square", "box")
#: Issue 67's target for the box: the P-rank speed-up at least this fraction of the
#: independent parts' in the same run.
PARTS_FRACTION_TARGET = 0.85


def worker(shape: str, cells: int, method: str) -> None:
    """Run in every rank of ``mpirun -n P``: solve once, print the phase times on rank 0."""
    from mpi4py import MPI
    from threadpoolctl import threadpool_limits

    from coupling.manufactured import box_contact, manufactured_problem, square_contact
    from coupling.options import SolverOptions
    from coupling.preconditioners import build_preconditioner, create_matrix
    from coupling.solvers import solve
    from fem_py.forms import make_material
    from fem_py.parallel import threads_per_rank

    comm = MPI.COMM_WORLD
    options = SolverOptions(method=method)
    comm.Barrier()
    threads = threads_per_rank(comm)  # collective
    with threadpool_limits(threads):  # as the fembem command does
        tic = time.perf_counter()
        solution = {"square": square_contact, "box": box_contact}[shape]()
        problem = manufactured_problem(comm, solution, make_material("carstensen"), cells=cells)
        assembled = time.perf_counter()
        # built here to report its class; one P1 matrix for B and the Jacobians, as
        # solve() shares it when it builds B itself
        matrix = create_matrix(problem, options)
        B = build_preconditioner(problem, options, matrix=matrix)
        factorisations = time.perf_counter() - assembled
        comm.Barrier()  # the slowest rank's set-up
        built = time.perf_counter() - tic
        result = solve(problem, options, preconditioner=B, matrix=matrix)
        total = time.perf_counter() - tic
        B.destroy()
        matrix.destroy()
    t = {**problem.timings, **result.timings}
    phases = {
        "S_h": t["steklov_poincare"],
        "factorisations": factorisations,
        "iterations": t["step_estimate"] + t["solve"],
    }
    phases["setup"] = built - phases["S_h"] - phases["factorisations"]
    phases["outputs"] = total - built - phases["iterations"]  # u_e and its flux on Gamma
    phases["total"] = total
    coarse = getattr(problem.domain, "coarse", None)  # the planar subdomains (none in 3D)
    if comm.rank == 0:
        print(
            json.dumps(
                {
                    "ranks": comm.size,
                    "dofs": problem.V.dofmap.index_map.size_global,
                    "boundary_dofs": problem.boundary.n_gamma,
                    "method": method,
                    "shape": shape,
                    "threads": threads,
                    "subdomains": 0 if coarse is None else coarse.n_subdomains,
                    "preconditioner": type(B).__name__,
                    "iterations_count": result.iterations,
                    "converged": bool(result.converged),
                    "energy": result.energy,
                    **phases,
                }
            ),
            flush=True,
        )


#: The ceiling kernels' fixed work: triad arrays of 2^25 doubles (3 x 256 MiB in all, far
#: beyond the 32 MiB L3), and 2^26 transcendental evaluations on an array of 2^15 doubles.
TRIAD_ENTRIES, COMPUTE_ENTRIES, COMPUTE_SWEEPS = 2**25, 2**15, 2**11
#: The sustained triad: that many triads back to back (3 s on one rank of the 2-vCPU VMs),
#: as long as a phase of the solve. The best single triad is the machine's peak; a
#: phase meets the machine's speed over seconds, which differs between its vCPUs
#: (docs/design/parallel.md, "The ninth session").
SUSTAINED_SWEEPS = 100


def ceiling_worker() -> None:
    """Run in every rank of ``mpirun -n P``: the best of 10 times of a fixed amount of
    memory-bound and of compute-bound work split evenly over the ranks (one thread each);
    rank 0 prints them."""
    import numpy as np
    from mpi4py import MPI
    from threadpoolctl import threadpool_limits

    comm = MPI.COMM_WORLD
    n = TRIAD_ENTRIES // comm.size
    a, b, c = np.zeros(n), np.ones(n), np.ones(n)  # written once: pages are touched before timing
    small = np.linspace(0.0, 1.0, COMPUTE_ENTRIES)
    sweeps = COMPUTE_SWEEPS // comm.size

    def triad() -> None:
        """a = b + 3 c: 5 x 8 bytes an entry (multiply: c in, a out; add: a, b in, a out)."""
        np.multiply(c, 3.0, out=a)
        np.add(a, b, out=a)

    def compute() -> None:
        for _ in range(sweeps):
            np.sin(np.exp(small), out=small)

    times = {}
    with threadpool_limits(1):
        for name, kernel in (("triad", triad), ("compute", compute)):
            best = float("inf")
            for _ in range(10):
                comm.Barrier()
                tic = time.perf_counter()
                kernel()
                comm.Barrier()
                best = min(best, time.perf_counter() - tic)
            times[name] = best
        comm.Barrier()
        tic = time.perf_counter()
        for _ in range(SUSTAINED_SWEEPS):
            triad()
        own = time.perf_counter() - tic
        comm.Barrier()
        times["sustained"] = time.perf_counter() - tic
    own_times = comm.gather(own)
    if comm.rank == 0:
        print(json.dumps({"ranks": comm.size, **times, "sustained_ranks": own_times}), flush=True)


def _command(ranks: int, args: list[str]) -> list[str]:
    """``mpirun -n ranks`` of this script with ``args`` (the script alone for one rank)."""
    cmd = [
        "mpirun",
        "--allow-run-as-root",
        "--oversubscribe",
        "--bind-to",
        "none",
        "-n",
        str(ranks),
        sys.executable,
        __file__,
        *args,
    ]
    return cmd[cmd.index(sys.executable) :] if ranks == 1 else cmd


def _start(cmd: list[str], **env: str) -> subprocess.Popen:
    # os.environ, not the C environment: an MPI-initialised parent (a test process) has
    # Open MPI singleton variables there that make mpirun fail
    return subprocess.Popen(
        cmd,
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, **env},
    )


def _last_json(proc: subprocess.Popen, what: str) -> dict:
    """The last JSON line ``proc`` printed, once it has ended (exit if it failed)."""
    stdout, stderr = proc.communicate()
    if proc.returncode != 0:
        sys.exit(f"error: {what} failed:\n{(stdout + stderr)[-2000:]}")
    return json.loads(stdout.strip().splitlines()[-1])


def _mpirun(ranks: int, args: list[str]) -> dict:
    """The last JSON line printed by ``mpirun -n ranks`` of this script with ``args``."""
    return _last_json(_start(_command(ranks, args)), f"the run with {ranks} rank(s)")


def _worker_args(shape: str, cells: int, method: str) -> list[str]:
    return ["--worker", "--shape", shape, "--cells", str(cells), "--method", method]


def run(ranks: int, shape: str, cells: int, method: str) -> dict:
    return _mpirun(ranks, _worker_args(shape, cells, method))


def independent_parts(parts: int, shape: str, cells: int, method: str) -> dict:
    """``parts`` serial solves of the problem with about 1/parts of the dofs (``cells`` /
    parts^(1/d) per side, d = 2 for the square, 3 for the box: :func:`_part_cells`), run
    at the same time with one thread each and no
    communication: the slowest one's result (its phase times, as :func:`worker` prints
    them) and its size, ``part_dofs``.

    This is what ``parts`` ranks could reach at best on this machine if the solve split
    into independent pieces: each piece meets its twins' load on the memory system and
    the cores, but never waits for them, and nothing is computed twice. The full size's
    one-rank time over this time is the workload's own ceiling for P = ``parts``, beside
    the triad's (docs/design/parallel.md)."""
    part_cells = _part_cells(shape, cells, parts)
    procs = [
        _start(_command(1, _worker_args(shape, part_cells, method)), OMP_NUM_THREADS="1")
        for _ in range(parts)
    ]
    try:
        results = [_last_json(proc, f"an independent part of {part_cells} cells") for proc in procs]
    finally:  # one failed: the others do not outlive the bench
        for proc in procs:
            if proc.poll() is None:
                proc.kill()
    slowest = max(results, key=lambda r: r["total"])
    return {**slowest, "part_dofs": slowest["dofs"]}


def _part_cells(shape: str, cells: int, parts: int) -> int:
    """Cells per side of an independent part: about 1/parts of the dofs, at least 8; on
    the box the nearest size whose lattice the multigrid coarsens (as the whole box's), so
    that the parts run the same preconditioner."""
    if shape != "box":
        return max(8, round(cells / parts**0.5))
    from coupling.preconditioners.lattice_multigrid import lattice_levels

    target = cells / parts ** (1 / 3)
    sizes = [n for n in range(8, max(cells, 8) + 1) if lattice_levels(n) is not None]
    return min(sizes, key=lambda n: abs(n - target)) if sizes else max(8, round(target))


def ceilings(ranks: list[int], repeat: int) -> tuple[str, dict[int, dict[str, float]]]:
    """The ceiling kernels on every rank count, ``repeat`` rounds alternating between the
    rank counts (the bandwidth a VM gets varies with its neighbours' load): the best
    times as a markdown table with the triad speed-ups of every round, and the best
    speed-ups over the first rank count, {P: {"triad", "sustained", "compute"}}."""
    rounds = [[_mpirun(p, ["--ceiling"]) for p in ranks] for _ in range(repeat)]
    kernels = ("triad", "sustained", "compute")
    best = [{k: min(rnd[i][k] for rnd in rounds) for k in kernels} for i in range(len(ranks))]
    base = best[0]
    speedups = {p: {k: base[k] / r[k] for k in kernels} for p, r in zip(ranks, best)}
    lines = [
        f"# Machine ceilings: fixed work split over P ranks (one thread per rank; the best "
        f"of {repeat} round(s) shown)\n",
        "- peak triad: the best of 10 single triads (a = b + 3 c on 2^25 doubles in all);",
        f"- sustained triad: {SUSTAINED_SWEEPS} triads back to back, the slowest rank's time "
        "(each rank's own time in brackets: the vCPUs' speeds differ);",
        "- compute-bound: the best of 10 runs of transcendental functions on an L1/L2 array.\n",
        "| P | peak triad | triad bandwidth | sustained triad | compute-bound kernel |",
        "|---|---|---|---|---|",
    ]
    for i, (p, r) in enumerate(zip(ranks, best)):
        fastest = min((rnd[i] for rnd in rounds), key=lambda x: x["sustained"])
        own = ", ".join(f"{t:.2f}" for t in fastest["sustained_ranks"])
        lines.append(
            f"| {p} | {r['triad']:.3f} s ({speedups[p]['triad']:.2f}x) | "
            f"{5 * 8 * TRIAD_ENTRIES / r['triad'] / 1e9:.1f} GB/s | "
            f"{r['sustained']:.2f} s ({speedups[p]['sustained']:.2f}x; {own}) | "
            f"{r['compute']:.3f} s ({speedups[p]['compute']:.2f}x) |"
        )
    every = "; ".join(
        f"P = {p}: "
        + ", ".join(
            f"{rnd[0]['triad'] / rnd[i]['triad']:.2f}x / "
            f"{rnd[0]['sustained'] / rnd[i]['sustained']:.2f}x"
            for rnd in rounds
        )
        for i, p in enumerate(ranks)
        if i > 0
    )
    text = "\n".join(lines) + f"\n\npeak / sustained triad speed-up of every round: {every}\n"
    return text, speedups


def best_runs(
    ranks: list[int], shape: str, cells: int, method: str, repeat: int
) -> tuple[list[dict], dict, dict]:
    """The fastest of ``repeat`` runs for every rank count and, for every count P > 1, the
    fastest of ``repeat`` runs of P independent parts (:func:`independent_parts`); every
    total. Rounds alternate between them, so slow spells of the machine hit all."""
    totals: dict[int, list[float]] = {p: [] for p in ranks}
    best: dict[int, dict] = {}
    parts: dict[int, dict] = {}
    for _ in range(repeat):
        for p in ranks:
            r = run(p, shape, cells, method)
            totals[p].append(r["total"])
            if p not in best or r["total"] < best[p]["total"]:
                best[p] = r
            if p > 1:
                r = independent_parts(p, shape, cells, method)
                if p not in parts or r["total"] < parts[p]["total"]:
                    parts[p] = r
    return [best[p] for p in ranks], totals, parts


def table(
    runs: list[dict],
    totals: dict[int, list[float]],
    parts: dict[int, dict],
    ceiling: dict[int, dict[str, float]],
) -> str:
    """The phase table of the fastest runs, every run's total, the independent parts, and
    each speed-up beside the same run's ceilings (``ceiling``, from :func:`ceilings`)."""
    base = runs[0]
    head = (
        f"# Strong scaling, the {base['shape']}: {base['dofs']} dofs, {base['boundary_dofs']} "
        f"boundary dofs, {base['subdomains']} subdomains, method {base['method']}\n\n"
        f"machine: {platform.node()}, {os.cpu_count()} cores, load average "
        f"{os.getloadavg()[0]:.2f} at the end; times in s (slowest rank), speed-up "
        f"relative to P = {base['ranks']}; the fastest of "
        f"{len(totals[base['ranks']])} run(s) per P; GLIBC_TUNABLES="
        f"{os.environ.get('GLIBC_TUNABLES', '(unset)')} (docs/guide/mpi.md)\n\n"
    )
    lines = [
        "| P | threads a rank | B | iterations | " + " | ".join(PHASES) + " |",
        "|---|---|---|---|" + "---|" * len(PHASES),
    ]
    # the parts are a ceiling against one rank only: each part's speed-up over it
    parts = parts if base["ranks"] == 1 else {}
    parts_speedup = {p: base["total"] / r["total"] for p, r in parts.items()}
    rows = [(str(r["ranks"]), r) for r in runs]
    rows += [(f"{p} independent parts", r) for p, r in parts.items()]  # beside the P-rank run
    for label, r in rows:
        cells = [f"{r[p]:.2f} ({base[p] / r[p]:.2f}x)" for p in PHASES]
        lines.append(
            f"| {label} | {r['threads']} | {r['preconditioner']} | {r['iterations_count']} | "
            + " | ".join(cells)
            + " |"
        )
    every = "; ".join(f"P = {p}: " + ", ".join(f"{t:.2f}" for t in ts) for p, ts in totals.items())
    text = head + "\n".join(lines) + f"\n\ntotals of every run (s): {every}\n"
    if parts:
        text += (
            "\nIndependent parts (P serial solves of 1/P of the dofs at the same time, one "
            "thread each, no communication; the slowest of the fastest run): "
            + "; ".join(
                f"P = {p}: {r['part_dofs']} dofs each, {r['total']:.2f} s, a ceiling of "
                f"{parts_speedup[p]:.2f}x"
                for p, r in parts.items()
            )
            + "\n"
        )
    for r in runs[1:]:
        c = ceiling[r["ranks"]]
        speedup = base["total"] / r["total"]
        independent = parts_speedup.get(r["ranks"])
        text += (
            f"\nP = {r['ranks']}: speed-up {speedup:.2f}x; ceilings in this "
            f"run: peak triad {c['triad']:.2f}x, sustained triad {c['sustained']:.2f}x, "
            f"compute-bound {c['compute']:.2f}x"
            + ("" if independent is None else f", independent parts {independent:.2f}x")
            + "\n"
            + _verdict(speedup, c["triad"], independent)
        )
        if independent is not None:
            # of the ratios as printed, as _verdict compares them
            fraction = round(round(speedup, 2) / round(independent, 2), 2)
            text += (
                f"{fraction:.0%} of the independent parts' speed-up (the box's target: at "
                f"least {PARTS_FRACTION_TARGET:.0%}): "
                f"{'met' if fraction >= PARTS_FRACTION_TARGET else 'missed'}\n"
            )
    return text


def _verdict(speedup: float, triad: float, independent: float | None) -> str:
    """Whether the speed-up is at or above the peak triad's (the target), and whether the
    workload's own ceiling let any code reach it in this run: P independent parts never
    wait for each other and compute nothing twice, so no P-rank solve can beat them. The
    ratios are compared as printed, to two decimals."""
    speedup, triad = round(speedup, 2), round(triad, 2)
    text = f"target (at or above the peak triad): {'met' if speedup >= triad else 'missed'}"
    if independent is not None:
        reach = round(independent, 2) >= triad
        text += (
            f"; the independent parts ({independent:.2f}x) "
            f"{'reach' if reach else 'fall short of'} the peak triad, so the target was "
            f"{'reachable' if reach else 'out of reach'} in this run"
        )
    return text + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shape", default="square", choices=SHAPES)
    parser.add_argument(
        "--cells",
        type=int,
        default=None,
        help="cells (cubes) per side (default: 1000 for the square, 1.0e6 dofs; 64 for the box)",
    )
    parser.add_argument("--ranks", type=int, nargs="+", default=[1, 2])
    parser.add_argument(
        "--method",
        nargs="+",
        default=["ssn", "pgpm"],
        choices=["pgpm", "apgpm", "ssn"],
        help="solver methods, one table each (default: ssn pgpm)",
    )
    parser.add_argument(
        "--repeat",
        type=int,
        default=3,
        help="runs per rank count, the fastest reported (default 3)",
    )
    parser.add_argument("--output", type=Path, help="also write the table (markdown) here")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--ceiling", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.cells is None:
        args.cells = 64 if args.shape == "box" else 1000
    if args.cells < 8 or any(p < 1 for p in args.ranks) or args.repeat < 1:
        print("error: --cells must be >= 8, --ranks >= 1 and --repeat >= 1", file=sys.stderr)
        return 2
    if args.worker:
        worker(args.shape, args.cells, args.method[0])
        return 0
    if args.ceiling:
        ceiling_worker()
        return 0
    ceiling_text, ceiling = ceilings(args.ranks, args.repeat)
    tables = [ceiling_text]
    tables += [
        table(*best_runs(args.ranks, args.shape, args.cells, method, args.repeat), ceiling)
        for method in args.method
    ]
    text = "\n".join(tables)
    print(text)
    if args.output:
        tmp = args.output.with_suffix(".tmp")
        tmp.write_text(text)
        tmp.replace(args.output)
    return 0


if __name__ == "__main__":
    sys.exit(main())
