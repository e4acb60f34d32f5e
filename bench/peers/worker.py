"""The worker process of the peer benchmark: every solver on one mesh size, each in its
own window for wall time and peak memory; one JSON record per solve on stdout."""
from __future__ import annotations

import ctypes
import gc
import json
import resource
import time
from typing import Any, Callable

import numpy as np

from bench.peers.solvers import (
    BY_NAME,
    DEEP_MIN_DOFS,
    NEWTON_TOL,
    PROBLEMS,
    TOL_PHI,
    TOL_U,
    Solver,
)

RECORD = "@@record "


def _status_kb(key: str) -> float:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith(key + ":"):
                return float(line.split()[1])
    raise KeyError(key)


class MemoryWindow:
    """Peak resident memory of a code section: VmHWM after resetting it (Linux >= 4.0)
    to the current RSS; falls back to the process-wide ru_maxrss elsewhere."""

    def __enter__(self) -> "MemoryWindow":
        # hand memory freed by earlier solvers back to the OS first, so that the
        # baseline is the live memory and the increase is this solver's own
        gc.collect()
        try:
            ctypes.CDLL("libc.so.6").malloc_trim(0)
        except (OSError, AttributeError):
            pass
        try:
            with open("/proc/self/clear_refs", "w") as fh:
                fh.write("5")
            self.base = _status_kb("VmRSS") / 1024
            self.exact = True
        except OSError:
            self.base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
            self.exact = False
        return self

    def __exit__(self, *exc) -> None:
        peak = (
            _status_kb("VmHWM")
            if self.exact
            else resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        ) / 1024
        self.peak, self.delta = peak, max(peak - self.base, 0.0)


def _measured(result: Any, memory: MemoryWindow) -> dict[str, Any]:
    """The fields of a solve's record from its result and its memory window."""
    return dict(
        converged=bool(result.converged),
        reason=result.reason,
        iterations=result.iterations,
        linear_iterations=result.linear_iterations,
        setup=result.setup,
        solve=result.solve,
        total=result.setup + result.solve,
        peak_mb=memory.peak,
        delta_mb=memory.delta,
        exact_memory=memory.exact,
    )


def _relative(a: np.ndarray, b: np.ndarray) -> float:
    scale = np.linalg.norm(b)
    return float(np.linalg.norm(a - b) / scale) if scale > 0 else float(np.linalg.norm(a))


def _coarser_levels(
    problem, cells: int, hierarchy: str, data: Callable[[Any], dict[str, Any]]
) -> list[Callable[[], Any]]:
    """Builders of the coarser levels of the benchmark's square for a grid-sequenced
    peer, coarsest first, from :func:`coupling.app.from_config.coarser_configs`:
    ``nested`` h doubled with the subdomains d = 4h kept (one coarser level at 2h: the
    peer's fastest hierarchy, 18.4 s at 10^6 against 38.9 s on the 4h levels of
    ``[solver] nested``, docs/design/baselines.md), ``deep`` h doubled down to
    DEEP_MIN_DOFS dofs (on 2 x 2 subdomains); ``data(mesh)`` gives f, t0, u0, a on a level's mesh.
    """
    from coupling.app.config import parse_config
    from coupling.app.from_config import coarser_configs, domain_from_config
    from coupling.manufactured import square_contact
    from coupling.problem import SignoriniProblem

    shape = square_contact()
    h = shape.width / cells
    d = 4 * h if hierarchy == "nested" else shape.width / 2
    config = parse_config(
        {
            "geometry": {
                "shape": shape.shape,
                "h": h,
                "subdomain_size": d,
                "center": list(shape.center),
                "width": shape.width,
                "structured": True,
                "signorini": [[list(a), list(b)] for a, b in shape.signorini],
            }
        }
    )
    dofs = problem.V.dofmap.index_map.size_global
    if hierarchy == "nested":
        levels = coarser_configs(config, dofs, coarsening=2, keep_subdomains=True)
    else:
        levels = coarser_configs(config, dofs, coarsening=2, min_dofs=DEEP_MIN_DOFS)

    def builder(level_config: dict) -> Callable[[], Any]:
        def build():
            domain = domain_from_config(problem.comm, level_config)
            values = data(domain.mesh)
            return SignoriniProblem(
                domain,
                problem.material,
                f=values["f"],
                u0=values["u0"],
                t0=values["t0"],
                a=values["a"],
                boundary_operator=problem.boundary_operator,
            )

        return build

    return [builder(c) for c in levels]


def _run_one(solver: Solver, problem, budget: float, reference, coarser=None) -> Any:
    from bench.peers import baselines

    if solver.budget is not None:
        budget = min(budget, solver.budget)
    opts = dict(solver.options)
    if solver.kind == "project":
        return baselines.solve_project(problem, opts.pop("method"), budget=budget, **opts)
    if solver.kind == "snes":
        return baselines.solve_snes_vi(problem, rtol=NEWTON_TOL, budget=budget, **opts)
    if solver.kind == "snes-sequenced":
        levels = coarser(opts.pop("hierarchy"))
        return baselines.solve_snes_vi_sequenced(
            problem, levels, rtol=NEWTON_TOL, budget=budget, **opts
        )
    if solver.kind == "tao":
        stop = None
        if opts.pop("oracle", False) and reference is not None:
            u_ref, phi_ref = reference

            def stop(u, phi):  # the accuracy test of the benchmark, as a stopping rule
                return _relative(u, u_ref) <= TOL_U and _relative(phi, phi_ref) <= TOL_PHI

        return baselines.solve_tao(
            problem, opts.pop("kind"), gttol=NEWTON_TOL, budget=budget, stop=stop, **opts
        )
    raise ValueError(f"unknown solver kind {solver.kind!r}")


