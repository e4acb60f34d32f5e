"""From a validated configuration (:class:`coupling.options.RunConfig`, made by
:mod:`coupling.app.config`) to the objects of the library: the domain, the material, the
assembled problem and the solver options."""
from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import Any

from mpi4py import MPI

from coupling.options import (
    NESTED_COARSENING,
    NESTED_COARSENING_3D,
    NESTED_MIN_DOFS,
    MaterialOptions,
    ProblemOptions,
    RunConfig,
    SolverOptions,
)
from coupling.problem import SignoriniProblem

__all__ = [
    "domain_from_config",
    "planned_size",
    "estimated_size",
    "coarser_configs",
    "kernel_of",
    "material_from_config",
    "run_material",
    "problem_on_domain",
    "problem_from_config",
]


def domain_from_config(comm: MPI.Comm, config: RunConfig) -> Any:
    """The ``fem_py.mesh.Domain`` of a validated configuration (collective)."""
    from fem_py.mesh import build_domain

    return build_domain(comm, config.geometry)


def planned_size(config: RunConfig) -> Any:
    """The ``fem_py.mesh.DomainSize`` of the configuration's domain in closed form (no
    mesh), or None when only meshing tells (a mesh file: then its existence is checked)."""
    from fem_py.mesh import domain_size

    mesh = config.geometry.mesh
    if mesh and not Path(mesh).is_file():  # before an output folder is made
        raise ValueError(
            f"mesh: file {mesh!r} not found; give the path of a gmsh .msh "
            "file (relative to the configuration file's folder)"
        )
    return domain_size(config.geometry)


def estimated_size(config: RunConfig) -> Any:
    """The ``fem_py.mesh.DomainSize`` of a generated gmsh mesh estimated before meshing
    (``fem_py.mesh.size_estimate.mesh_size_estimate``: from the area and h, the ball from
    its volume, its surface and h), or None for a mesh file (it is the size it is)."""
    from fem_py.mesh.size_estimate import mesh_size_estimate

    if config.geometry.mesh:
        return None
    return mesh_size_estimate(config.geometry)


def coarser_configs(
    config: RunConfig,
    dofs: int,
    *,
    coarsening: int | None = None,
    min_dofs: int = NESTED_MIN_DOFS,
    keep_subdomains: bool = False,
) -> list[RunConfig]:
    """The configurations of the coarser levels of a nested solve of a configuration whose
    mesh has ``dofs`` dofs, coarsest first: h multiplied by ``coarsening`` per level
    (default :data:`coupling.options.NESTED_COARSENING`; for a body
    ``NESTED_COARSENING_3D``: 4 per level, and 2 for the coarsest where 4 leaves too few
    dofs or cuts a box's cubes), the subdomain size d kept while a coarse edge keeps at
    least two segments and raised to 2 h there (d_k = max(d, 2 h_k); with
    ``keep_subdomains`` the levels stop there instead; a body has no subdomains), while the
    level has at least ``min_dofs`` dofs (estimated as dofs / factor^dim per level) and its
    geometry is valid (the levels stop at the first that is not, e.g. a Signorini arc end
    on the given subdomains' grid but not on the raised d's, or a box whose width is no
    multiple of the coarser h: the solve is then cold, never an error the fine mesh does
    not raise). No levels for a mesh file (it has no h to coarsen)."""
    from fem_py.mesh import spec_dimension

    g = config.geometry
    if g.mesh:
        return []
    dim = spec_dimension(g)
    if coarsening is not None:
        factors: tuple[int, ...] = (coarsening,)
    else:
        factors = NESTED_COARSENING_3D if dim == 3 else (NESTED_COARSENING,)

    def level(h: float) -> RunConfig | None:
        if keep_subdomains and 2 * h > g.subdomain_size:
            return None
        if dim == 3:
            geometry = dataclasses.replace(g, h=h)
        else:
            geometry = dataclasses.replace(g, h=h, subdomain_size=max(g.subdomain_size, 2 * h))
        candidate = dataclasses.replace(config, geometry=geometry)
        try:
            planned_size(candidate)  # the checks of build_domain, without a mesh
        except ValueError:
            return None
        return candidate

    levels, h, estimate = [], g.h, float(dofs)
    while True:
        for factor in factors:
            found = level(h * factor) if estimate / factor**dim >= min_dofs else None
            if found is not None:
                break
        else:
            break
        levels.append(found)
        h, estimate = h * factor, estimate / factor**dim
        if factor != factors[0]:  # the smaller step ends the hierarchy
            break
    return levels[::-1]


