"""Speed as the user meets it (issue 18): the whole `fembem solve` against an independent
Poisson pipeline on the same mesh size.

For every size (the structured square [-1/4, 1/4]^2 with ``cells`` cells per side, about
(cells + 1)^2 dofs, subdomains d = 4h, the carstensen material and the manufactured
contact case ``coupling.manufactured.square_contact`` written as [data] expressions,
tol 1e-8, plots and XDMF on, one rank) it runs, each in its own subprocess:

- for each data set (:data:`DATA_SETS`: the same f, t0, u0 written compactly, f of
  1,716 characters, or with |grad u|^2 expanded inside the material, f of 4,750), the
  cold ``fembem solve`` (``[solver] nested = false``) and the nested one: the process
  wall and the stage timings of its summary.json;
- a Poisson pipeline (``--poisson CELLS``): dolfinx ``create_rectangle`` with the cells
  of the runs' mesh (the subdomains of 4 cells may round ``cells``: 250 gives 248), P1
  stiffness and load assembly, CG + GAMG to rtol 1e-8 (the process wall; mesh,
  assembly, GAMG set-up and CG timed inside).

The ratios, measured in the same run (issue 33's targets at 10^6 and 4e6 dofs, on both
data sets): whole run / Poisson pipeline (process walls; target <= 2.0), solve stage /
Poisson solve (the stage from the assembled problem to the converged iterate:
preconditioner, step estimate, iteration and, when nested, the coarser levels and the
prolongation; against assembly + GAMG set-up + CG; target <= 1.0) and mesh stage /
Poisson mesh (target <= 1.1); and issue 18's: the outputs' share of the run (target
<= 10 %) and, nested, the Newton steps and CG iterations of the finest level (target
<= 3 and about 30); printed as met / not met for every size from 10^6 dofs on. The bare
iteration (summary.json ``solve``) over the Poisson solve is shown too, and how far the
nested answer is from the cold one and the expanded data's from the compact data's. No
assertions: the numbers go to docs/design/speed.md.

    .venv/bin/python bench/speed.py [--sizes 100,250,500,1000,2000] [--repeat 1]
                                    [--data compact,expanded] [--kinds cold,nested]
                                    [--out DIR] [--json FILE]

The 1.6e7-dof run (issue 33: at most 1 KB per dof, within 2.5x the Poisson pipeline):
``make bench-large``, i.e. ``bench/speed.py --sizes 4000 --data compact --kinds nested``
(about 10 minutes and 18 GB). Every run's peak resident memory is printed, per dof.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DEFAULT_SIZES = (100, 250, 500, 1000, 2000)
#: Stages of summary.json that make up the solve stage (from the assembled problem to
#: the converged iterate); the nested run adds its coarser levels and prolongation.
SOLVE_STAGES = ("preconditioner", "step_estimate", "solve", "coarse_levels", "prolongation")
TARGET_WHOLE, TARGET_SOLVE, TARGET_MESH = 2.0, 1.0, 1.1
#: From this many dofs on (the 1.6e7 run): whole run <= 2.5x the Poisson pipeline and at
#: most 1 KB of peak memory per dof.
LARGE, TARGET_LARGE_WHOLE, TARGET_LARGE_KB = 1.5e7, 2.5, 1.0
#: The data sets: one manufactured solution, its expressions written two ways.
DATA_SETS = ("compact", "expanded")
#: The runs of each data set: a cold solve and a nested one (the default).
KINDS = ("cold", "nested")
#: The outputs stage's share of the run (summary.json ``outputs`` / ``total``), and the
#: finest level of the nested run: at most this many Newton steps and about this many
#: preconditioned CG iterations in all (issue 18).
TARGET_OUTPUTS, TARGET_FINE_STEPS, TARGET_FINE_CG = 0.10, 3, 30


def cell_sizes(parser: argparse.ArgumentParser, text: str) -> list[int]:
    """``--sizes``: the comma-separated cells per side of the square (at least 8: subdomains
    of 4 cells), or ``parser.error`` (also bench.peers)."""
    try:
        sizes = [int(s) for s in text.split(",")]
    except ValueError:
        parser.error(f"--sizes must be comma-separated integers, got {text!r}")
    if any(s < 8 for s in sizes):
        parser.error("--sizes: at least 8 cells per side (subdomains of 4 cells)")
    return sizes


def manufactured_data(expanded: bool = False) -> dict[str, str]:
    """The [data] expressions (f, t0, u0) of ``square_contact`` with the carstensen
    material: f = -div(rho(|grad u|) grad u), t0 = (rho(|grad u|) grad u - grad u_e).n,
    u0 = u - u_e + g* (g* on the bottom side, selected by max(0, -ny); it vanishes at
    both bottom corners, where the node normal is averaged). The derivatives are taken
    by sympy; every term of u with max(0, -x) has it to the third power, so in its first
    and second derivatives each Heaviside factor multiplies a positive power of
    max(0, -x) (set to 1) and each DiracDelta factor a square of it (set to 0).

    ``expanded``: |grad u|^2 is expanded before it enters rho, as a user writing the
    flux out by hand might: the same functions in longer text (f 4,750 characters
    against 1,716, t0 1,596 against 826)."""
    import sympy

    from coupling.manufactured import square_contact
    from fem_py.forms import make_material, parse_expression

    sol = square_contact()
    x, y, nx, ny = sympy.symbols("x y nx ny", real=True)
    env = {"x": x, "y": y}
    u = parse_expression(sol.u, env, backend="sympy")
    ue = parse_expression(sol.ue, env, backend="sympy")
    gap = parse_expression(sol.arcs[0].gap, env, backend="sympy")
    rho = make_material("carstensen").rho_sym

    def clean(expr):
        expr = expr.replace(sympy.DiracDelta, lambda *a: 0)
        return expr.replace(sympy.Heaviside, lambda *a: 1)

    ux, uy = clean(sympy.diff(u, x)), clean(sympy.diff(u, y))
    norm2 = sympy.expand(ux**2 + uy**2) if expanded else ux ** 2 + uy**2
    factor = rho.subs(rho.free_symbols.pop(), sympy.sqrt(norm2))
    qx, qy = factor * ux, factor * uy
    f = -(clean(sympy.diff(qx, x)) + clean(sympy.diff(qy, y)))
    t0 = (qx - sympy.diff(ue, x)) * nx + (qy - sympy.diff(ue, y)) * ny
    u0 = u - ue + gap * sympy.Max(0, -ny)

    def text(expr) -> str:
        return str(expr).replace("Max(", "max(")

    return {"f": text(f), "t0": text(t0), "u0": text(u0), "a": sol.a}


def write_config(folder: Path, cells: int, data: dict[str, str], name: str = "") -> Path:
    """The configuration of the benchmark's square with ``cells`` cells per side."""
    h = 0.5 / cells
    path = folder / f"square-{cells}{'-' + name if name else ''}.toml"
    path.write_text(
        "[geometry]\n"
        'shape = "square"\n'
        f"h = {h!r}\nsubdomain_size = {4 * h!r}\nstructured = true\n"
        'signorini = ["bottom"]\n'
        '[material]\nrho = "carstensen"\n'
        "[data]\n"
        f"f = {json.dumps(data['f'])}\nt0 = {json.dumps(data['t0'])}\n"
        f"u0 = {json.dumps(data['u0'])}\na = {data['a']!r}\n"
        '[solver]\nmethod = "ssn"\ntol = 1e-8\n'
        "[output]\nxdmf = true\nplots = true\n"
    )
    return path


