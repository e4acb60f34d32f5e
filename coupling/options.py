"""Every default and every choice of the project, stated once.

:data:`DEFAULTS` is the TOML schema of ``fembem`` (section -> key -> default; the type
of a default is the expected type), :data:`CHOICES` the keys restricted to a fixed set of
strings. The ``[geometry]`` defaults are those of :class:`fem_py.spec.GeometrySpec` (the
geometry layer's own type); every other section is a frozen dataclass here whose
defaults are read from :data:`DEFAULTS`: :class:`SolverOptions` (the one object a solve
takes, :func:`coupling.solvers.solve`), :class:`MaterialOptions`, :class:`DataOptions`,
:class:`AdaptOptions` and :class:`OutputOptions`; :class:`RunConfig` holds the six (the
application makes it once, ``coupling.app.config``). The lower layers
(preconditioners, solvers, projection) take their parameters as required arguments,
so no default is written twice.
"""
from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fem_py.spec import GeometrySpec

__all__ = [
    "DEFAULTS",
    "CHOICES",
    "DATA_VARIABLES",
    "DATA_VARIABLES_3D",
    "SolverOptions",
    "solver_options",
    "MaterialOptions",
    "ProblemOptions",
    "ExteriorOptions",
    "DataOptions",
    "AdaptOptions",
    "OutputOptions",
    "RunConfig",
    "hmatrix_tol",
    "hmatrix_tol_for",
    "parse_slice",
]


def _toml(value: Any) -> Any:
    """A default as TOML reads it (arrays are lists)."""
    return [_toml(v) for v in value] if isinstance(value, tuple) else value


#: Every key of the schema with its default value.
DEFAULTS: dict[str, dict[str, Any]] = {
    # the equation: the paper's scalar one, or elasticity (docs/method.md section 12)
    "problem": {"equation": "scalar", "tangential": "slip"},
    # the fields of GeometrySpec, but its dimension (derived from the shape or mesh file)
    "geometry": {
        f.name: _toml(f.default) for f in dataclasses.fields(GeometrySpec) if f.name != "dim"
    },
    # rho, p, eps: the scalar equation's; the others elasticity's (shear: a number or an
    # expression in s = |dev eps|)
    "material": {
        "rho": "linear",
        "p": 2.0,
        "eps": 1.0,
        "model": "linear-elastic",
        "E": 1.0,
        "nu": 0.3,
        "bulk": 1.0,
        "shear": 1.0,
    },
    # the exterior elastic medium (elasticity)
    "exterior": {"E": 1.0, "nu": 0.3},
    "data": {"f": "0", "u0": "0", "t0": "0", "a": 0.0, "exact": ""},
    "solver": {
        "method": "ssn",
        "preconditioner": "auto",
        "tol": 1e-8,
        "max_iterations": 2000,
        "step": "auto",
        "projection": "exact",
        "projection_tol": 0.5,
        "projection_max_iterations": 1000,
        "edge_form": "paper",
        "flux_space": "p1",
        "jacobian": "ufl",
        "signorini_weight": 0.25,
        "coarse_space": "auto",
        "nested": True,
        "boundary_operator": "auto",
    },
    "output": {
        "dir": "fembem-out",
        "xdmf": True,
        "plots": True,
        "estimator": False,
        "indicators": False,
        "slice": "auto",
    },
    "adapt": {"steps": 0, "theta": 0.5, "max_dofs": 200000},
}

#: The tangential condition of the elastic problem on Gamma_s (docs/method.md section 12):
#: "slip" (frictionless) or "stick" (no slip).
DEFAULT_TANGENTIAL = DEFAULTS["problem"]["tangential"]
#: The keys of [material] that belong to the scalar equation and to elasticity.
SCALAR_MATERIAL_KEYS = ("rho", "p", "eps")
ELASTIC_MATERIAL_KEYS = {
    "linear-elastic": ("model", "E", "nu"),
    "hencky": ("model", "bulk", "shear"),
}

