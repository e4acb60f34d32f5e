"""Time and peak memory of the output stage of `fembem solve`, and its share of a whole run.

For each mesh (the structured square [-1/4, 1/4]^2 with the data of tests/test_info.py,
ssn, one rank) the problem is solved once and its outputs are written three times into
fresh folders: the data alone (summary.json, fields.npz), with solution.xdmf/.h5, and with
the xdmf and the plots, as `fembem solve` does by default. Each row gives the seconds of
each (xdmf and plots as the increments over the previous variant), the CPU seconds of
the process in the last write of the full outputs (wall time counts the load of a shared
machine, CPU time much less; the two agree on an idle one), the peak resident
memory of the process while the full outputs are written and its rise above the memory
held before they start (the peak is reset through /proc/self/clear_refs). Last, one
whole `fembem solve` at --whole cells per side: outputs / total from its summary.json and
its peak resident memory. With --pieces, the seconds of each piece of the last full
write at the largest mesh (gathering u_h, the flux, the XDMF file, each file written,
rasterising u_h, each figure built, the exterior potential and its triangulation). No
assertions: the numbers go to docs/design/outputs.md and docs/design/speed.md.

    .venv/bin/python bench/outputs.py [--cells 100 250 500 1000] [--whole 1000] [--repeat 1]
        [--pieces]
"""
from __future__ import annotations

import argparse
import contextlib
import importlib
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from mpi4py import MPI

from coupling.app.config import check_data_and_material, load_config
from coupling.app.from_config import problem_from_config
from coupling.io.outputs import write_outputs
from coupling.solvers import solve

CONFIG = """
[geometry]
shape = "square"
h = {h!r}
subdomain_size = {d!r}
structured = true
signorini = ["bottom"]
[material]
rho = "carstensen"
[data]
f = "1 + x"
t0 = "-1"
u0 = "0.1"
[solver]
method = "ssn"
"""
VARIANTS = (("data", False, False), ("xdmf", True, False), ("plots", True, True))
#: The pieces of the outputs stage that --pieces times: (module, function) pairs.
PIECES = (
    ("coupling.io.outputs", "gather_p1_and_cells"),
    ("coupling.io.outputs", "boundary_flux"),
    ("coupling.io.outputs", "write_solution_xdmf"),
    ("coupling.io.plots", "rasterise"),
    ("coupling.io.figures", "render"),
    ("coupling.io.figures", "_figure_u"),
    ("coupling.io.figures", "_figure_boundary"),
    ("coupling.io.figures", "_figure_whole_plane"),
    ("coupling.io.figures", "figure_history"),
    ("bem_cpp", "exterior_potential"),
    ("coupling.io.figures", "Triangulation"),
)


def write_config(folder: Path, cells: int) -> Path:
    """The configuration file of the square with ``cells`` cells per side (h = 1/(2 cells))."""
    h = 0.5 / cells
    path = folder / f"square-{cells}.toml"
    path.write_text(CONFIG.format(h=h, d=4 * h))
    return path


def _status(key: str) -> int:
    """Bytes of /proc/self/status ``key`` (VmRSS, VmHWM)."""
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith(key + ":"):
                return int(line.split()[1]) * 1024
    raise OSError(f"{key} not in /proc/self/status")


def _reset_peak() -> None:
    with open("/proc/self/clear_refs", "w") as refs:  # "5": reset VmHWM to VmRSS (Linux)
        refs.write("5")


@contextlib.contextmanager
def _timed_pieces(seconds: dict):
    """Add the seconds of each call of :data:`PIECES` (and of each file written, keyed by
    its name) to ``seconds`` while the block runs; the functions are restored after."""
    saved = []

    def patch(module, name, key):
        original = getattr(module, name)

        def timed(*args, **kwargs):
            tic = time.perf_counter()
            try:
                return original(*args, **kwargs)
            finally:
                label = key(args)
                seconds[label] = seconds.get(label, 0.0) + time.perf_counter() - tic

        saved.append((module, name, original))
        setattr(module, name, timed)

    for module_name, name in PIECES:
        patch(importlib.import_module(module_name), name, lambda args, name=name: name)
    for module_name in ("coupling.io.outputs", "coupling.io.plots"):
        patch(importlib.import_module(module_name), "atomic_write", lambda a: Path(a[0]).name)
    try:
        yield seconds
    finally:
        for module, name, original in reversed(saved):
            setattr(module, name, original)