def _env() -> dict[str, str]:
    return dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")


def _measured(cmd: list[str]) -> tuple[int, str, str, float, int]:
    """Run ``cmd``: (exit status, its output, its error output, the process wall in
    seconds, its peak resident memory in bytes: ru_maxrss of this child alone, from
    ``os.wait4``; the output goes through files, so no pipe can fill)."""
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        tic = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=out, stderr=err, text=True, env=_env())
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - tic
        proc.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        return proc.returncode, out.read(), err.read(), wall, usage.ru_maxrss * 1024


def run_solve(config: Path, out: Path, nested: bool) -> dict:
    """One ``fembem solve`` process: its wall time, peak memory and summary.json."""
    fembem = Path(sys.executable).parent / "fembem"
    cmd = [str(fembem), "solve", str(config), "--out", str(out), "--quiet", "--force"]
    cmd += ["--set", f"solver.nested={'true' if nested else 'false'}"]
    status, _, err, wall, peak = _measured(cmd)
    if status != 0:
        return {"wall": wall, "peak_bytes": peak, "error": err.strip().splitlines()[-1:]}
    summary = json.loads((out / "summary.json").read_text())
    timings = summary["timings"]
    return {
        "wall": wall,
        "peak_bytes": peak,
        "dofs": summary["dofs"],
        "converged": summary["converged"],
        "iterations": summary["iterations"],
        "timings": timings,
        "solve_stage": sum(timings.get(k, 0.0) for k in SOLVE_STAGES),
        "levels": summary.get("levels"),
        "fields": str(out / "fields.npz"),
    }