#: Keys whose value must be one of a fixed set of strings.
CHOICES: dict[tuple[str, str], tuple[str, ...]] = {
    ("problem", "equation"): ("scalar", "elasticity"),
    ("problem", "tangential"): ("slip", "stick"),
    ("material", "model"): ("linear-elastic", "hencky"),
    ("geometry", "shape"): ("square", "lshape", "polygon", "disk", "ellipse", "box", "ball"),
    ("geometry", "subdomains"): ("auto", "physical"),
    ("solver", "method"): ("pgpm", "apgpm", "ssn"),
    ("solver", "preconditioner"): ("auto", "substructuring", "amg", "identity", "exact"),
    ("solver", "projection"): ("inexact", "exact"),
    ("solver", "edge_form"): ("paper", "sqrt-laplacian"),
    ("solver", "coarse_space"): ("auto", "graph", "galerkin"),
    ("solver", "flux_space"): ("p1", "p0"),
    ("solver", "jacobian"): ("ufl", "handwritten"),
    ("solver", "boundary_operator"): ("auto", "dense", "hmatrix"),
}

#: The variables each expression of [data] may use in 2D: boundary data also see the
#: outward unit normal (nx, ny). ``a`` is a number, not an expression; ``exact`` (the
#: exact interior solution u, "" when none is known) is checked only when given.
DATA_VARIABLES: dict[str, tuple[str, ...]] = {
    "f": ("x", "y"),
    "u0": ("x", "y", "nx", "ny"),
    "t0": ("x", "y", "nx", "ny"),
    "exact": ("x", "y"),
}
#: The same for a body in R^3: z and nz too (docs/method.md section 11).
DATA_VARIABLES_3D: dict[str, tuple[str, ...]] = {
    "f": ("x", "y", "z"),
    "u0": ("x", "y", "z", "nx", "ny", "nz"),
    "t0": ("x", "y", "z", "nx", "ny", "nz"),
    "exact": ("x", "y", "z"),
}