def output_stage(
    comm: MPI.Comm, folder: Path, cells: int, repeat: int, pieces: dict | None = None
) -> dict:
    """Solve once, then time each variant of the outputs (fresh folder each; the best of
    ``repeat`` writes, the peak memory of the first). With ``pieces`` (a dict) the last
    write of the full outputs records the seconds of its pieces there."""
    config = load_config(write_config(folder, cells))
    check_data_and_material(config)
    problem, options, _ = problem_from_config(comm, config)
    result = solve(problem, options)
    row = {"N": problem.V.dofmap.index_map.size_global}
    previous = 0.0
    for name, xdmf, plots in VARIANTS:
        times = []
        for k in range(repeat):
            out = Path(tempfile.mkdtemp(dir=folder))
            _reset_peak()
            before = _status("VmRSS")
            last = pieces is not None and name == VARIANTS[-1][0] and k == repeat - 1
            timers = _timed_pieces(pieces) if last else contextlib.nullcontext()
            tic, cpu = time.perf_counter(), time.process_time()
            with timers:
                write_outputs(
                    comm, out, problem, result, tol=options.tol, timings={}, xdmf=xdmf, plots=plots
                )
            times.append(time.perf_counter() - tic)
            row["cpu"] = time.process_time() - cpu
            if k == 0:
                row["peak"], row["rise"] = _status("VmHWM"), _status("VmHWM") - before
        row[name] = min(times) - previous
        previous = row["outputs"] = min(times)
    return row


def whole_run(folder: Path, cells: int) -> dict:
    """One `fembem solve` in a child process: its timings and peak resident memory (GNU
    time: the peak of a child of this large process would count the pages of its fork)."""
    fembem = str(Path(sys.executable).parent / "fembem")
    out, peak = folder / f"whole-{cells}", folder / f"whole-{cells}.rss"
    config = write_config(folder, cells)
    subprocess.run(
        ["/usr/bin/time", "-f", "%M", "-o", str(peak), fembem, "solve", str(config)]
        + ["--out", str(out), "--quiet"],
        check=True,
    )
    summary = json.loads((out / "summary.json").read_text())
    return dict(
        N=summary["dofs"],
        timings=summary["timings"],
        peak=int(peak.read_text().split()[-1]) * 1024,
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, nargs="+", default=[100, 250, 500, 1000])
    parser.add_argument("--whole", type=int, default=1000, help="cells per side (0: skip)")
    parser.add_argument("--repeat", type=int, default=1, help="writes per variant (the best)")
    parser.add_argument("--pieces", action="store_true", help="time the pieces at the largest N")
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    print(f"# output stage, one rank ({platform.node()}, load average {os.getloadavg()[0]:.1f})")
    print("| N | data (s) | + xdmf (s) | + plots (s) | outputs (s) | CPU (s) | peak RSS | rise |")
    print("|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        pieces = {}
        for cells in args.cells:
            last = args.pieces and cells == max(args.cells)
            r = output_stage(comm, Path(tmp), cells, args.repeat, pieces if last else None)
            print(
                f"| {r['N']:,} | {r['data']:.2f} | {r['xdmf']:.2f} | {r['plots']:.2f} "
                f"| {r['outputs']:.2f} | {r['cpu']:.2f} | {r['peak'] / 1e6:,.0f} MB "
                f"| {r['rise'] / 1e6:,.0f} MB |",
                flush=True,
            )
        if pieces:
            print(f"\npieces of the last full write at {max(args.cells)} cells per side:\n")
            print("| piece | s |\n|---|---:|")
            for label, seconds in pieces.items():
                print(f"| {label} | {seconds:.3f} |")
        if args.whole and comm.rank == 0:
            w = whole_run(Path(tmp), args.whole)
            t = w["timings"]
            rest = sum(v for k, v in t.items() if k not in ("outputs", "total"))
            print(
                f"\nwhole `fembem solve`, N = {w['N']:,}: outputs {t['outputs']:.1f} s of "
                f"total {t['total']:.1f} s ({t['outputs'] / t['total']:.0%}); other stages "
                f"{rest:.1f} s (sum of the stages {rest + t['outputs']:.1f} s); "
                f"peak RSS {w['peak'] / 1e6:,.0f} MB"
            )


if __name__ == "__main__":
    main()