def _profile_pgpm(problem, u: np.ndarray, phi: np.ndarray, repeat: int = 5) -> dict[str, float]:
    """Wall time of the parts of one PGPM iteration at the state (u, phi) [s]: the best
    of ``repeat`` calls each (the least disturbed by other load), with the B and the
    projection of PGPM's solve (default options, built here)."""
    from dolfinx import fem

    from coupling.options import SolverOptions
    from coupling.preconditioners import build_preconditioner
    from coupling.solvers.solution import build_projection
    from coupling.timing import best_of

    def best(fn) -> float:
        return best_of(fn, repeat)

    options = SolverOptions(flux_space=problem.flux_space, jacobian=problem.jacobian)
    f, pre = problem.functional, build_preconditioner(problem, options)
    projection = build_projection(pre, options)
    u_fun = fem.Function(problem.V)
    u_fun.x.array[:] = u
    grad = problem.forms.create_vector()
    g_u = np.ones(u.size)
    g_phi = np.ones(phi.size)
    parts = {
        "residual assembly DG(u)": best(lambda: problem.forms.assemble_residual(u_fun, grad)),
        "energy assembly G(u)": best(lambda: problem.forms.energy(u_fun)),
        "S_h product (+ trace T u)": best(lambda: f.S @ f.boundary_block(u_fun.vector, phi)),
        "B_Omega^-1 (local solves, edges, coarse)": best(lambda: pre.apply_omega(g_u)),
        "M_s^-1": best(lambda: pre.apply_signorini(g_phi)),
        "projection (exact)": best(lambda: projection(phi - 1e-3 * g_phi, phi)),
    }
    grad.destroy()
    pre.destroy()
    return parts


def worker(spec: dict[str, Any]) -> None:
    """Run the solvers of one mesh size; print one JSON record per solve."""
    from mpi4py import MPI

    from bench.peers import baselines
    from coupling.manufactured import square_contact
    from coupling.problem import SignoriniProblem
    from fem_py.forms import make_material
    from fem_py.mesh import GeometrySpec, build_domain

    comm = MPI.COMM_WORLD
    cells, budget = int(spec["cells"]), float(spec["budget"])

    def emit(record: dict[str, Any]) -> None:
        print(RECORD + json.dumps(record), flush=True)

    manufactured = square_contact()
    h = manufactured.width / cells
    tic = time.perf_counter()
    domain = build_domain(
        comm,
        GeometrySpec(
            manufactured.shape,
            h=h,
            subdomain_size=4 * h,
            center=manufactured.center,
            width=manufactured.width,
            signorini=manufactured.signorini,
            structured=True,
        ),
    )
    mesh_time = time.perf_counter() - tic
    material = make_material("carstensen")

    base = {"cells": cells}
    for name, solver_names in spec["jobs"].items():
        tic = time.perf_counter()

        def data_on(mesh, name=name):
            if name == "manufactured":
                return manufactured.data(mesh, material)
            return {k: PROBLEMS[name][k] for k in ("f", "t0", "u0", "a")}

        data = data_on(domain.mesh)
        # the shared set-up: forms, S_h, loads (every solver builds its own B); the dense
        # S_h at every size, as the PETSc peers assemble it into their Hessian
        problem = SignoriniProblem(
            domain,
            material,
            f=data["f"],
            u0=data["u0"],
            t0=data["t0"],
            a=data["a"],
            boundary_operator="dense",
        )
        shared = time.perf_counter() - tic
        info = {
            **base,
            "problem": name,
            "dofs": problem.V.dofmap.index_map.size_global,
            "n_gamma": problem.boundary.n_gamma,
            "n_signorini": problem.n_signorini,
        }
        emit(
            {
                **info,
                "type": "setup",
                "mesh": mesh_time,
                "shared": shared,
                "timings": dict(problem.timings),
            }
        )
        reference = None

        def coarser(hierarchy: str, data_on=data_on) -> list[Callable[[], Any]]:
            return _coarser_levels(problem, cells, hierarchy, data_on)

        for solver in (BY_NAME[n] for n in solver_names):
            record = {**info, "type": "solve", "solver": solver.name}
            try:
                with MemoryWindow() as memory:
                    result = _run_one(solver, problem, budget, reference, coarser)
            except Exception as err:  # reported, never dropped
                emit(
                    {
                        **record,
                        "converged": False,
                        "status": "error",
                        "reason": f"{type(err).__name__}: {err}",
                    }
                )
                continue
            record.update(
                _measured(result, memory), evaluations=result.evaluations, details=result.details
            )
            if solver.name == "ssn" and reference is None and result.converged:
                # PGPM skipped on this mesh: the default method is the reference
                reference, record["reference"] = (result.u, result.phi), True
            if solver.name == "pgpm":
                reference = (result.u, result.phi)
                if spec.get("profile"):
                    parts = _profile_pgpm(problem, result.u, result.phi)
                    record["profile"] = {
                        **parts,
                        "one PGPM iteration (measured)": result.solve / max(result.iterations, 1),
                    }
            if reference is not None:
                record["du"] = _relative(result.u, reference[0])
                record["dphi"] = _relative(result.phi, reference[1])
            emit(record)
    if spec["poisson"]:
        record = {
            **base,
            "type": "solve",
            "problem": "poisson",
            "solver": "poisson",
            "dofs": domain.mesh.topology.index_map(0).size_global,
        }
        from fem_py.boundary import BoundaryMap
        from fem_py.dofs import p1_space

        V = p1_space(domain.mesh)
        boundary = BoundaryMap(V, domain)
        with MemoryWindow() as memory:
            result = baselines.poisson_yardstick(V, boundary.dofs)
        record.update(_measured(result, memory), dofs=V.dofmap.index_map.size_global)
        emit(record)