#: Steps of the semismooth Newton method that are not part of the schema.
#: PGPM steps before the first Newton step: fewer cost time at 10^6 dofs
#: (docs/design/solvers.md, "ssn's start").
SSN_START_STEPS = 5
SSN_WARM_START_STEPS = 0  # the same from a given iterate (nested iteration, adaptivity)
SSN_CG_MAX_ITERATIONS = 500  # cap on the CG iterations of one Newton step
#: Exponent p of the inexact-Newton forcing min(0.1, (r_k / r_0)^p) of a Newton step's CG:
#: 1/2 from xi_0 = 0 (the active set still moves), 1 (q-quadratic) from a given iterate
#: (docs/design/solvers.md, "The forcing from a given iterate").
SSN_FORCING_EXPONENT = 0.5
SSN_WARM_FORCING_EXPONENT = 1.0
#: A Newton step after one of relative B-norm at most this keeps the Jacobian of the step
#: before: its error, O(this), is about such a step's CG tolerance
#: (docs/design/solvers.md, "ssn keeps the Jacobian after small steps").
SSN_JACOBIAN_REUSE_STEP = 1e-3
#: The V solve of every product with an H-matrix S_h inside a Newton step's CG runs to
#: this times the CG's rtol instead of to the operator's own tolerance: the step needs
#: only rtol, and products this much more accurate leave its CG iterations as they were
#: (docs/design/solvers.md, "S_h's V solves to the Newton step's accuracy").
SSN_INNER_TOL_FACTOR = 1e-2
#: c of the forcing floor c tol ||xi||_B / (tau r) of a Newton step's CG (no oversolving),
#: small enough to keep the answer well within tol (docs/design/solvers.md, "ssn's
#: stopping rule and the oversolving safeguard").
OVERSOLVE_SAFEGUARD = 0.1
#: Nested iteration (``[solver] nested``): h grows by this factor from one level to the
#: next coarser one, which has at least NESTED_MIN_DOFS dofs; a coarse level then costs
#: 1/16 of the fine one (docs/design/nested.md, "Coarser levels at 4h").
NESTED_COARSENING = 4
NESTED_MIN_DOFS = 1000
#: A body in R^3: h grows by the first factor per level (a level then has 1/64 of the dofs
#: and 1/16 of the boundary dofs of the next, so that its S_h costs little), and by the
#: second for the coarsest level where the first would leave fewer than NESTED_MIN_DOFS
#: dofs or cut a box's cubes (docs/design/three_dimensions.md, "Nested").
NESTED_COARSENING_3D = (4, 2)
#: ``preconditioner = "auto"``: the paper's substructuring B for a planar domain, amg
#: (multigrid and E^T W_h E, docs/method.md section 11) for a body in R^3.
AUTO_PRECONDITIONER = {2: "substructuring", 3: "amg"}
#: The inner CG + GAMG solve of B_Omega of the ``amg`` preconditioner: relative tolerance
#: and cap. Tight, since the iterations use B_Omega u and B_Omega^{-1} g as inverses of
#: each other; its error enters the iterates at this level, far below the solver tol
#: (docs/design/three_dimensions.md, "The amg preconditioner").
AMG_RTOL = 1e-12
AMG_MAX_ITERATIONS = 500
#: PETSc options of that GAMG (its defaults but one smoothing step per level: measured
#: per solve of B_Omega on the box, 0.528 -> 0.384 s at 64^3 cubes (17 -> 20 iterations),
#: 1.69 -> 1.39 s at 96^3; without squaring the graph, GAMG's default unless options are
#: read: squared, the set-up halves but a solve takes 28 iterations, 0.60 s at 64^3;
#: docs/design/three_dimensions.md, "The amg preconditioner's multigrid").
AMG_OPTIONS = {"pc_gamg_square_graph": 0, "mg_levels_ksp_max_it": 1}
#: The amg preconditioner on the box and the structured square (the scalar problem and
#: elasticity): a geometric multigrid on their vertex lattice in place of
#: GAMG (``coupling.preconditioners.lattice_multigrid``): Chebyshev smoothing steps per
#: level, the lower end of the Chebyshev interval as a fraction of the Gershgorin bound, and
#: the most cubes per side of the coarsest lattice (factored by Cholesky; a box whose halved
#: n stays above it keeps GAMG). Measured on the box (K + c M_Gamma, 64^3 cubes, levels down
#: to 4^3): one V-cycle has condition number 1.17 against B_Omega (GAMG's: 3.08), CG to 1e-12
#: takes 7 cycles, 0.26 s (GAMG 18, 0.49 s) after a set-up of 0.3 s (GAMG 1.9-2.3 s);
#: docs/design/three_dimensions.md, "A geometric multigrid on the box".
LATTICE_MG_SMOOTHING_STEPS = 2
LATTICE_MG_EIGENVALUE_FRACTION = 0.2
LATTICE_MG_COARSEST = 16
LANCZOS_STEPS = 20  # Lanczos steps of the step estimate C0 (and of lambda_min for apgpm)
#: Lanczos steps of ssn's C0, only the scale of its PGPM steps, prediction and stopping
#: rule; the largest Ritz value converges first (docs/design/solvers.md, "ssn's start").
SSN_LANCZOS_STEPS = 10