def kernel_of(config: RunConfig) -> str | tuple:
    """The kernel of the boundary operators of a validated configuration: Laplace's, or
    Kelvin's of its ``[exterior]`` medium for elasticity."""
    if config.problem.equation == "elasticity":
        return ("lame", config.exterior.E, config.exterior.nu)
    return "laplace"


def material_from_config(config: RunConfig, dim: int = 2) -> Any:
    """The ``fem_py.forms.Material`` of a validated configuration, or for elasticity the
    ``fem_py.forms.elasticity.ElasticMaterial`` of a ``dim``-dimensional body."""
    from fem_py.forms import make_material
    from fem_py.forms.elasticity import hencky, linear_elastic

    m = config.material
    if config.problem.equation == "elasticity":
        if m.model == "hencky":
            return hencky(m.bulk, m.shear, dim)
        return linear_elastic(m.E, m.nu, dim)
    return make_material(m.rho, p=m.p, eps=m.eps)


def run_material(folder: Path, dim: int) -> Any:
    """The body's material of the finished run whose results are in ``folder``, from the
    configuration its summary.json keeps (``fembem evaluate``'s stress of a body)."""
    import json

    summary = json.loads((Path(folder) / "summary.json").read_text())
    if "config" not in summary:
        raise ValueError(
            f"{Path(folder) / 'summary.json'} holds no configuration: the body's stress needs "
            "the run's material; solve again with this version of fembem"
        )
    stored = summary["config"]  # validated by the run, every key (RunConfig.as_dict)
    sections = {
        "problem": ProblemOptions(**stored["problem"]),
        "material": MaterialOptions(**stored["material"]),
    }
    return material_from_config(RunConfig(**sections), dim)


def _data(value: Any, components: int) -> Any:
    """A [data] value for ``components`` unknowns per node: a vector as a list; a
    default (one "0" or 0.0) repeated for every component of elasticity."""
    if isinstance(value, tuple):
        return list(value)
    return value if components == 1 else [value] * components


def problem_on_domain(
    domain: Any, config: RunConfig
) -> tuple[SignoriniProblem, SolverOptions, dict[str, float]]:
    """The assembled problem on ``domain``, the solver options and the problem's stage
    timings, for a validated configuration (collective)."""
    data, options = config.data, config.solver
    material = material_from_config(config, domain.dim)
    d = material.components
    elastic = d > 1
    problem = SignoriniProblem(
        domain,
        material,
        f=_data(data.f, d),
        u0=_data(data.u0, d),
        t0=_data(data.t0, d),
        a=_data(data.a, d),
        exterior=(config.exterior.E, config.exterior.nu) if elastic else None,
        tangential=config.problem.tangential,
        flux_space=options.flux_space,
        jacobian=options.jacobian,
        boundary_operator=options.boundary_operator,
    )
    return problem, options, dict(problem.timings)


def problem_from_config(
    comm: MPI.Comm, config: RunConfig
) -> tuple[SignoriniProblem, SolverOptions, dict[str, float]]:
    """The assembled problem, the solver options and the set-up timings (``mesh`` and the
    problem's stages) of a validated configuration (collective)."""
    tic = time.perf_counter()
    domain = domain_from_config(comm, config)
    mesh_time = time.perf_counter() - tic
    problem, options, timings = problem_on_domain(domain, config)
    return problem, options, {"mesh": mesh_time, **timings}