def run_poisson(cells: int, dim: int = 2) -> dict:
    """The Poisson pipeline (:func:`poisson_pipeline`) in its own process: wall time and its
    inner timings."""
    cmd = [sys.executable, str(Path(__file__).resolve()), "--poisson", str(cells)]
    cmd += ["--poisson-dim", str(dim)]
    return run_child(cmd, "Poisson pipeline")


def run_child(cmd: list[str], what: str) -> dict:
    """A pipeline's child process ``cmd``: its wall time, its peak memory and the JSON
    record it prints last; a RuntimeError naming ``what`` if it fails."""
    status, out, err, wall, peak = _measured(cmd)
    if status != 0:
        raise RuntimeError(f"the {what} failed: {err.strip().splitlines()[-1:]}")
    return {"wall": wall, "peak_bytes": peak, **json.loads(out.strip().splitlines()[-1])}


def poisson_pipeline(cells: int, dim: int = 2) -> dict:
    """-Laplace w = 1 in the square [-1/4, 1/4]^2 (dim 3: the box [-1/4, 1/4]^3, six
    tetrahedra per cube), w = 0 on its boundary: mesh (create_rectangle, create_box), P1
    assembly (stiffness and load), CG + GAMG to rtol 1e-8; the seconds of each part."""

    def forms(domain):
        import ufl
        from dolfinx import fem
        from petsc4py import PETSc

        V = fem.FunctionSpace(domain, ("Lagrange", 1))
        w, v = ufl.TrialFunction(V), ufl.TestFunction(V)
        load = fem.Constant(domain, PETSc.ScalarType(1.0))
        return V, ufl.inner(ufl.grad(w), ufl.grad(v)) * ufl.dx, load * v * ufl.dx, None

    return linear_pipeline(cells, dim, forms)


def linear_pipeline(cells: int, dim: int, forms) -> dict:
    """A linear problem on the square [-1/4, 1/4]^2 (dim 3: the box, six tetrahedra per
    cube) with ``cells`` cells per side, zero on its boundary: ``forms(mesh)`` gives the
    space, the bilinear and linear UFL forms and a near-nullspace builder for GAMG (or
    None); mesh, assembly, CG + GAMG to rtol 1e-8; the seconds of each part."""
    tic = time.perf_counter()
    import dolfinx.fem.petsc  # noqa: F401 - fem.petsc
    import numpy as np
    from dolfinx import fem, mesh
    from mpi4py import MPI
    from petsc4py import PETSc

    imports = time.perf_counter() - tic
    comm = MPI.COMM_WORLD
    times = {"imports": imports}
    tic = time.perf_counter()
    corners = [np.full(dim, -0.25), np.full(dim, 0.25)]
    if dim == 2:
        domain = mesh.create_rectangle(comm, corners, [cells, cells])
    else:
        domain = mesh.create_box(comm, corners, [cells] * 3, mesh.CellType.tetrahedron)
    times["mesh"] = time.perf_counter() - tic
    tic = time.perf_counter()
    V, a_form, L_form, near_nullspace = forms(domain)
    a, L = fem.form(a_form), fem.form(L_form)
    domain.topology.create_connectivity(dim - 1, dim)
    facets = mesh.exterior_facet_indices(domain.topology)
    zero = np.zeros(V.dofmap.index_map_bs, dtype=PETSc.ScalarType)
    dofs = fem.locate_dofs_topological(V, dim - 1, facets)
    bc = fem.dirichletbc(zero if len(zero) > 1 else zero[0], dofs, V)
    times["forms"] = time.perf_counter() - tic
    tic = time.perf_counter()
    A = fem.petsc.assemble_matrix(a, bcs=[bc])
    A.assemble()
    b = fem.petsc.assemble_vector(L)
    fem.petsc.apply_lifting(b, [a], [[bc]])
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    fem.petsc.set_bc(b, [bc])
    times["assembly"] = time.perf_counter() - tic
    tic = time.perf_counter()
    if near_nullspace is not None:
        A.setNearNullSpace(PETSc.NullSpace().create(vectors=near_nullspace(V), comm=comm))
    ksp = PETSc.KSP().create(comm)
    ksp.setOperators(A)
    ksp.setType("cg")
    ksp.getPC().setType("gamg")
    ksp.setTolerances(rtol=1e-8)
    ksp.setUp()
    times["gamg_setup"] = time.perf_counter() - tic
    tic = time.perf_counter()
    x = A.createVecRight()
    ksp.solve(b, x)
    times["cg"] = time.perf_counter() - tic
    times["cg_iterations"] = ksp.getIterationNumber()
    times["converged"] = ksp.getConvergedReason() > 0
    times["dofs"] = V.dofmap.index_map.size_global * V.dofmap.index_map_bs
    times["solve"] = times["assembly"] + times["gamg_setup"] + times["cg"]
    return times


