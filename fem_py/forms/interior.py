"""Interior energy G, residual DG and Jacobians D^2 G (docs/method.md sections 3, 4, 6).

With V_h the continuous P1 space and u in V_h,

    G(u)            = int_Omega g(|grad u|) dx                           (2.1)
    A(u)_i          = DG(u, v_i) = int rho(|grad u|) grad u . grad v_i     (2.1), section 4
    D^2G(u)_{ij}    = int (rho^(grad u) grad v_j) . grad v_i               (4.1)
    b_f,i           = int f v_i dx,        m_t,j = int_Gamma t0 v_j ds      section 4
    A_lap,ij        = int grad v_j . grad v_i                             (4.2), section 6

The residual is ``ufl.derivative`` of the energy. The Jacobian is either
``ufl.derivative`` of the residual (``"ufl"``) or the hand-written tangent rho^ of
docs/method.md section 6 (``"handwritten"``); see :mod:`fem_py.forms.materials` for how both stay
finite at grad u = 0. b_f is integrated at degree 2 (:data:`VOLUME_DATA_QUADRATURE`:
the data's expression at three points per triangle), m_t at degree 6
(:data:`DATA_QUADRATURE`).

The P1 space is ``fem_py.dofs.p1.p1_space``, the only place it is created, so that every
module sees the same global dof numbering.
"""
from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp
import ufl
from dolfinx import cpp, fem, la
from mpi4py import MPI
from petsc4py import PETSc

from fem_py.dofs.p1 import quiet_jit
from fem_py.forms.expressions import parse_expression
from fem_py.forms.elasticity import ElasticMaterial
from fem_py.forms.materials import Material
from fem_py.forms.p1_matrix import P1Matrix

__all__ = [
    "spatial_variables",
    "as_ufl_data",
    "compile_form",
    "matching_data",
    "InteriorForms",
    "assemble_boundary_load",
    "JACOBIANS",
    "COORDINATES",
]

JACOBIANS = ("ufl", "handwritten")

#: Quadrature of the interior energy, residual and Jacobians. For P1, grad u is
#: constant on each cell, so every integrand g(|grad u|), rho(|grad u|) grad u . grad v
#: and (rho^(grad u) grad w) . grad v is cellwise constant and one point integrates it
#: exactly (UFL's estimate for the nonpolynomial rho would use several).
P1_EXACT = {"quadrature_degree": 0}
#: Quadrature of the boundary data integral int_Gamma t0 v: degree 6 integrates smooth
#: data against P1 test functions with an error O(h^7) per facet, far below the O(h^2)
#: discretisation error; UFL's own estimate for composite expressions (e.g. the
#: manufactured t0 = (rho(|grad u|) grad u - grad u_e) . n) can exceed 1000 points. The
#: boundary has O(h^(1-d)) facets against O(h^-d) cells: its cost stays small.
DATA_QUADRATURE = {"quadrature_degree": 6}
#: Quadrature of the volume load int f v: degree 2 (three interior points per triangle,
#: four per tetrahedron). Exact for quadratic integrands, it changes b_f by O(h^2) (a
#: change of u_h of O(h^2) in energy, below the P1 energy error O(h)), and the total
#: load int f, which the far field's log coefficient b sees, by O(h^4) (the rule is
#: symmetric; measured 1.5e-7, 9e-9, 5.6e-10 on three L-shape meshes). The data's
#: compiled expression runs three times per cell against twelve at degree 6: 0.33 s
#: against 1.15 s at 2e6 triangles for an f of 1,716 characters (docs/design/speed.md,
#: "Data expressions"), and never at a vertex, where data singular at a corner (f ~
#: r^(-1/3) at the L-shape's) is infinite. The centroid rule (0.15 s) errs in int f by
#: O(h^2): b off by 4e-5 on the same meshes.
VOLUME_DATA_QUADRATURE = {"quadrature_degree": 2}


#: The coordinate names of the expressions, by the dimension of Omega; the normal's
#: components are these with an ``n`` in front (nx, ny[, nz]).
COORDINATES = {2: ("x", "y"), 3: ("x", "y", "z")}


def spatial_variables(mesh: Any, *, boundary: bool = False) -> dict[str, Any]:
    """UFL values of the expression variables: x, y (z in 3D) and on the boundary nx, ny
    (nz), the outward unit normal (docs/method.md section 11 for 3D)."""
    X = ufl.SpatialCoordinate(mesh)
    names = COORDINATES[X.ufl_shape[0]]
    out = {name: X[k] for k, name in enumerate(names)}
    if boundary:
        n = ufl.FacetNormal(mesh)
        out.update({f"n{name}": n[k] for k, name in enumerate(names)})
    return out


