"""Speed of an elastic run as the user meets it (issue 65): the whole `fembem solve` of the
elastic problem against an independent linear elasticity pipeline on the same mesh.

For every size, each in its own process:

- ``fembem solve`` of a Hencky square [-1/4, 1/4]^2 with ``n`` cells per side (2D; bulk 2,
  mu(s) = 1 + 1/(1 + s); the medium E = 1.5, nu = 0.3; f = (1, 0), u0 = (0, 0.05 x), "slip"
  on the bottom side: part of it in contact) or of a linear elastic box with ``n`` cubes per
  side (3D; E = 2.5, nu = 0.25; the same load in 3D): the process wall, the stage timings
  of its summary.json and the peak resident memory (ru_maxrss of the child); tol 1e-8,
  figures and XDMF on, nested iteration on;
- a linear elasticity pipeline on a mesh of the same cells (dolfinx create_rectangle /
  create_box): vector P1, the stiffness and load assembled, CG + GAMG with the rigid-body
  modes as its near-nullspace to rtol 1e-8, the body clamped on its boundary (its process
  wall; the parts timed inside).

Printed: the ratio of the two walls, the bytes per dof and the stage table. No assertions:
the numbers go to docs/design/elasticity.md.

    .venv/bin/python bench/elastic.py [--dim 2] [--sizes 64,128,256] [--json FILE]
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

if __package__ in (None, ""):  # run as a script: the repository's root on the path
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.solid import STAGES  # noqa: E402
from bench.speed import linear_pipeline, run_child, run_solve  # noqa: E402

DEFAULT_SIZES = {2: (64, 128, 256), 3: (8, 16, 32)}


def write_config(folder: Path, n: int, dim: int) -> Path:
    """The benchmark's elastic run with ``n`` cells (cubes) per side."""
    path = folder / f"elastic-{dim}d-{n}.toml"
    if dim == 2:
        body = (
            '[geometry]\nshape = "square"\n'
            f"h = {0.5 / n!r}\nsubdomain_size = 0.125\n"
            'signorini = ["bottom"]\n'
            '[material]\nmodel = "hencky"\nbulk = 2.0\nshear = "1 + 1/(1 + s)"\n'
            '[data]\nf = ["1", "0"]\nu0 = ["0", "0.05*x"]\n'
        )
    else:
        body = (
            '[geometry]\nshape = "box"\nwidth = 0.5\n'
            f"h = {0.5 / n!r}\n"
            'signorini = ["bottom"]\n'
            '[material]\nmodel = "linear-elastic"\nE = 2.5\nnu = 0.25\n'
            '[data]\nf = ["1", "0", "0"]\nu0 = ["0", "0", "0.05*x"]\n'
        )
    path.write_text(
        '[problem]\nequation = "elasticity"\n'
        + body
        + "[exterior]\nE = 1.5\nnu = 0.3\n"
        + "[solver]\ntol = 1e-8\n[output]\nxdmf = true\nplots = true\n"
    )
    return path


def elasticity_pipeline(cells: int, dim: int) -> dict:
    """Linear elasticity (E = 2.5, nu = 0.25) in the square or the box [-1/4, 1/4]^d under a
    unit body force e_1, clamped on the boundary: mesh, vector P1 assembly, CG + GAMG with
    the rigid-body modes to rtol 1e-8 (``bench.speed.linear_pipeline``); the seconds of each
    part."""

    def forms(domain):
        import numpy as np
        import ufl
        from dolfinx import fem
        from petsc4py import PETSc

        from fem_py.forms.elasticity import lame_parameters, rigid_body_modes

        V = fem.VectorFunctionSpace(domain, ("Lagrange", 1))
        lam, mu = lame_parameters(2.5, 0.25)
        w, v = ufl.TrialFunction(V), ufl.TestFunction(V)
        eps = ufl.sym(ufl.grad(w))
        sigma = lam * ufl.tr(eps) * ufl.Identity(dim) + 2 * mu * eps
        load = fem.Constant(domain, np.eye(dim)[0].astype(PETSc.ScalarType))
        a = ufl.inner(sigma, ufl.sym(ufl.grad(v))) * ufl.dx
        return V, a, ufl.inner(load, v) * ufl.dx, rigid_body_modes

    return linear_pipeline(cells, dim, forms)


def run_pipeline(cells: int, dim: int) -> dict:
    """:func:`elasticity_pipeline` in its own process: wall time and its inner timings."""
    cmd = [sys.executable, str(Path(__file__).resolve()), "--pipeline", str(cells)]
    cmd += ["--dim", str(dim)]
    return run_child(cmd, "elasticity pipeline")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--dim", type=int, choices=(2, 3), default=2)
    parser.add_argument("--sizes", help="cells (cubes) per side, comma-separated")
    parser.add_argument("--json", type=Path, help="write the records here")
    parser.add_argument("--pipeline", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.pipeline is not None:  # the child process of run_pipeline
        print(json.dumps(elasticity_pipeline(args.pipeline, args.dim)))
        return 0
    sizes = args.sizes.split(",") if args.sizes else DEFAULT_SIZES[args.dim]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in (int(s) for s in sizes):
            config = write_config(Path(tmp), n, args.dim)
            run = run_solve(config, Path(tmp) / f"out-{n}", nested=True)
            pipeline = run_pipeline(n, args.dim)
            rows.append({"n": n, "run": run, "pipeline": pipeline})
            if "error" in run:
                print(f"n = {n}: fembem solve failed: {run['error']}", flush=True)
                continue
            dofs, peak = run["dofs"], run["peak_bytes"]
            ratio = run["wall"] / pipeline["wall"]
            print(
                f"n = {n}: {dofs} dofs; fembem solve {run['wall']:.1f} s "
                f"({run['iterations']} iterations), elasticity pipeline {pipeline['wall']:.1f} s"
                f" ({pipeline['cg_iterations']} CG): {ratio:.2f}x; peak {peak / 1e6:.0f} MB = "
                f"{peak / dofs / 1e3:.2f} KB per dof (pipeline "
                f"{pipeline['peak_bytes'] / pipeline['dofs'] / 1e3:.2f})",
                flush=True,
            )
            stages = run["timings"]
            print("    " + ", ".join(f"{k} {stages[k]:.1f}" for k in STAGES if k in stages))
    if args.json:
        args.json.write_text(json.dumps(rows, indent=2, default=str))
    return 0


if __name__ == "__main__":
    sys.exit(main())