def measure(
    sizes: list[int],
    folder: Path,
    log,
    repeat: int = 1,
    data_sets: tuple[str, ...] = DATA_SETS,
    kinds: tuple[str, ...] = KINDS,
) -> list[dict]:
    """Every size: for each data set the ``fembem solve`` of each of ``kinds`` (cold,
    nested), then the Poisson pipeline, ``repeat`` times in turn; each kept at its
    fastest run (process wall; the machine is shared, and other load only ever adds
    time)."""
    data = {name: manufactured_data(expanded=name == "expanded") for name in data_sets}
    rows = []
    for cells in sizes:
        configs = {name: write_config(folder, cells, data[name], name) for name in data_sets}
        best: dict[str, dict] = {}
        walls: dict[str, list[float]] = {}

        def keep(key: str, run: dict) -> None:
            walls.setdefault(key, []).append(run["wall"])
            if key not in best or ("error" not in run and run["wall"] < best[key]["wall"]):
                best[key] = run

        for attempt in range(repeat):
            for name in data_sets:
                for kind in kinds:
                    out = folder / f"out-{cells}-{name}-{kind}-{attempt}"
                    run = run_solve(configs[name], out, kind == "nested")
                    log(f"cells = {cells}: fembem solve ({name}, {kind}) {run['wall']:.1f} s")
                    keep(f"{name} {kind}", run)
            # the same mesh size: the subdomains may round the cells
            dofs = next((r["dofs"] for r in best.values() if "dofs" in r), (cells + 1) ** 2)
            side = math.isqrt(dofs) - 1
            poisson = run_poisson(side)
            log(f"cells = {side}: Poisson pipeline {poisson['wall']:.1f} s")
            keep("poisson", poisson)
        poisson = best.pop("poisson")
        rows.append({"cells": cells, "poisson": poisson, "runs": best, "walls": walls})
        rows[-1]["load"] = os.getloadavg()[0]
        _compare(rows[-1], data_sets)
    return rows


def _compare(row: dict, data_sets: tuple[str, ...]) -> None:
    """The largest nodal differences relative to max |u|: nested - cold for each data
    set, and between the data sets' cold runs (the same functions: round-off apart)."""
    import numpy as np

    def u(key: str):
        run = row["runs"].get(key, {})
        return np.load(run["fields"])["u"] if "fields" in run else None

    pairs = [(f"{n} nested", f"{n} cold") for n in data_sets]
    pairs += [(f"{n} cold", f"{data_sets[0]} cold") for n in data_sets[1:]]
    row["differences"] = {}
    for a, b in pairs:
        ua, ub = u(a), u(b)
        if ua is not None and ub is not None:
            row["differences"][f"{a} - {b}"] = float(np.abs(ua - ub).max() / np.abs(ub).max())