#: The sparse Cholesky factor of A_II (one block per subdomain) keeps the mesh's numbering
#: ("natural" ordering) when no block has more rows than this, nested dissection otherwise:
#: small blocks fill little either way (docs/design/preconditioners.md, "Set-up cuts").
NATURAL_ORDERING_MAX_BLOCK = 1024
#: On two or more ranks the coarse matrix C is solved through its interface Schur
#: complement (dense, |S| x |S| on every rank) while the coarse vertices shared by
#: subdomains of different ranks are at most this many (128 MB for Sigma and its factor),
#: and factored whole on every rank beyond (docs/design/parallel.md, "The coarse problem
#: over the ranks").
INTERFACE_COARSE_MAX_VERTICES = 4000
#: The exact Signorini projection factors a principal block M_II of M_s through a sparse
#: elimination of the rows of M_s with at most this many nonzeros and at most a quarter of
#: the row (the two-level form's edge nodes: an edge's nodes and its two ends) and a dense
#: Schur complement on the others (its coarse nodes, dense among themselves), when those
#: are at most half the rows; a dense M_s is factored densely (docs/design/solvers.md,
#: "The projection's factors").
METRIC_SPARSE_ROW_NONZEROS = 64
#: ``boundary_operator = "auto"``: the H-matrix S_h from this many boundary dofs on, the
#: dense one below, where the H-matrix is clearly the cheaper in a whole solve
#: (docs/design/hmatrix.md, "The crossover after the set-up and product speed-ups").
HMATRIX_CROSSOVER = 2048
#: The same for a surface in R^3: the whole `fembem solve` (the box pressed onto its bottom
#: face) takes as long with either S_h at 866 boundary dofs (4.1 s), and from there the
#: H-matrix is faster (1,538: 7.0 against 8.1 s; 3,458: 17.5 against 33.7 s) and smaller
#: (peak 0.21 against 0.34 GB; 0.31 against 1.0 GB) (docs/design/three_dimensions.md,
#: "The 3D crossover").
HMATRIX_CROSSOVER_3D = 1000
#: Relative accuracy of the H-matrix blocks of S_h (``bem_cpp.steklov_poincare`` tol):
#: products agree with the dense S_h to a few times this (docs/design/hmatrix.md), far
#: below the solver tolerances (1e-8 by default).
HMATRIX_TOL = 1e-10
#: For a surface in R^3 the tolerance is chosen from the discretisation error it must not
#: spoil: tol = min(HMATRIX_TOL_3D_MAX, HMATRIX_TOL_3D_SCALE / N_Gamma) for N_Gamma boundary
#: dofs. P1's nodal error falls like h^2, i.e. like 1 / N_Gamma, and u_h moves by about
#: 3e-2 tol, so this tol keeps u_h's change a fixed small fraction of its error at every
#: size. Measured on the manufactured box (coupling.manufactured.box_contact, ssn, tol
#: 1e-8): max |u_h(tol) - u_h(1e-7)| = 2.2e-7 at 1e-5 and 7.4e-7 at 3e-5 against a nodal
#: error of 3.0e-4 at 32^3 cubes (6,146 boundary dofs: tol 4.1e-5), 3.0e-7 at 1e-5
#: against 8.2e-5 at 64^3 (24,578: tol 1.0e-5), 2.9e-6 at 1e-4 against 1.1e-3 at 16^3
#: (1,538: tol 1e-4): 0.3-0.4 % of the error, which itself moves in its fourth digit; the
#: S_h set-up at 64^3 takes about a fifth less time than at 1e-6 (docs/design/
#: three_dimensions.md, "The boundary operators' accuracy").
HMATRIX_TOL_3D_SCALE = 0.25
HMATRIX_TOL_3D_MAX = 1e-4
#: The 3D estimator's boundary-integral residual (coupling.adapt.estimator.
#: surface_bie_residual) on the surface with every triangle split into four: V_h and K_h
#: as H-matrices (``bem_cpp.boundary_operators(..., triangles=...)``, P1 flux) from this
#: many split-surface nodes on, dense below (docs/design/estimator.md, "Bodies in R^3").
ESTIMATOR_HMATRIX_NODES_3D = 600
#: Their block tolerance: the residual is a difference of products much larger than
#: itself, so it is tighter than S_h's (HMATRIX_TOL_3D_MAX). Measured against 1e-8 on an
#: icosphere: the per-triangle values move by 1.7e-5 of the largest, their sum by 4e-7,
#: at half the set-up time (docs/design/estimator.md, "Bodies in R^3").
ESTIMATOR_HMATRIX_TOL_3D = 1e-6


def hmatrix_tol(nodes: Any) -> float:
    """The H-matrix tolerance of the boundary operators on the boundary nodes ``nodes``
    (N_Gamma, dim): :func:`hmatrix_tol_for` their count."""
    return hmatrix_tol_for(*np.shape(nodes))


def hmatrix_tol_for(boundary_nodes: int, dim: int) -> float:
    """The H-matrix tolerance of the boundary operators on ``boundary_nodes`` nodes of a
    boundary in R^``dim`` (the elastic operators' too: their nodes, not their d unknowns
    per node): ``HMATRIX_TOL`` in 2D; in 3D see ``HMATRIX_TOL_3D_SCALE``."""
    if dim == 2:
        return HMATRIX_TOL
    return min(HMATRIX_TOL_3D_MAX, HMATRIX_TOL_3D_SCALE / max(int(boundary_nodes), 1))


#: The adaptive loop splits a subdomain (``fem_py.mesh.grading``) once its diameter over its
#: smallest cell exceeds this many times the largest such ratio of the first mesh (d/h
#: for a structured mesh), so that H/h in the substructuring bound (1 + log(H/h))^2
#: stays bounded over the levels; the parts are halved until each is below the bound.
#: 2: one level of local refinement halves h, so a graded subdomain is split every
#: level or two (docs/design/adapt.md, "Subdomains on graded meshes").
GRADING_SPLIT_FACTOR = 2.0
#: Fitted convergence rates (adapt.png, the study's adaptivity part) use the levels with
#: at least this many dofs (the pre-asymptotic coarse levels left out), or all levels
#: when fewer than two are that large.
SLOPE_MIN_DOFS = 1000


