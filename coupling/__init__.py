"""The coupled FEM-BEM problem with Signorini contact, its solvers, its outputs and the
application, with one public face: a script needs ``import coupling`` (and the MPI
communicator) for a first solve::

    import coupling
    from mpi4py import MPI

    spec = coupling.GeometrySpec("square", h=1 / 32, subdomain_size=1 / 8, signorini=["bottom"])
    domain = coupling.build_domain(MPI.COMM_WORLD, spec)
    problem = coupling.SignoriniProblem(domain, coupling.make_material("carstensen"), t0="-1")
    result = coupling.solve(problem, coupling.SolverOptions())

The names below are those of the modules that define them (the deep paths keep working:
``coupling.solve is coupling.solvers.solve``); each is imported on first use, so
``import coupling`` alone loads neither MPI nor DOLFINx (the figure process imports
``coupling.io`` without them).

- the geometry: :class:`GeometrySpec` (what Omega to build, ``fem_py.spec``),
  :func:`build_domain` (mesh it, collective) and :func:`domain_size` (its sizes in closed
  form), from ``fem_py.mesh``; :func:`make_material` (``fem_py.forms``);
- the problem and the options: :class:`SignoriniProblem` (``coupling.problem``),
  :class:`SolverOptions`, :class:`AdaptOptions` and :class:`RunConfig`
  (``coupling.options``, where every default is);
- the solvers: :func:`solve` (``coupling.solvers``), :func:`solve_nested`
  (``coupling.solvers.nested``), :func:`solve_adaptive` (the adaptive loop,
  ``coupling.adapt.adapt``: the subpackage ``coupling.adapt`` keeps its name) and
  :func:`estimate` (the a posteriori estimator), :func:`build_preconditioner`
  (``coupling.preconditioners``) to reuse one B over several solves;
- the outputs: :func:`prepare_output_dir` (``coupling.io.atomic``), :func:`write_outputs`
  and :func:`load_fields` (``coupling.io.outputs``), :func:`evaluate`
  (``coupling.io.evaluation``);
- the application: :func:`load_config` (a TOML file to a :class:`RunConfig`,
  ``coupling.app.config``), :func:`problem_from_config` (``coupling.app.from_config``) and
  :class:`ProgressMonitor` (``coupling.app.progress``).
"""
from __future__ import annotations

from importlib import import_module
from typing import Any

#: Public name -> (the module that defines it, its name there).
_PUBLIC: dict[str, tuple[str, str]] = {
    "GeometrySpec": ("fem_py.spec", "GeometrySpec"),
    "build_domain": ("fem_py.mesh", "build_domain"),
    "domain_size": ("fem_py.mesh", "domain_size"),
    "make_material": ("fem_py.forms", "make_material"),
    "SignoriniProblem": ("coupling.problem", "SignoriniProblem"),
    "SolverOptions": ("coupling.options", "SolverOptions"),
    "AdaptOptions": ("coupling.options", "AdaptOptions"),
    "RunConfig": ("coupling.options", "RunConfig"),
    "solve": ("coupling.solvers", "solve"),
    "solve_nested": ("coupling.solvers.nested", "solve_nested"),
    "solve_adaptive": ("coupling.adapt", "adapt"),
    "estimate": ("coupling.adapt", "estimate"),
    "build_preconditioner": ("coupling.preconditioners", "build_preconditioner"),
    "prepare_output_dir": ("coupling.io.atomic", "prepare_output_dir"),
    "write_outputs": ("coupling.io.outputs", "write_outputs"),
    "load_fields": ("coupling.io.outputs", "load_fields"),
    "evaluate": ("coupling.io.evaluation", "evaluate"),
    "load_config": ("coupling.app.config", "load_config"),
    "problem_from_config": ("coupling.app.from_config", "problem_from_config"),
    "ProgressMonitor": ("coupling.app.progress", "ProgressMonitor"),
}

__all__ = sorted(_PUBLIC)


def __getattr__(name: str) -> Any:
    """The public name ``name``, imported from its module on first use (PEP 562)."""
    try:
        module, attribute = _PUBLIC[name]
    except KeyError:
        raise AttributeError(f"module 'coupling' has no attribute {name!r}") from None
    value = getattr(import_module(module), attribute)
    globals()[name] = value  # found here from now on
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC))