def as_ufl_data(value: Any, mesh: Any, *, boundary: bool = False, what: str = "data") -> Any:
    """Turn data given as text (x, y[, nx, ny]), a number or a UFL expression into UFL; a
    list of them (the components of a vector, e.g. f = ["0", "-1"]) into a UFL vector."""
    if isinstance(value, str):
        return parse_expression(value, spatial_variables(mesh, boundary=boundary), backend="ufl")
    if isinstance(value, (int, float, np.floating, np.integer)) and not isinstance(value, bool):
        return ufl.as_ufl(float(value))
    if isinstance(value, ufl.core.expr.Expr):
        return value
    if isinstance(value, (list, tuple)) and value:
        return ufl.as_vector(
            [
                as_ufl_data(c, mesh, boundary=boundary, what=f"{what}[{k}]")
                for k, c in enumerate(value)
            ]
        )
    raise ValueError(
        f"{what} must be a string expression, a number or a UFL expression, "
        f"got {type(value).__name__}"
    )


def matching_data(value: Any, V: fem.FunctionSpace, what: str) -> Any:
    """The UFL data ``value`` when it has the unknown's shape on ``V`` (a scalar, or d
    components for elasticity), else a one-line ``ValueError`` naming ``what``."""
    have, want = ufl.shape(value), V.ufl_element().value_shape()
    if have != want:
        n, m = (shape[0] if shape else 1 for shape in (have, want))
        hint = f"a list of {m} expressions" if m > 1 else "one expression"
        raise ValueError(
            f"{what} has {n} component{'s' if n != 1 else ''}, the unknown {m}: give {what} as"
            f" {hint}"
        )
    return value


def compile_form(form: Any, jit_params: dict | None = None) -> fem.FormMetaClass:
    """``fem.form`` with quiet JIT output."""
    with quiet_jit():
        return fem.form(form, jit_params=dict(jit_params or {}))