def _solver_default(key: str) -> Any:
    return field(default=DEFAULTS["solver"][key])


@dataclass(frozen=True)
class SolverOptions:
    """The ``[solver]`` section (defaults in :data:`DEFAULTS`; README, configuration).

    ``flux_space``, ``jacobian`` and ``boundary_operator`` (S_h dense or as an H-matrix
    operator) choose how the problem is discretised
    (:class:`coupling.problem.SignoriniProblem` takes them), ``nested`` whether the
    application solves by nested iteration over coarser meshes
    (:func:`coupling.solvers.nested.solve_nested`); the rest choose how one problem is
    solved (:func:`coupling.solvers.solve`).
    """

    method: str = _solver_default("method")
    preconditioner: str = _solver_default("preconditioner")
    tol: float = _solver_default("tol")
    max_iterations: int = _solver_default("max_iterations")
    step: Any = _solver_default("step")
    projection: str = _solver_default("projection")
    projection_tol: float = _solver_default("projection_tol")
    projection_max_iterations: int = _solver_default("projection_max_iterations")
    edge_form: str = _solver_default("edge_form")
    flux_space: str = _solver_default("flux_space")
    jacobian: str = _solver_default("jacobian")
    signorini_weight: float = _solver_default("signorini_weight")
    coarse_space: str = _solver_default("coarse_space")
    nested: bool = _solver_default("nested")
    boundary_operator: str = _solver_default("boundary_operator")

    def __post_init__(self) -> None:
        for name in (
            "method",
            "preconditioner",
            "projection",
            "edge_form",
            "coarse_space",
            "flux_space",
            "jacobian",
            "boundary_operator",
        ):
            allowed = CHOICES["solver", name]
            if getattr(self, name) not in allowed:
                raise ValueError(
                    f"SolverOptions.{name} must be one of {allowed}, "
                    f"got {getattr(self, name)!r}"
                )


def solver_options(section: dict[str, Any]) -> SolverOptions:
    """:class:`SolverOptions` from a validated ``[solver]`` section."""
    names = {f.name for f in dataclasses.fields(SolverOptions)}
    return SolverOptions(**{k: v for k, v in section.items() if k in names})


def _section(name: str) -> Any:
    """A frozen dataclass of the ``[name]`` section: its annotated fields take their
    defaults from :data:`DEFAULTS` (every key of the section, in its order)."""

    def make(cls: type) -> type:
        if list(cls.__annotations__) != list(DEFAULTS[name]):
            raise TypeError(f"{cls.__name__} must declare the keys of [{name}] in order")
        for key in cls.__annotations__:
            setattr(cls, key, field(default=DEFAULTS[name][key]))
        return dataclass(frozen=True)(cls)

    return make


@_section("problem")
class ProblemOptions:
    """The ``[problem]`` section: the ``equation`` (``"scalar"``, the paper's, or
    ``"elasticity"``, docs/method.md section 12) and, for elasticity, the ``tangential``
    condition on Gamma_s (``"slip"``: frictionless; ``"stick"``: no slip)."""

    equation: str
    tangential: str


@_section("material")
class MaterialOptions:
    """The ``[material]`` section: the scalar equation's built-in material ``rho``
    (``linear``, ``carstensen``, ``power`` or an expression in t) and the power law's ``p``
    and ``eps`` (``fem_py.forms.make_material``); elasticity's ``model``
    (``"linear-elastic"`` with ``E``, ``nu``; ``"hencky"`` with ``bulk`` and ``shear``, a
    number or an expression in s; ``fem_py.forms.elasticity``)."""

    rho: str
    p: float
    eps: float
    model: str
    E: float
    nu: float
    bulk: float
    shear: float | str


@_section("exterior")
class ExteriorOptions:
    """The ``[exterior]`` section: Young's modulus ``E`` and Poisson's ratio ``nu`` of the
    unbounded elastic medium (elasticity)."""

    E: float
    nu: float


