"""DOLFINx's ``create_mesh`` against a topology made directly from cells already on their
rank (issue 33; docs/design/parallel.md, "The ninth session").

The structured mesh's cells are written on the rank that owns them
(``fem_py.mesh.structured``), yet DOLFINx 0.5.2's ``create_mesh`` still calls the
partitioner, sends every cell to its rank (itself), builds the dual graph and reorders
the cells before it makes the topology. Its Python layer does not expose
``create_topology`` and ``create_geometry``; the probe ``bench/direct_topology/`` (a
pybind11 module against libdolfinx, built here with CMake into a temporary directory)
calls them on the cells as given.

For each size, the unit square of ``cells`` x ``cells`` squares cut into 2 triangles is
made both ways, each in a fresh process, alternating, ``--repeat`` times; the fastest of
each is printed, with the area and the integral of x^2 + y on both meshes (equal to
round-off: the same mesh). One rank, no ghost cells: what the direct path would save on
the project's one-rank pipeline, not a replacement for it.

    .venv/bin/python bench/direct_topology.py [--cells 1000 2000] [--repeat 2]
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
SOURCE = HERE / "direct_topology"
PATHS = ("create_mesh", "direct")


def build(into: Path) -> Path:
    """Configure and build the probe module in ``into``; its directory (exit on failure)."""
    import pybind11

    configure = ["cmake", "-S", str(SOURCE), "-B", str(into), "-DCMAKE_BUILD_TYPE=Release"]
    configure += [f"-DPython3_EXECUTABLE={sys.executable}"]  # the one that sees mpi4py
    configure += [f"-Dpybind11_DIR={pybind11.get_cmake_dir()}"]
    for cmd in (
        configure,
        ["cmake", "--build", str(into), "-j2"],
    ):
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            sys.exit(f"error: building the probe failed:\n{(proc.stdout + proc.stderr)[-2000:]}")
    return into


def worker(cells: int, path: str, module_dir: str) -> None:
    """Make the mesh one way, time it, and print the time and two integrals over it."""
    import numpy as np
    import ufl
    from dolfinx import cpp, fem
    from dolfinx import mesh as dmesh
    from mpi4py import MPI

    comm = MPI.COMM_SELF
    i, j = (a.ravel() for a in np.meshgrid(np.arange(cells), np.arange(cells), indexing="ij"))
    corner = i * (cells + 1) + j  # nodes row by row, (cells + 1)^2 of them
    triangles = np.empty((2 * cells * cells, 3), dtype=np.int64)
    triangles[0::2] = np.stack([corner, corner + 1, corner + cells + 2], axis=1)
    triangles[1::2] = np.stack([corner, corner + cells + 2, corner + cells + 1], axis=1)
    axis = np.linspace(0.0, 1.0, cells + 1)
    x = np.stack([c.ravel() for c in np.meshgrid(axis, axis, indexing="ij")], axis=1)
    domain = ufl.Mesh(ufl.VectorElement("Lagrange", ufl.triangle, 1))

    tic = time.perf_counter()
    if path == "create_mesh":

        def partitioner(comm_, nparts, tdim, local_cells, ghost_mode):  # every cell stays
            return cpp.graph.AdjacencyList_int32(np.zeros(len(triangles), dtype=np.int32))

        msh = dmesh.create_mesh(comm, triangles, x, domain, partitioner=partitioner)
    else:
        sys.path.insert(0, module_dir)
        import direct_topology

        msh = dmesh.Mesh(direct_topology.triangle_mesh(comm, triangles, x), domain)
    seconds = time.perf_counter() - tic

    V = fem.FunctionSpace(msh, ("Lagrange", 1))
    u = fem.Function(V)
    u.interpolate(lambda p: p[0] ** 2 + p[1])
    area = fem.assemble_scalar(fem.form(1.0 * ufl.dx(domain=msh)))
    integral = fem.assemble_scalar(fem.form(u * ufl.dx))
    print(json.dumps({"path": path, "seconds": seconds, "area": area, "integral": integral}))


def run(cells: int, path: str, module_dir: Path) -> dict:
    cmd = [sys.executable, __file__, "--worker", path, "--cells", str(cells)]
    proc = subprocess.run(cmd + ["--module-dir", str(module_dir)], capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit(f"error: the {path} run failed:\n{(proc.stdout + proc.stderr)[-2000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, nargs="+", default=[1000], help="squares a side")
    parser.add_argument("--repeat", type=int, default=2, help="runs of each path (default 2)")
    parser.add_argument("--worker", choices=PATHS, help=argparse.SUPPRESS)
    parser.add_argument("--module-dir", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if any(c < 1 for c in args.cells) or args.repeat < 1:
        print("error: --cells and --repeat must be >= 1", file=sys.stderr)
        return 2
    if args.worker:
        worker(args.cells[0], args.worker, args.module_dir)
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        module_dir = build(Path(tmp))
        print("| cells a side | triangles | create_mesh | direct | ratio | area, integral equal |")
        print("|---:|---:|---:|---:|---:|---|")
        for cells in args.cells:
            runs = {path: [] for path in PATHS}
            for _ in range(args.repeat):
                for path in PATHS:
                    runs[path].append(run(cells, path, module_dir))
            best = {path: min(r["seconds"] for r in runs[path]) for path in PATHS}
            a, b = runs["create_mesh"][0], runs["direct"][0]
            same = all(abs(a[k] - b[k]) <= 1e-12 * abs(a[k]) for k in ("area", "integral"))
            print(
                f"| {cells} | {2 * cells * cells} | {best['create_mesh']:.3f} s | "
                f"{best['direct']:.3f} s | {best['create_mesh'] / best['direct']:.2f}x | "
                f"{'yes' if same else 'NO'} |",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
