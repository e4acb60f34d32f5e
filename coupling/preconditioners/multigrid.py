"""The ``amg`` preconditioner of a body in R^3 (docs/method.md section 11, "Preconditioning").

    B_Omega = K + c T^T M_Gamma T,      c = <S_h 1, 1> / |Gamma|,
    M_s     = E^T W_h E,

with K the P1 Laplace stiffness matrix, M_Gamma the P1 mass matrix of Gamma and W_h the
Galerkin hypersingular operator. Both blocks are spectrally equivalent, uniformly in h, to
the diagonal blocks of the Hessian D^2 J_h:

- u block: A + T^T S_h T is equivalent to the H^1(Omega) norm (the interior energy plus
  <S_h z, z>, which in 3D is positive on constants), and so is K + c M_Gamma (the trace
  theorem); c is S_h's value on the constant, |Gamma|^{-1} <S_h 1, 1> (1/R on a sphere of
  radius R), so that both agree on the mode K does not see.
- phi block: E^T S_h E >= 1/2 E^T W_h E (S_h = 1/2 (W_h + (K_h - M_h)^T V_h^{-1} (K_h - M_h)),
  the second term positive semi-definite), and both are equivalent to the H~^{1/2}(Gamma_s)
  norm, on which W is elliptic (phi vanishes on the boundary curves of Gamma_s). On the
  sphere W Y_l / S Y_l = 2l / (2l + 1): the two agree on the oscillating modes.

B_Omega^{-1} is applied by conjugate gradients preconditioned by one multigrid V-cycle, to
the relative tolerance ``rtol`` (the iterations read B_Omega u and B_Omega^{-1} g as
inverses of each other, so the inner solve is tight, not one cycle); its cost per
application grows like N, its count stays bounded as h -> 0. On the box and on the
structured square the V-cycle is the geometric multigrid of their vertex lattice
(``coupling.preconditioners.lattice_multigrid``; for elasticity on the d components of
every node, the prolongation Kronecker I_d), the same operator on any number of ranks,
so that one cycle alone (``cycle_omega``) may precondition the Newton steps' CG; on
other domains it is PETSc's GAMG with one smoothing step per level
(``coupling.options.AMG_OPTIONS``; for elasticity with the rigid motions as its
near-nullspace), whose aggregates follow the partition, and ``cycle_omega`` is the
tight solve. M_s is dense
(n_s x n_s, the projection (3.19) and the Newton steps read it), and factored on every
rank; with the H-matrix S_h it is read from the H-matrix of W_h that S_h holds (to its
tolerance), else integrated over the triangles of Gamma_s alone
(``bem_cpp.hypersingular(..., block=)``) on rank 0 with every core and broadcast.
"""
from __future__ import annotations

from typing import Any, Callable

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

import bem_cpp
from bem_cpp.dense import SingleMatrix, release_free_heap
from coupling.options import AMG_OPTIONS
from coupling.preconditioners.base import DenseSignoriniBlock
from coupling.preconditioners.lattice_multigrid import LatticeHierarchy, lattice_levels
from fem_py.forms.elasticity import rigid_body_modes
from fem_py.forms.interior import compile_form
from fem_py.mesh.box import BoxLattice
from fem_py.parallel import array_from_root

__all__ = ["MultigridPreconditioner", "constant_mode_weight", "signorini_hypersingular"]


