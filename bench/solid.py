"""Speed of a 3D run as the user meets it (issue 34): the whole `fembem solve` of a box
against an independent 3D Poisson pipeline on the same mesh.

For every size (the box [-1/4, 1/4]^3 with ``n`` cubes per side, six tetrahedra each,
(n + 1)^3 dofs, its bottom face the Signorini face; the carstensen material, f = 1,
t0 = -1, u0 = 0.02 x; tol 1e-8, plots and XDMF on, nested iteration on, one rank) it
runs, each in its own process:

- ``fembem solve``: the process wall, the stage timings of its summary.json and the peak
  resident memory (ru_maxrss of the child);
- a Poisson pipeline (``--poisson N``): dolfinx ``create_box`` with the same cells, P1
  stiffness and load assembly, CG + GAMG to rtol 1e-8 (its process wall; the parts timed
  inside).

Printed: the ratio of the two walls (targets: <= 6 at 64^3 cells, <= 4 at 128^3), the
bytes per dof (target <= 4 KB at the largest size) and the stage table. No assertions:
the numbers go to docs/design/three_dimensions.md.

    .venv/bin/python bench/solid.py [--sizes 16,32,64] [--json FILE]
"""
from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

if __package__ in (None, ""):  # run as a script: the repository's root on the path
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.speed import _env, run_solve  # noqa: E402

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


def poisson_pipeline(n: int) -> dict:
    """-Laplace w = 1 in the box, w = 0 on its surface: mesh (create_box), P1 assembly,
    CG + GAMG to rtol 1e-8; the seconds of each part."""
    tic = time.perf_counter()
    import dolfinx.fem.petsc  # noqa: F401 - fem.petsc
    import numpy as np
    import ufl
    from dolfinx import fem, mesh
    from mpi4py import MPI
    from petsc4py import PETSc

    times = {"imports": time.perf_counter() - tic}
    comm = MPI.COMM_WORLD
    tic = time.perf_counter()
    corners = [np.array([-0.25, -0.25, -0.25]), np.array([0.25, 0.25, 0.25])]
    domain = mesh.create_box(comm, corners, [n, n, n], mesh.CellType.tetrahedron)
    times["mesh"] = time.perf_counter() - tic
    tic = time.perf_counter()
    V = fem.FunctionSpace(domain, ("Lagrange", 1))
    w, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    a = fem.form(ufl.inner(ufl.grad(w), ufl.grad(v)) * ufl.dx)
    L = fem.form(fem.Constant(domain, PETSc.ScalarType(1.0)) * v * ufl.dx)
    domain.topology.create_connectivity(2, 3)
    facets = mesh.exterior_facet_indices(domain.topology)
    bc = fem.dirichletbc(PETSc.ScalarType(0.0), fem.locate_dofs_topological(V, 2, facets), V)
    A = fem.petsc.assemble_matrix(a, bcs=[bc])
    A.assemble()
    b = fem.petsc.assemble_vector(L)
    fem.petsc.apply_lifting(b, [a], [[bc]])
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    fem.petsc.set_bc(b, [bc])
    times["assembly"] = time.perf_counter() - tic
    tic = time.perf_counter()
    ksp = PETSc.KSP().create(comm)
    ksp.setOperators(A)
    ksp.setType("cg")
    ksp.getPC().setType("gamg")
    ksp.setTolerances(rtol=1e-8)
    x = A.createVecRight()
    ksp.solve(b, x)
    times["solve"] = time.perf_counter() - tic
    times["cg_iterations"] = ksp.getIterationNumber()
    times["dofs"] = V.dofmap.index_map.size_global
    return times


def run_poisson(n: int) -> dict:
    """The Poisson pipeline in its own process: wall time and its inner timings."""
    cmd = [sys.executable, str(Path(__file__).resolve()), "--poisson", str(n)]
    tic = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=_env(), check=True)
    return {"wall": time.perf_counter() - tic, **json.loads(proc.stdout.strip().splitlines()[-1])}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", default=",".join(map(str, DEFAULT_SIZES)))
    parser.add_argument("--json", type=Path, help="write the records here")
    parser.add_argument("--poisson", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.poisson:
        print(json.dumps(poisson_pipeline(args.poisson)))
        return 0
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in (int(s) for s in args.sizes.split(",")):
            config = write_config(Path(tmp), n)
            run = run_solve(config, Path(tmp) / f"out-{n}", nested=True)
            # the largest child so far: the sizes grow, so this one's
            peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024
            poisson = run_poisson(n)
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