class InteriorForms:
    """Compiled interior forms of one material on one P1 space.

    Parameters
    ----------
    V
        The space from :func:`p1_space`.
    material
        A :class:`fem_py.forms.materials.Material`.
    f
        Volume load: text in x, y (z in 3D), a number, a UFL expression, or None (zero).
    jacobian
        Default Jacobian kind of :meth:`assemble_jacobian`: ``"ufl"`` or ``"handwritten"``.
    jit_params
        Passed to ``fem.form`` (e.g. ``{"cache_dir": ...}``).

    Notes
    -----
    ``u`` arguments may be a ``fem.Function`` on ``V`` or a PETSc Vec with the layout of
    :meth:`create_vector`; the value is copied into an internal state function (ghosts
    updated), so the caller's object is never modified.
    """

    def __init__(
        self,
        V: fem.FunctionSpace,
        material: Material,
        f: Any = None,
        *,
        jacobian: str = "ufl",
        jit_params: dict | None = None,
    ):
        if jacobian not in JACOBIANS:
            raise ValueError(f"jacobian must be one of {JACOBIANS}, got {jacobian!r}")
        if not isinstance(material, (Material, ElasticMaterial)):
            raise ValueError(
                "material must be a fem_py.forms.Material or ElasticMaterial, got "
                f"{type(material).__name__}; use make_material, linear_elastic or hencky"
            )
        components = V.dofmap.index_map_bs
        if components != material.components:
            raise ValueError(
                f"material {material.name!r} has {material.components} component(s) per node, "
                f"the space {components}"
            )
        self.V = V
        self.mesh = V.mesh
        self.comm = V.mesh.comm
        self.material = material
        self.jacobian_kind = jacobian
        self._jit = dict(jit_params or {})
        self._u = fem.Function(V, name="u_state")
        u, v, w = self._u, ufl.TestFunction(V), ufl.TrialFunction(V)
        dx = ufl.dx(metadata=P1_EXACT)
        energy = material.energy_integrand(u) * dx
        residual = ufl.derivative(energy, u, v)
        self._ufl = {
            "energy": energy,
            "residual": residual,
            "ufl": ufl.derivative(residual, u, w),
            "handwritten": material.jacobian_integrand(u, w, v) * dx,
            "stiffness": material.stiffness_integrand(w, v) * dx,
        }
        if f is not None:
            f = matching_data(as_ufl_data(f, self.mesh, what="f"), V, "f")
            self._ufl["load"] = ufl.inner(f, v) * ufl.dx(
                domain=self.mesh, metadata=VOLUME_DATA_QUADRATURE
            )
        self._compiled: dict[str, Any] = {}
        # the packed coefficients (the state u per cell) at the state they were packed at:
        # shared by the forms whose only coefficient is u (_state_only)
        self._packed: dict | None = None
        self._packed_state: np.ndarray | None = None
        for key in ("energy", "residual", jacobian):
            self._form(key)

    # ------------------------------------------------------------ helpers
    def _form(self, key: str) -> Any:
        if key not in self._compiled:
            self._compiled[key] = compile_form(self._ufl[key], self._jit)
        return self._compiled[key]

    def _state_only(self, form: Any) -> bool:
        """Whether u is the only coefficient of ``form``, with one cell integral over all
        cells: its packed coefficients (u on every cell) are those of every such form."""
        cell = fem.IntegralType.cell
        return (
            len(form.coefficients) == 1
            and form.coefficients[0] is self._u._cpp_object
            and set(form.integral_types) == {cell}
            and list(form.integral_ids(cell)) == [-1]
        )

    def _coefficients(self, key: str) -> dict | None:
        """The packed coefficients of form ``key`` at the current state, or None (dolfinx
        packs them). The energy, the residual and the Jacobian at one u pack u once: the
        pack is kept with a copy of the state it was packed at and reused while the state
        is unchanged (compared exactly); one pack is held at a time (its cost and size:
        docs/design/fem_py.md, "Packed coefficients of the interior forms")."""
        form = self._form(key)
        if not self._state_only(form):
            return None
        state = self._u.x.array
        if self._packed is None or not np.array_equal(self._packed_state, state):
            self._packed = None  # the old pack freed first: never two at once
            self._packed = cpp.fem.pack_coefficients(form)
            self._packed_state = state.copy()
        return self._packed

    def set_state(self, u: Any) -> fem.Function:
        """Copy ``u`` (Function or PETSc Vec) into the internal state; return the state."""
        if isinstance(u, fem.Function):
            if u is not self._u:
                self._u.x.array[:] = u.x.array
        elif isinstance(u, PETSc.Vec):
            u.copy(self._u.vector)
            self._u.x.scatter_forward()
        else:
            raise ValueError(f"u must be a dolfinx Function or a PETSc Vec, got {type(u).__name__}")
        return self._u

    # ------------------------------------------------------------ public
    def energy(self, u: Any) -> float:
        """G(u) = int g(|grad u|) dx (2.1), summed over all ranks."""
        self.set_state(u)
        value = fem.assemble_scalar(self._form("energy"), coeffs=self._coefficients("energy"))
        return self.comm.allreduce(value, op=MPI.SUM)

    def create_vector(self) -> PETSc.Vec:
        """A ghosted PETSc Vec with the layout of V (caller destroys it)."""
        return fem.petsc.create_vector(self._form("residual"))

    def create_matrix(self) -> PETSc.Mat:
        """A PETSc Mat with the P1 sparsity (caller destroys it)."""
        return fem.petsc.create_matrix(self._form(self.jacobian_kind))

    def create_p1_matrix(self) -> P1Matrix:
        """A :class:`fem_py.forms.p1_matrix.P1Matrix` with the P1 sparsity: the Jacobians'
        and the stiffness's matrix without PETSc's insertion (its module docstring)."""
        return P1Matrix(self._form(self.jacobian_kind))

    def assemble_residual(self, u: Any, b: PETSc.Vec) -> PETSc.Vec:
        """b_i = DG(u, v_i) = int rho(|grad u|) grad u . grad v_i dx; ghosts summed (REVERSE)
        and then refreshed (FORWARD). Returns ``b``."""
        self.set_state(u)
        with b.localForm() as bl:
            bl.set(0.0)
        fem.petsc.assemble_vector(b, self._form("residual"), coeffs=self._coefficients("residual"))
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        b.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        return b

    def assemble_jacobian(
        self, u: Any, A: PETSc.Mat | P1Matrix, kind: str | None = None
    ) -> PETSc.Mat | P1Matrix:
        """A_ij = D^2G(u)(v_j, v_i) (4.1), ``kind`` ``"ufl"`` or ``"handwritten"``
        (default: the constructor's), into a PETSc Mat or, for its products, a
        :class:`P1Matrix`. Returns the assembled ``A``."""
        kind = self.jacobian_kind if kind is None else kind
        if kind not in JACOBIANS:
            raise ValueError(f"kind must be one of {JACOBIANS}, got {kind!r}")
        self.set_state(u)
        if isinstance(A, P1Matrix):
            A.assemble_local(self._form(kind), self._coefficients(kind))
            return A
        A.zeroEntries()
        fem.petsc.assemble_matrix(A, self._form(kind), coeffs=self._coefficients(kind))
        A.assemble()
        return A

    def assemble_load(self) -> PETSc.Vec:
        """b_f,i = int f v_i dx (a new Vec; zero when f is None or zero)."""
        return assemble_linear_form(self.V, self._ufl.get("load"), self._jit)

    def boundary_load(self, t0: Any, boundary: Any) -> np.ndarray:
        """m_t = int_Gamma t0 v_j ds in boundary order (``boundary``: a
        :class:`fem_py.boundary.BoundaryMap`), the same array on every rank."""
        b = assemble_boundary_load(self.V, t0, jit_params=self._jit)
        try:
            return boundary.gather(b)
        finally:
            b.destroy()

    def stiffness_rows(self, A: P1Matrix | None = None) -> sp.csr_matrix:
        """The owned rows of the Laplace stiffness matrix int grad v_j . grad v_i dx, with
        global column numbers (collective), assembled in ``A`` (whose values it overwrites)
        or in a new :class:`P1Matrix`."""
        A = P1Matrix(self._form("stiffness")) if A is None else A
        return A.assemble_owned(self._form("stiffness"))

    def stiffness_local(self, A: P1Matrix | None = None) -> sp.csr_matrix:
        """This rank's cells' share of the Laplace stiffness matrix on its local dofs, local
        column numbers (:attr:`P1Matrix.local_rows`; no communication): a view into ``A``
        (whose values it overwrites, valid until its next assembly) or a new matrix."""
        own = A is None
        A = P1Matrix(self._form("stiffness")) if own else A
        A.assemble_local(self._form("stiffness"))
        return A.local_rows.copy() if own else A.local_rows

    def assemble_stiffness(self, A: PETSc.Mat | None = None) -> PETSc.Mat:
        """The Laplace stiffness matrix int grad v_j . grad v_i dx, assembled into ``A``
        (a Mat of :meth:`create_matrix`: the same P1 sparsity) or into a new Mat."""
        if A is None:
            A = fem.petsc.assemble_matrix(self._form("stiffness"))
        else:
            A.zeroEntries()
            fem.petsc.assemble_matrix(A, self._form("stiffness"))
        A.assemble()
        return A