def _runs(rows: list[dict]):
    """(the Poisson record, the run's name, the run's record) of every run of ``rows``."""
    for row in rows:
        for key, run in row["runs"].items():
            yield row["poisson"], key, run


def table(rows: list[dict]) -> list[str]:
    """The markdown table of the stage timings and the ratios (one row per run)."""
    stages = ("startup", "mesh", "forms", "steklov_poincare", "loads", "preconditioner")
    stages += ("step_estimate", "coarse_levels", "solve", "exterior_flux", "estimator")
    stages += ("outputs", "total")
    head = (
        "| N | run | its | wall [s] | "
        + " | ".join(stages)
        + " | solve stage | Poisson wall [s] | Poisson solve [s] | whole / Poisson "
        "| solve stage / Poisson solve | mesh / Poisson mesh | iteration / Poisson solve "
        "| peak [MB] | KB per dof | Poisson KB per dof |"
    )
    lines = [head, "|" + "---:|" * (len(stages) + 15)]
    for p, key, r in _runs(rows):
        if "error" in r:
            lines.append(f"| {p['dofs']} | {key} | error: {' '.join(r['error'])} |")
            continue
        t = r["timings"]
        its = str(r["iterations"])
        if r.get("levels"):
            its = " / ".join(str(lv["iterations"]) for lv in r["levels"])
        cells = " | ".join(f"{t[s]:.1f}" if s in t else "-" for s in stages)
        lines.append(
            f"| {r['dofs']} | {key} | {its} | {r['wall']:.1f} | {cells} "
            f"| {r['solve_stage']:.1f} | {p['wall']:.1f} | {p['solve']:.1f} "
            f"| {r['wall'] / p['wall']:.2f} | {r['solve_stage'] / p['solve']:.2f} "
            f"| {t['mesh'] / p['mesh']:.2f} | {t['solve'] / p['solve']:.2f} "
            f"| {r['peak_bytes'] / 1e6:.0f} | {r['peak_bytes'] / r['dofs'] / 1e3:.2f} "
            f"| {p['peak_bytes'] / p['dofs'] / 1e3:.2f} |"
        )
    return lines


