"""Speed of a 3D run as the user meets it (issue 34): the whole `fembem solve` of a box
against an independent 3D Poisson pipeline on the same mesh.

For every size (the box [-1/4, 1/4]^3 with ``n`` cubes per side, six tetrahedra each,
(n + 1)^3 dofs, its bottom face the Signorini face; the carstensen material, f = 1,
t0 = -1, u0 = 0.02 x; tol 1e-8, plots and XDMF on, nested iteration on, one rank) it
runs, each in its own process:

- ``fembem solve``: the process wall, the stage timings of its summary.json and the peak
  resident memory (ru_maxrss of the child);
- a Poisson pipeline (bench/speed.py's, in 3D): dolfinx ``create_box`` with the same cells,
  P1 stiffness and load assembly, CG + GAMG to rtol 1e-8 (its process wall; the parts
  timed inside).

Printed: the ratio of the two walls (targets: <= 6 at 64^3 cells, <= 4 at 128^3), the
bytes per dof (target <= 4 KB at the largest size) and the stage table. No assertions:
the numbers go to docs/design/three_dimensions.md.

    .venv/bin/python bench/solid.py [--sizes 16,32,64] [--json FILE]
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

if __package__ in (None, ""):  # run as a script: the repository's root on the path
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.speed import run_poisson, run_solve  # noqa: E402

DEFAULT_SIZES = (16, 32, 64)
#: Whole run over the Poisson pipeline, by cubes per side (issue 34).
TARGETS = {64: 6.0, 128: 4.0}
TARGET_BYTES_PER_DOF = 4e3
STAGES = (
    "mesh",
    "forms",
    "steklov_poincare",
    "loads",
    "coarse_levels",
    "prolongation",
    "preconditioner",
    "step_estimate",
    "solve",
    "exterior_flux",
    "outputs",
)


def write_config(folder: Path, n: int) -> Path:
    """The benchmark's box with ``n`` cubes per side."""
    path = folder / f"box-{n}.toml"
    path.write_text(
        '[geometry]\nshape = "box"\ncenter = [0.0, 0.0, 0.0]\nwidth = 0.5\n'
        f"h = {0.5 / n!r}\n"
        'signorini = ["bottom"]\n'
        '[material]\nrho = "carstensen"\n'
        '[data]\nf = "1"\nt0 = "-1"\nu0 = "0.02*x"\n'
        "[solver]\ntol = 1e-8\n"
        "[output]\nxdmf = true\nplots = true\n"
    )
    return path


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", default=",".join(map(str, DEFAULT_SIZES)))
    parser.add_argument("--json", type=Path, help="write the records here")
    args = parser.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in (int(s) for s in args.sizes.split(",")):
            config = write_config(Path(tmp), n)
            run = run_solve(config, Path(tmp) / f"out-{n}", nested=True)
            peak = run["peak_bytes"]  # of this fembem process alone
            poisson = run_poisson(n, dim=3)
            rows.append({"n": n, "run": run, "poisson": poisson, "peak_bytes": peak})
            dofs = run.get("dofs", (n + 1) ** 3)
            ratio = run["wall"] / poisson["wall"]
            target = TARGETS.get(n)
            verdict = "" if target is None else (" met" if ratio <= target else " NOT met")
            print(
                f"n = {n}: {dofs} dofs; fembem solve {run['wall']:.1f} s "
                f"({run.get('iterations')} iterations), Poisson {poisson['wall']:.1f} s: "
                f"{ratio:.2f}x{'' if target is None else f' (target {target})'}{verdict}; "
                f"peak {peak / 1e6:.0f} MB = {peak / dofs / 1e3:.2f} KB per dof",
                flush=True,
            )
            stages = run.get("timings", {})
            print("    " + ", ".join(f"{k} {stages[k]:.1f}" for k in STAGES if k in stages))
    last = rows[-1]
    per_dof = last["peak_bytes"] / last["run"].get("dofs", (last["n"] + 1) ** 3)
    met = "met" if per_dof <= TARGET_BYTES_PER_DOF else "NOT met"
    print(f"memory at the largest size: {per_dof / 1e3:.2f} KB per dof (target 4): {met}")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=2, default=str))
    return 0


if __name__ == "__main__":
    sys.exit(main())
