"""Peak memory of elastic runs against `fembem info`'s estimate, and the refit of the box's
constants (issue 65; docs/design/memory.md, "Elasticity (2026-12-07)").

Each run is bench/elastic.py's configuration (the Hencky square with ``n`` cells per side,
the linear elastic box with ``n`` cubes per side; figures and XDMF on, nested iteration),
``fembem solve`` in its own process under GNU time (``%M``: the peak resident memory of the
process; with ``--ranks 2`` under mpirun, the sum of each rank's), against the estimate of
coupling.app.sizing as it stands (``memory_estimate`` of the run's counts and ranks).
Printed: one table row per run (d, cells, ranks, S_h, N, n, n_s, measured, estimate,
ratio), and with ``--fit`` the least squares of the box's per-unknown and per-boundary-
unknown bytes (``DOF_BYTES_ELASTIC_3D``, ``HMATRIX_BOUNDARY_BYTES_ELASTIC_3D``) over the
box's H-matrix runs given, the other terms fixed at their constants. ``--json`` keeps the
records; ``--add`` reads records kept before (runs too large to repeat), so that a refit
can use every run measured: bench/elastic_memory.json holds the runs of memory.md's table
(2026-12-07).

    .venv/bin/python bench/elastic_memory.py --runs 3:20 3:24 3:32 [--fit] [--json F]
    .venv/bin/python bench/elastic_memory.py --add bench/elastic_memory.json --fit
    .venv/bin/python bench/elastic_memory.py --runs 2:256:dense 3:16:hmatrix 3:24::2
    (a run: DIM:CELLS[:OPERATOR[:RANKS]], OPERATOR auto, dense or hmatrix)
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

if __package__ in (None, ""):  # run as a script: the repository's root on the path
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.elastic import write_config  # noqa: E402

FEMBEM = Path(sys.executable).parent / "fembem"


def measure(folder: Path, dim: int, cells: int, operator: str, ranks: int) -> dict:
    """One run: its counts (summary.json) and its peak resident memory in bytes (summed
    over the ranks)."""
    config = write_config(folder, cells, dim)
    out = folder / f"out-{dim}-{cells}-{operator}-{ranks}"
    cmd = [str(FEMBEM), "solve", str(config), "--out", str(out), "--quiet", "--force"]
    cmd += ["--set", f"solver.boundary_operator={operator}"]
    peaks = folder / f"peak-{dim}-{cells}-{operator}-{ranks}"
    timed = f"/usr/bin/time -f %M -o {peaks}.$OMPI_COMM_WORLD_RANK " + " ".join(cmd)
    if ranks == 1:
        run = ["/usr/bin/time", "-f", "%M", "-o", f"{peaks}.0", *cmd]
    else:
        mpirun = [shutil.which("mpirun") or "mpirun", "--allow-run-as-root", "--oversubscribe"]
        run = [*mpirun, "-n", str(ranks), "sh", "-c", timed]
    proc = subprocess.run(run, capture_output=True, text=True, env=dict(os.environ))
    if proc.returncode != 0:
        raise RuntimeError(f"fembem solve failed: {proc.stderr.strip().splitlines()[-1:]}")
    peak = sum(int(Path(f"{peaks}.{r}").read_text().split()[-1]) * 1024 for r in range(ranks))
    summary = json.loads((out / "summary.json").read_text())
    counts = {k: summary[k] for k in ("dofs", "boundary_dofs", "signorini_dofs")}
    return dict(dim=dim, cells=cells, operator=operator, ranks=ranks, peak=peak, **counts)


def estimate(record: dict) -> int:
    """coupling.app.sizing's estimate (its constants as they stand) of the record's run."""
    from coupling.app.sizing import memory_estimate
    from fem_py.mesh import DomainSize

    d = record["dim"]
    counts = {k: record[k] for k in ("dofs", "boundary_dofs", "signorini_dofs")}
    size = DomainSize(**counts, subdomains=0, h_min=1.0, h_max=1.0, dim=d, components=d)
    return memory_estimate(size, record["ranks"], boundary_operator=record["operator"])


def kind(record: dict) -> str:
    """The S_h of the run: dense or H-matrix, as "auto" settles it or as asked."""
    from coupling.distributed import boundary_operator_kind

    d, operator = record["dim"], record["operator"]
    chosen = boundary_operator_kind(operator, record["boundary_dofs"] // d, d, kernel="lame")
    return chosen + ("" if operator == "auto" else ", asked for")


def row(r: dict) -> str:
    """The record's line of the table of docs/design/memory.md."""
    cells, guess = f"{r['cells']}^{r['dim']}", estimate(r)
    return (
        f"| {r['dim']} | {cells} | {r['ranks']} | {kind(r)} | {r['dofs']:,} | "
        f"{r['boundary_dofs']:,} | {r['signorini_dofs']:,} | {r['peak'] / 1e6:,.0f} | "
        f"{guess / 1e6:,.0f} | {guess / r['peak']:.2f} |"
    )


def fit(records: list[dict], smallest: int = 16) -> tuple[float, float]:
    """Least squares of the relative error over the box's one-rank H-matrix runs from
    ``smallest`` cubes per side: the bytes per unknown and per boundary unknown, the
    process, plots and M_s terms fixed."""
    import numpy as np

    from coupling.app import sizing

    box = [
        r
        for r in records
        if r["dim"] == 3 and r["ranks"] == 1 and r["cells"] >= smallest and "hmatrix" in kind(r)
    ]
    if len(box) < 2:
        raise ValueError("the fit needs two H-matrix runs of the box at least")
    keys = ("dofs", "boundary_dofs", "signorini_dofs", "peak")
    N, n, ns, peak = (np.array([r[k] for r in box], float) for k in keys)
    fixed = sizing.PROCESS_BYTES + sizing.PLOT_PROCESS_BYTES + sizing.PLOT_DOF_BYTES * N
    fixed = fixed + sizing.SIGNORINI_BYTES_ELASTIC_3D * ns**2
    A = np.stack([N / peak, n / peak], axis=1)
    (per_dof, per_boundary), *_ = np.linalg.lstsq(A, (peak - fixed) / peak, rcond=None)
    return float(per_dof), float(per_boundary)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", nargs="*", default=[], help="DIM:CELLS[:OPERATOR[:RANKS]]")
    parser.add_argument("--add", type=Path, help="records of earlier runs (--json's file)")
    parser.add_argument("--json", type=Path, help="write the records here")
    parser.add_argument("--fit", action="store_true", help="refit the box's two constants")
    parser.add_argument("--fit-from", type=int, default=16, help="the fit's smallest box")
    args = parser.parse_args(argv)
    records = json.loads(args.add.read_text()) if args.add else []
    for record in records:
        print(row(record), flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        for spec in args.runs:
            dim, cells, operator, ranks = (spec.split(":") + ["", "", ""])[:4]
            record = measure(Path(tmp), int(dim), int(cells), operator or "auto", int(ranks or 1))
            records.append(record)
            print(row(record), flush=True)
    if args.json:
        args.json.write_text(json.dumps(records, indent=2))
    if args.fit:
        per_dof, per_boundary = fit(records, args.fit_from)
        print(
            f"box, least squares: {per_dof:,.0f} B per unknown, "
            f"{per_boundary:,.0f} B per boundary unknown"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