def poisson_table(rows: list[dict]) -> list[str]:
    lines = [
        "| N | process wall [s] | imports | mesh | forms | assembly | GAMG set-up | CG | CG its |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for row in rows:
        p = row["poisson"]
        lines.append(
            f"| {p['dofs']} | {p['wall']:.1f} | {p['imports']:.1f} | {p['mesh']:.1f} "
            f"| {p['forms']:.1f} | {p['assembly']:.2f} | {p['gamg_setup']:.2f} "
            f"| {p['cg']:.2f} | {p['cg_iterations']} |"
        )
    return lines


def _verdict(ok: bool) -> str:
    return f"**{'met' if ok else 'not met'}**"


def targets(rows: list[dict]) -> list[str]:
    """The targets at each size from 10^6 dofs on: whole run, solve stage and mesh
    against the Poisson pipeline, the outputs' share of the run and, for the nested run,
    the Newton steps and CG iterations of its finest level."""
    lines = []
    big = [r for r in rows if r["poisson"]["dofs"] >= 1e6]
    if not big:
        return ["Targets: not measured (no size with 10^6 dofs or more in this run)."]
    for p, key, r in _runs(big):
        if "error" in r:
            lines.append(f"- N = {p['dofs']}, {key}: the run failed")
            continue
        whole, solve = r["wall"] / p["wall"], r["solve_stage"] / p["solve"]
        mesh = r["timings"]["mesh"] / p["mesh"]
        if r["dofs"] >= LARGE:
            kb = r["peak_bytes"] / r["dofs"] / 1e3
            lines.append(
                f"- N = {r['dofs']}, {key}: whole run / Poisson pipeline = {whole:.2f} "
                f"(target <= {TARGET_LARGE_WHOLE}): {_verdict(whole <= TARGET_LARGE_WHOLE)}; "
                f"peak {kb:.2f} KB per dof (target <= {TARGET_LARGE_KB}): "
                f"{_verdict(kb <= TARGET_LARGE_KB)}"
            )
            continue
        share = r["timings"]["outputs"] / r["timings"]["total"]
        line = (
            f"- N = {r['dofs']}, {key}: whole run / Poisson pipeline = {whole:.2f} "
            f"(target <= {TARGET_WHOLE}): {_verdict(whole <= TARGET_WHOLE)}; solve stage "
            f"/ Poisson solve = {solve:.2f} (target <= {TARGET_SOLVE}): "
            f"{_verdict(solve <= TARGET_SOLVE)}; mesh / Poisson mesh = {mesh:.2f} (target "
            f"<= {TARGET_MESH}): {_verdict(mesh <= TARGET_MESH)}; outputs "
            f"{100 * share:.1f} % of the run "
            f"(target <= {100 * TARGET_OUTPUTS:.0f} %): {_verdict(share <= TARGET_OUTPUTS)}"
        )
        if r.get("levels"):
            fine = r["levels"][-1]
            steps, cg = fine["iterations"], fine["cg_iterations"]
            ok = steps <= TARGET_FINE_STEPS and cg <= TARGET_FINE_CG
            line += (
                f"; finest level {steps} Newton steps, {cg} CG iterations (target <= "
                f"{TARGET_FINE_STEPS}, about {TARGET_FINE_CG}): {_verdict(ok)}"
            )
        lines.append(line)
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--sizes",
        default=",".join(map(str, DEFAULT_SIZES)),
        help="comma-separated cells per side (N ~ (cells + 1)^2; default "
        f"{','.join(map(str, DEFAULT_SIZES))}: 1e4 .. 4e6 dofs)",
    )
    parser.add_argument(
        "--repeat",
        type=int,
        default=1,
        help="runs of each measurement, the fastest kept (default 1)",
    )
    parser.add_argument(
        "--data",
        default=",".join(DATA_SETS),
        help=f"comma-separated data sets of {DATA_SETS} (default: both)",
    )
    parser.add_argument(
        "--kinds",
        default=",".join(KINDS),
        help=f"comma-separated runs of {KINDS} (default: both)",
    )
    parser.add_argument("--out", help="folder of the runs' outputs (default: a temporary one)")
    parser.add_argument("--json", metavar="FILE", help="write the raw records to FILE")
    parser.add_argument("--poisson", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--poisson-dim", type=int, default=2, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.poisson:
        print(json.dumps(poisson_pipeline(args.poisson, args.poisson_dim)))
        return 0
    sizes = cell_sizes(parser, args.sizes)

    def names(option: str, text: str, allowed: tuple[str, ...]) -> tuple[str, ...]:
        chosen = tuple(text.split(","))
        if not set(chosen) <= set(allowed):
            parser.error(f"--{option}: comma-separated names of {allowed}, got {text!r}")
        return chosen

    data_sets, kinds = names("data", args.data, DATA_SETS), names("kinds", args.kinds, KINDS)

    def log(message: str) -> None:
        print(message, file=sys.stderr, flush=True)

    load, started = os.getloadavg(), time.strftime("%Y-%m-%d %H:%M")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(args.out) if args.out else Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        rows = measure(sizes, folder, log, max(args.repeat, 1), data_sets, kinds)
    print(
        f"Started {started} at load average {load[0]:.1f} (1 min), {load[2]:.1f} (15 min); "
        f"finished {time.strftime('%Y-%m-%d %H:%M')}; {os.cpu_count()} cores\n"
    )
    print("\n".join(table(rows)))
    print()
    print("\n".join(poisson_table(rows)))
    print()
    for row in rows:
        walls = "; ".join(
            f"{k} " + ", ".join(f"{w:.1f}" for w in v) for k, v in row["walls"].items()
        )
        print(
            f"- N = {row['poisson']['dofs']}: process walls of every run [s]: {walls}; "
            f"load average {row['load']:.1f} after the last"
        )
    for row in rows:
        for pair, du in row["differences"].items():
            print(f"- N = {row['poisson']['dofs']}: {pair}, max |du| / max |u| = {du:.1e}")
    print()
    print("\n".join(targets(rows)))
    if args.json:
        Path(args.json).write_text(json.dumps({"load": load, "rows": rows}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