def assemble_linear_form(
    V: fem.FunctionSpace, form: Any, jit_params: dict | None = None
) -> PETSc.Vec:
    """A new ghosted Vec on V holding the assembled linear ``form`` (ghosts summed and
    refreshed). ``None``, or a form whose integrands UFL simplified to zero (zero data,
    e.g. f = "0"), gives zeros."""
    index_map = V.dofmap.index_map
    b = la.create_petsc_vector(index_map, V.dofmap.index_map_bs)
    with b.localForm() as bl:
        bl.set(0.0)
    if form is not None and not all(
        isinstance(i.integrand(), ufl.constantvalue.Zero) for i in form.integrals()
    ):
        fem.petsc.assemble_vector(b, compile_form(form, jit_params))
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        b.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
    return b


def assemble_boundary_load(
    V: fem.FunctionSpace, t0: Any, *, jit_params: dict | None = None
) -> PETSc.Vec:
    """m_t,j = int_Gamma t0 v_j ds over the whole boundary (docs/method.md section 4).

    ``t0`` is text in x, y, nx, ny (z, nz in 3D; the outward unit normal
    ``ufl.FacetNormal``), a number
    or a UFL expression. Returns a new ghosted Vec (caller destroys it); its
    boundary-order values are ``BoundaryMap.gather(m_t)``.
    """
    mesh = V.mesh
    t0 = matching_data(as_ufl_data(t0, mesh, boundary=True, what="t0"), V, "t0")
    form = ufl.inner(t0, ufl.TestFunction(V)) * ufl.ds(domain=mesh, metadata=DATA_QUADRATURE)
    return assemble_linear_form(V, form, jit_params)