def constant_mode_weight(V: fem.FunctionSpace, S: Any) -> float:
    """c = <S_h 1, 1> / |Gamma| (collective); for the d components of elasticity the mean
    over the d translations e_k, sum_k <S_h e_k, e_k> / (d |Gamma|)."""
    d = V.dofmap.index_map_bs
    translations = np.kron(np.ones(S.shape[0] // d), np.eye(d))  # (d, d n)
    area_form = fem.form(fem.Constant(V.mesh, PETSc.ScalarType(1.0)) * ufl.ds(domain=V.mesh))
    area = V.mesh.comm.allreduce(fem.assemble_scalar(area_form), op=MPI.SUM)
    value = sum(float(e @ (S @ e)) for e in translations)
    return value / (d * float(area))


def signorini_hypersingular(
    comm: MPI.Comm, boundary: Any, S: Any = None, *, gap: Any = None, kernel: Any = "laplace"
) -> np.ndarray:
    """M_s = E^T W_h E (n_s x n_s) on every rank (collective): read from the H-matrix of
    W_h that S_h holds, when it does (``S.holds_hypersingular``), else integrated on rank 0.
    With Kelvin's ``kernel`` (elasticity) the Lame W_h on the d components of the Signorini
    nodes, and E the ``gap`` map's directions there (``fem_py.boundary.blocked.GapMap``)."""
    if boundary.signorini.size == 0:
        return np.zeros((0, 0))
    if getattr(S, "holds_hypersingular", False):
        W = S.hypersingular_block(boundary.signorini)  # Lame's: (d k, d k), node-major
    else:
        W = array_from_root(
            comm,
            lambda: bem_cpp.hypersingular(
                boundary.nodes,
                triangles=getattr(boundary, "triangles", None),  # None: a polygon (2D)
                block=boundary.signorini,
                kernel=kernel,
            ),
            all_cores=True,
        )
    if kernel == "laplace":
        return W
    d = boundary.components
    rows = (d * np.asarray(boundary.signorini)[:, None] + np.arange(d)).ravel()
    E = gap.matrix[rows].tocsc()  # the directions of the gap unknowns at those entries
    single = getattr(S, "single_precision", False)
    M = _turned(W, E, np.float32 if single else np.float64)
    del W
    release_free_heap()  # the blocks of rows' scratch (0.13 GB off the 48^3 box's peak)
    return SingleMatrix(M) if single else M


def _turned(W: np.ndarray, E: Any, dtype: Any, rows: int = 512) -> np.ndarray:
    """E^T W E (m x m) of a dense symmetric W (n x n) and a sparse E (n x m, CSC), in
    ``dtype``, a block of ``rows`` rows at a time: besides W and the result, one block
    (rows x n) at a time, where the dense E and the whole product E^T W would take two more
    n x m arrays (M_s of the elastic box at 48^3 cubes: 0.35 GB each). Every rank that calls
    it with the same arrays gets the same bits."""
    m = E.shape[1]
    out = np.empty((m, m), dtype=dtype)
    for start in range(0, m, rows):
        block = E[:, start : start + rows].T @ W  # (rows, n): the rows' E^T W
        out[start : start + block.shape[0]] = (E.T @ block.T).T
    return out


#: The options prefix of the inner solve's KSP (its options live in PETSc's database only
#: while the KSP reads them).
AMG_OPTIONS_PREFIX = "fembem_amg_"


def _set_up(ksp: PETSc.KSP, prefix: str, options: dict) -> None:
    """``ksp`` set up with ``options`` under ``prefix`` (the PC's levels read theirs while
    they are set up), which are then removed from PETSc's global options database again
    (collective)."""
    database = PETSc.Options()
    ksp.setOptionsPrefix(prefix)
    for key, value in options.items():
        database[prefix + key] = value
    try:
        ksp.setFromOptions()
        ksp.setUp()
    finally:
        for key in options:
            database.delValue(prefix + key)


class MultigridPreconditioner(DenseSignoriniBlock):
    """B = diag(K + c T^T M_Gamma T, E^T W_h E) (module docstring), same interface as the
    others (:class:`coupling.preconditioners.base.Preconditioner`), on distributed owned
    arrays.

    Parameters
    ----------
    V
        The P1 space (vector P1 for elasticity; its owned dofs are the entries of u).
    weight
        c of the boundary mass term.
    signorini_metric
        M_s, (n_s, n_s), the same on every rank.
    lattice
        The vertex lattice of the box or of the structured square
        (``fem_py.mesh.box.BoxLattice``): the geometric multigrid on it, with V's block
        size (d components per node for elasticity), when it can be coarsened
        (``lattice_levels``), else (and for ``None``) GAMG.
    rtol, max_iterations
        Of the inner CG + multigrid solve of B_Omega (a solve that stops short raises on every
        rank: B would not be the fixed operator the iterations need).
    pattern
        A P1 Mat on V (``problem.forms.create_matrix()``) whose nonzero structure B_Omega's
        matrix copies (its own values; the boundary mass adds no entries to P1's cell
        pattern) instead of building the pattern again (a few seconds at 2e6 dofs).
        Not referenced afterwards.
    stiffness
        The integrand (w, v) -> UFL of K (default grad w . grad v); for elasticity the
        linear elastic stiffness of the material's tangent at 0
        (``ElasticMaterial.stiffness_integrand``). On a vector space V GAMG gets the rigid
        motions as its near-nullspace (the lattice's interpolation reproduces them).
    """

    def __init__(
        self,
        V: fem.FunctionSpace,
        weight: float,
        signorini_metric: np.ndarray,
        *,
        lattice: BoxLattice | None = None,
        rtol: float,
        max_iterations: int,
        pattern: PETSc.Mat | None = None,
        stiffness: Callable[[Any, Any], Any] | None = None,
    ):
        comm = V.mesh.comm
        w, v = ufl.TrialFunction(V), ufl.TestFunction(V)
        c = fem.Constant(V.mesh, PETSc.ScalarType(weight))
        K = ufl.inner(ufl.grad(w), ufl.grad(v)) if stiffness is None else stiffness(w, v)
        form = compile_form(K * ufl.dx + c * ufl.inner(w, v) * ufl.ds)
        if pattern is None:
            self._matrix = fem.petsc.assemble_matrix(form)
        else:
            self._matrix = pattern.duplicate(copy=False)
            fem.petsc.assemble_matrix(self._matrix, form)
        self._matrix.assemble()
        self._near_nullspace = None
        levels = lattice_levels(lattice.n) if lattice is not None else None
        if levels is None and V.dofmap.index_map_bs > 1:
            # elasticity on GAMG: its aggregates carry the rigid motions
            self._modes = rigid_body_modes(V)
            self._near_nullspace = PETSc.NullSpace().create(vectors=self._modes, comm=comm)
            self._matrix.setNearNullSpace(self._near_nullspace)
        self._ksp = PETSc.KSP().create(comm)
        self._ksp.setOperators(self._matrix)
        self._ksp.setType(PETSc.KSP.Type.CG)
        self._ksp.setOptionsPrefix(AMG_OPTIONS_PREFIX)  # before PCMG names its levels' KSPs
        self._ksp.setTolerances(rtol=rtol, atol=0.0, max_it=max_iterations)
        self._ksp.setInitialGuessNonzero(False)
        self._hierarchy = None
        if levels is None:
            self._ksp.getPC().setType(PETSc.PC.Type.GAMG)
            _set_up(self._ksp, AMG_OPTIONS_PREFIX, AMG_OPTIONS)
        else:
            owned = V.dofmap.index_map.size_local
            points = lattice.indices(V.tabulate_dof_coordinates()[:owned])
            bs = V.dofmap.index_map_bs  # d components per node for elasticity
            self._hierarchy = LatticeHierarchy(self._matrix, points, levels, block_size=bs)
            options = self._hierarchy.configure(self._ksp.getPC())
            _set_up(self._ksp, AMG_OPTIONS_PREFIX, options)
        self._x, self._b = self._matrix.createVecs()
        self.iterations: list[int] = []  # inner CG iterations per application
        self.n_omega = V.dofmap.index_map.size_local * V.dofmap.index_map_bs
        super().__init__(signorini_metric)

    def apply_omega(self, g: np.ndarray) -> np.ndarray:
        self._b.array[:] = g
        self._ksp.solve(self._b, self._x)
        reason = self._ksp.getConvergedReason()
        if reason < 0:  # the same reason on every rank: raised everywhere
            raise RuntimeError(
                "the amg preconditioner's inner CG + multigrid solve failed (PETSc reason "
                f"{reason} after {self._ksp.getIterationNumber()} iterations)"
            )
        self.iterations.append(self._ksp.getIterationNumber())
        return self._x.array.copy()

    def cycle_omega(self, g: np.ndarray) -> np.ndarray:
        """A fixed symmetric positive definite approximation of B_Omega^{-1} g, the same on
        any number of ranks, for preconditioning a Krylov solve: one V-cycle of the lattice
        multigrid (condition number about 1.2 against B_Omega on the scalar box, 1.5-2.5
        for elasticity), else (GAMG) the tight solve ``apply_omega``."""
        if self._hierarchy is None:
            return self.apply_omega(g)
        self._b.array[:] = g
        self._ksp.getPC().apply(self._b, self._x)
        return self._x.array.copy()

    def matvec_omega(self, u: np.ndarray) -> np.ndarray:
        self._x.array[:] = u
        self._matrix.mult(self._x, self._b)
        return self._b.array.copy()

    def destroy(self) -> None:
        for obj in (self._ksp, self._matrix, self._x, self._b):
            obj.destroy()
        if self._near_nullspace is not None:
            self._near_nullspace.destroy()
            for mode in self._modes:
                mode.destroy()
        if self._hierarchy is not None:
            self._hierarchy.destroy()