@_section("data")
class DataOptions:
    """The ``[data]`` section: the expressions f, u0, t0 (:data:`DATA_VARIABLES`), the
    constant ``a`` of the exterior solution and the exact interior solution ``exact``
    ("" when none is known). For elasticity f, u0, t0 and a are vectors: tuples of d
    expressions (numbers for a), the defaults zero vectors."""

    f: str | tuple[str, ...]
    u0: str | tuple[str, ...]
    t0: str | tuple[str, ...]
    a: float | tuple[float, ...]
    exact: str


@_section("adapt")
class AdaptOptions:
    """The ``[adapt]`` section: ``steps`` refinements (0: no adaptivity), Doerfler's
    ``theta`` in (0, 1], and ``max_dofs``: no level beyond this many dofs is solved."""

    steps: int
    theta: float
    max_dofs: int

    def __post_init__(self) -> None:
        if not 0.0 < self.theta <= 1.0:
            raise ValueError(f"AdaptOptions.theta must lie in (0, 1], got {self.theta!r}")
        if self.steps < 0 or self.max_dofs <= 0:
            raise ValueError(
                f"AdaptOptions: steps >= 0 and max_dofs > 0, got {self.steps}, {self.max_dofs}"
            )


@_section("output")
class OutputOptions:
    """The ``[output]`` section: the folder ``dir``, and whether to write solution.xdmf
    and the figures (``coupling.io.outputs.RunOutputs``), to compute the a posteriori
    estimator of a plain or nested solve (adaptive runs always do) and to write its
    per-cell indicators (which implies it); for a body, the plane of slice.png (``slice``:
    ``"auto"``, through the Signorini part, or ``"x = c"``, ``"y = c"``, ``"z = c"``)."""

    dir: str
    xdmf: bool
    plots: bool
    estimator: bool
    indicators: bool
    slice: str

    @property
    def estimates(self) -> bool:
        """Whether a plain or nested solve computes the estimator."""
        return self.estimator or self.indicators


@dataclass(frozen=True)
class RunConfig:
    """A run's configuration, typed: one frozen value per section of :data:`DEFAULTS`.

    Made once from the TOML by ``coupling.app.config.load_config`` (which validates it);
    the library below the application takes the sections it needs, never the whole.
    """

    problem: ProblemOptions = field(default_factory=ProblemOptions)
    geometry: GeometrySpec = field(default_factory=GeometrySpec)
    material: MaterialOptions = field(default_factory=MaterialOptions)
    exterior: ExteriorOptions = field(default_factory=ExteriorOptions)
    data: DataOptions = field(default_factory=DataOptions)
    solver: SolverOptions = field(default_factory=SolverOptions)
    adapt: AdaptOptions = field(default_factory=AdaptOptions)
    output: OutputOptions = field(default_factory=OutputOptions)

    def __post_init__(self) -> None:
        if self.solver.nested and self.adapt.steps > 0:
            raise ValueError(
                "solver.nested = true and adapt.steps > 0 do not combine: the adaptive loop "
                "already starts each level from the one before; set solver.nested = false"
            )

    def as_dict(self) -> dict[str, dict[str, Any]]:
        """Section -> key -> value as TOML reads it (arrays as lists), the keys of
        :data:`DEFAULTS` (summary.json's ``config``)."""
        return {
            section: {key: _toml(getattr(getattr(self, section), key)) for key in keys}
            for section, keys in DEFAULTS.items()
        }


#: ``[output] slice``: a coordinate plane "x = c", "y = c" or "z = c"
_PLANE = re.compile(r"^\s*([xyz])\s*=\s*([-+0-9.eE]+)\s*$")


def parse_slice(text: str) -> tuple[int, float] | None:
    """``[output] slice`` as (the axis across the plane, 0-2; its coordinate), or None for
    ``"auto"``; a ``ValueError`` for anything else."""
    if text == "auto":
        return None
    match = _PLANE.match(text)
    try:
        value = float(match.group(2)) if match else np.nan
    except ValueError:
        value = np.nan
    if not np.isfinite(value):
        raise ValueError(
            f'must be "auto" or a coordinate plane "x = c", "y = c" or "z = c", got {text!r}'
        )
    return "xyz".index(match.group(1)), value
