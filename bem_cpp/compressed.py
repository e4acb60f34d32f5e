"""Operators held as H-matrices and applied, never formed: V_h and K_h
(:class:`BoundaryOperators`) and the Steklov-Poincare operator S_h
(:class:`SteklovPoincareOperator`, or the dense S_h; docs/method.md section 2,
docs/design/hmatrix.md)."""
from __future__ import annotations

import time
from typing import Any

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

import bem_cpp._bem as _bem
from bem_cpp import checks, defaults
from bem_cpp.collectives import mpi_collectives
from bem_cpp.dense import SingleMatrix, release_free_heap
from bem_cpp.operators import cholesky, lame_cholesky


class _CompiledOperator:
    """A compiled n x n operator of bem_cpp: its shape and the bytes it holds."""

    def __init__(self, compiled: _bem.BoundaryOperators | _bem.SteklovPoincareOperator) -> None:
        self._op = compiled

    @property
    def shape(self) -> tuple[int, int]:
        return (self._op.size, self._op.size)

    @property
    def nbytes(self) -> int:
        return int(self._op.nbytes)


class BoundaryOperators(_CompiledOperator):
    r"""V_h and K_h (:func:`single_layer`, :func:`double_layer`) held as H-matrices and
    applied, never formed: ACA blocks to the relative tolerance ``tol``, the near field
    exact (docs/design/hmatrix.md). Built by :func:`boundary_operators`.

    Attributes
    ----------
    shape : (n, n)
    nbytes : int
        Bytes held by the two H-matrices.
    """

    def single_layer(self, x: ArrayLike) -> NDArray[np.float64]:
        """V_h x for x of shape (n,) or (n, k) (coefficients in the space of the operators)."""
        return checks.columnwise(self._op.single_layer, x, self._op.size)

    def double_layer(self, x: ArrayLike) -> NDArray[np.float64]:
        """K_h x for x of shape (n,) or (n, k) (nodal values of a P1 trace)."""
        return checks.columnwise(self._op.double_layer, x, self._op.size)


def boundary_operators(
    nodes: ArrayLike,
    space: str = "p1",
    *,
    tol: float = 1e-10,
    triangles: ArrayLike | None = None,
) -> BoundaryOperators:
    """V_h and K_h of the closed polygon ``nodes`` (counter-clockwise) as H-matrices
    (:class:`BoundaryOperators`): products agree with ``single_layer(nodes, space) @ x``
    and ``double_layer(nodes, space) @ x`` to a few times ``tol``, in O(n log n) memory.
    3D (``triangles`` given, ``space="p1"`` only): those of the surface's H-matrix S_h
    (``steklov_poincare(..., compression="hmatrix")``, its V_h and K_h held alone; its set-up
    also builds W_h and the V solve's preconditioner).

    Raises
    ------
    ValueError
        Bad ``nodes``, ``triangles``, ``space`` or ``tol``.
    """
    if triangles is not None:
        geometry = checks.boundary(nodes, triangles)
        checks.space(space, "space")
        if space != "p1":
            raise ValueError('boundary_operators on a surface needs space="p1"')
        tol = checks.tolerance(tol)
        return BoundaryOperators(
            _bem.SurfaceSteklovOperator(
                *geometry,
                leaf_size=defaults.HMATRIX_SURFACE_LEAF_SIZE,
                eta=defaults.HMATRIX_SURFACE_ETA,
                tol=tol,
                solver_tol=defaults.HMATRIX_SOLVER_TOL_FACTOR * tol,
                max_iterations=defaults.HMATRIX_MAX_ITERATIONS,
                product_threads=defaults.HMATRIX_PRODUCT_THREADS,
                rank=0,
                size=1,
                allgather=None,
                allreduce=None,
            )
        )
    X = checks.nodes(nodes)
    tol = checks.tolerance(tol)
    return BoundaryOperators(
        _bem.BoundaryOperators(
            X,
            checks.space(space, "space"),
            leaf_size=defaults.HMATRIX_LEAF_SIZE,
            eta=defaults.HMATRIX_ETA,
            tol=tol,
            product_threads=defaults.HMATRIX_PRODUCT_THREADS,
        )
    )


class SteklovPoincareOperator(_CompiledOperator):
    r"""S_h applied as an operator, never formed (docs/design/hmatrix.md).

    .. math:: S x = \tfrac12\left(W x + (K - M)^T V^{-1} (K - M) x\right),
              \qquad W x = D^T V^{(0)} D x,

    with V (flux space), :math:`V^{(0)}` (P0, Maue's identity for W) and K held as
    H-matrices (ACA blocks to the relative tolerance ``tol``, near field exact), M and D
    sparse, and :math:`V^{-1}` by conjugate gradients with a Calderon preconditioner
    (W on a trace space paired with the flux space; bounded iteration counts). Built by
    :func:`steklov_poincare` with ``compression="hmatrix"``.

    Distributed (``comm`` of :func:`steklov_poincare`): each rank holds the blocks of its
    own rows of V, V0 and K (V, V0 in symmetric storage: the blocks on and above the
    diagonal), and every product is collective, with the same result on every rank: K x
    is the local rows and one Allgatherv; V x, V0 x and K^T y are partial sums and one
    Allreduce (on more than 2 ranks Reduce_scatter and Allgatherv, so that every rank gets
    the same bits).

    Attributes
    ----------
    shape : (n, n)
    nbytes : int
        Bytes held (H-matrix blocks, permutations, preconditioner factors); distributed,
        this rank's.
    last_iterations : int
        CG iterations of the V solve in the last product.
    info : object
        ``setup_seconds``, ``max_rank`` and the bytes per part
        (``nbytes_v``, ``nbytes_v0``, ``nbytes_k``, ``nbytes_preconditioner``).
    """

    dtype = np.dtype(np.float64)

    def __init__(self, compiled: _bem.SteklovPoincareOperator, *, single_precision: bool = False):
        super().__init__(compiled)
        #: whether the H-matrix blocks are held in single precision (a surface's at the
        #: tolerances ``defaults.HMATRIX_SINGLE_PRECISION_MIN_TOL`` and looser)
        self.single_precision = bool(single_precision)

    @property
    def last_iterations(self) -> int:
        return int(self._op.last_iterations)

    @property
    def info(self) -> _bem.SteklovInfo:
        return self._op.info

    def __matmul__(self, x: ArrayLike) -> NDArray[np.float64]:
        """S_h x for x of shape (n,) or (n, k) (nodal values of P1 traces)."""
        return checks.columnwise(self._op.apply, x, self._op.size)

    def apply(self, x: ArrayLike, solver_tol: float | None = None) -> NDArray[np.float64]:
        """S_h x with the V solve to the relative residual ``solver_tol`` where that is
        looser than the operator's own (1e-3 tol; None or a tighter one: as ``S @ x``). The
        looser solve makes a cheaper product with an error of about ``solver_tol`` relative
        to ``S @ x``: for the products inside an outer iteration that needs only a few
        digits (the CG of a Newton step, ``coupling.solvers.ssn``)."""
        if solver_tol is None:
            return self @ x
        solver_tol = checks.tolerance(solver_tol, "solver_tol")
        return checks.columnwise(
            lambda X: self._op.apply(X, solver_tol=solver_tol), x, self._op.size
        )

    def flux(self, dirichlet: ArrayLike) -> NDArray[np.float64]:
        """Coefficients of psi_h = V_h^{-1}(K_h - M_h) v (``exterior_flux`` with a = 0)."""
        return checks.columnwise(self._op.flux, dirichlet, self._op.size)

    @property
    def holds_hypersingular(self) -> bool:
        """Whether W_h is held as H-matrices on the P1 nodes (a surface's S_h, Laplace's or
        Lame's), so that :meth:`hypersingular_block` can read blocks of it."""
        held = getattr(self._op, "holds_hypersingular", None)  # Lame's: its surface's only
        return hasattr(self._op, "hypersingular_block") if held is None else bool(held)

    def hypersingular_block(self, indices: ArrayLike) -> NDArray[np.float64] | SingleMatrix:
        """W_h[indices, indices] = E^T W_h E (k, k) read from the H-matrix of W_h (to its
        tolerance), in O(k^2 r) work instead of integrating the block again (a surface's S_h
        only: :attr:`holds_hypersingular`; collective when distributed, the same on every
        rank). In the precision of the blocks: a float64 array, or, when they are held in
        single precision (:attr:`single_precision`), a :class:`bem_cpp.dense.SingleMatrix`
        (its entries carry the blocks' rounding already; half the memory).

        Lame's S_h (3D): ``indices`` are nodes, and the block is the (3 k, 3 k) one of their
        vector dofs ``3 * node + component``, node-major (Z's principal submatrix plus
        2 mu W_L's Kronecker I_3; lame_surface_steklov.hpp), a float64 array in either
        precision of the blocks (the gap's frames still turn it, ``coupling``'s M_s)."""
        if not self.holds_hypersingular:
            raise TypeError("hypersingular_block: this S_h holds no H-matrix of W_h on P1 nodes")
        d = getattr(self._op, "dimension", 1)  # Lame's operator: d components per node
        indices = checks.indices(indices, self._op.size // d, "indices")
        if self.single_precision and d == 1:  # Eigen's column-major: its transpose, C order
            return SingleMatrix(self._op.hypersingular_block_single(indices).T)
        return self._op.hypersingular_block(indices)

    def __repr__(self) -> str:
        n = self._op.size
        return f"SteklovPoincareOperator(n={n}, nbytes={self.nbytes})"


def steklov_poincare(
    nodes: ArrayLike,
    flux: str = "p1",
    *,
    compression: str = "none",
    tol: float = 1e-10,
    timings: dict[str, float] | None = None,
    comm: Any = None,
    triangles: ArrayLike | None = None,
    kernel: str | tuple = "laplace",
) -> NDArray[np.float64] | SteklovPoincareOperator:
    r"""Discrete Steklov-Poincare operator S_h of the exterior (docs/method.md (2.x), section 4).

    .. math:: S_h = \tfrac12\left(W_h + (K_h - M_h)^T V_h^{-1}(K_h - M_h)\right),

    rows and columns in the P1 trace space, V_h, K_h, M_h with rows in the flux space.
    Computed with the Cholesky factor :math:`V_h = L L^T` as :math:`Y = L^{-1}(K_h - M_h)`,
    :math:`S_h = \tfrac12(W_h + Y^T Y)` (LAPACK dpotrf, dtrsm, dsyrk), and symmetrised
    explicitly, so ``S == S.T`` exactly.

    Parameters
    ----------
    nodes : (n, 2) array_like
        Boundary nodes, counter-clockwise, first node not repeated, diam < 1.
    flux : {"p1", "p0"}
        Flux space of V_h and of the rows of K_h, M_h.
    compression : {"none", "hmatrix"}
        ``"none"``: the dense matrix above. ``"hmatrix"``: a
        :class:`SteklovPoincareOperator` that applies S_h with H-matrices of V_h, V0_h
        (for W_h) and K_h and a preconditioned CG solve with V_h, in O(n log n) memory
        and time per product (docs/design/hmatrix.md); products agree with the dense S_h
        to about ``tol`` relative.
    tol : float
        Relative accuracy of the H-matrix blocks (``"hmatrix"`` only); the V solves run
        to the relative residual 1e-3 tol. A surface's blocks are held in single precision
        (products summed in double) when tol >= ``defaults.HMATRIX_SINGLE_PRECISION_MIN_TOL``.
    timings : dict, optional
        If given, filled with the wall-clock seconds of the stages ``assembly``
        (V_h, K_h, W_h), ``cholesky``, ``triangular_solve`` and ``rank_update``
        (``"none"``), or ``setup`` (``"hmatrix"``).
    comm : mpi4py communicator, optional
        ``"hmatrix"`` only: build the operator distributed over ``comm`` (collective; the
        same ``nodes`` on every rank). Each rank holds the blocks of its rows in the
        cluster-tree order (about 1/P of the bytes of V, V0, K; the rows balanced by
        bytes), and ``S @ x``, ``S.flux(v)`` are collective and return the same array on
        every rank (docs/design/hmatrix.md, "Under MPI").
    triangles : (m, 3) array_like of int, optional
        3D: the triangles of the closed surface whose vertices are ``nodes`` (n, 3)
        (docs/method.md section 11). ``compression`` may then also be ``"auto"`` (the H-matrix
        from ``HMATRIX_SURFACE_AUTO_DOFS`` vertices on); ``"hmatrix"`` needs the P1 flux
        and preconditions the V solves by M^{-1} (W + c c^T) M^{-1} (docs/design/bem3d.md);
        dense, V_h is factorised by Cholesky (scipy) and S_h symmetrised explicitly.
    kernel : "laplace" or ("lame", E, nu)
        Laplace's kernel, or Kelvin's of linear elasticity (Young's modulus E, Poisson ratio
        nu; plane strain in 2D): S_h of the exterior elastic medium, (d n, d n) on the
        node-major dofs ``d * node + component``, the same formula with the Lame V_h, K_h,
        W_h (:func:`bem_cpp.single_layer` and the others with ``kernel``), dense
        (``compression="none"``, or ``"auto"`` at any size); V_h is factorised by Cholesky
        (scipy). Symmetric positive definite: the exterior fixes the rigid motions.

    Returns
    -------
    (n, n) ndarray or SteklovPoincareOperator
        Symmetric positive definite. On the circle of radius R < 1:
        S cos(m theta) = (m/R) cos(m theta), S 1 = -1/(R log R).

    Raises
    ------
    ValueError
        Invalid polygon, unknown compression, tol not in (0, 1), ``comm`` without
        ``"hmatrix"``, or V_h not positive definite (logarithmic capacity of Gamma >= 1;
        rescale the geometry to diameter < 1; for the Lame kernel in 2D its own capacity
        condition, docs/method.md section 12).
    """
    lame = checks.kernel(kernel)
    if lame is not None:
        return _lame_steklov_poincare(
            checks.boundary(nodes, triangles), flux, lame, compression, tol, timings, comm
        )
    if triangles is not None:
        return _surface_steklov_poincare(
            checks.surface(nodes, triangles), flux, compression, tol, timings, comm
        )
    args = (checks.nodes(nodes), checks.space(flux, "flux"))
    if compression not in defaults.COMPRESSIONS:
        raise ValueError(f"compression must be one of {defaults.COMPRESSIONS}, got {compression!r}")
    if comm is not None and compression != "hmatrix":
        raise ValueError('comm needs compression="hmatrix"')
    if compression == "hmatrix":
        tol = checks.tolerance(tol)
        return _compressed_operator(
            _bem.SteklovPoincareOperator,
            args,
            comm,
            timings,
            tol=tol,
            leaf_size=defaults.HMATRIX_LEAF_SIZE,
            eta=defaults.HMATRIX_ETA,
            preconditioner_tol=defaults.HMATRIX_PRECONDITIONER_TOL,
        )
    if timings is None:
        return _bem.steklov_poincare(*args)
    S, t = _bem.steklov_poincare_timed(*args)
    timings.update(
        assembly=t.assembly,
        cholesky=t.cholesky,
        triangular_solve=t.triangular_solve,
        rank_update=t.rank_update,
    )
    return S


def _surface_steklov_poincare(
    geometry: tuple[NDArray[np.float64], NDArray[np.int64]],
    flux: str,
    compression: str,
    tol: float,
    timings: dict[str, float] | None,
    comm: Any,
) -> NDArray[np.float64] | SteklovPoincareOperator:
    """:func:`steklov_poincare` of a closed surface (its ``triangles`` given)."""
    space = checks.space(flux, "flux")
    if compression not in defaults.SURFACE_COMPRESSIONS:
        raise ValueError(
            f"compression must be one of {defaults.SURFACE_COMPRESSIONS}, got {compression!r}"
        )
    if compression == "auto":
        large = geometry[0].shape[0] >= defaults.HMATRIX_SURFACE_AUTO_DOFS
        compression = "hmatrix" if large else "none"
    if comm is not None and compression != "hmatrix":
        raise ValueError('comm needs compression="hmatrix"')
    if compression == "none":
        return _dense_surface_steklov_poincare(geometry, space, timings)
    if flux != "p1":
        raise ValueError('compression="hmatrix" on a surface needs flux="p1"')
    tol = checks.tolerance(tol)
    return _compressed_operator(
        _bem.SurfaceSteklovOperator,
        geometry,
        comm,
        timings,
        tol=tol,
        leaf_size=defaults.HMATRIX_SURFACE_LEAF_SIZE,
        eta=defaults.HMATRIX_SURFACE_ETA,
        single_precision=tol >= defaults.HMATRIX_SINGLE_PRECISION_MIN_TOL,
    )


def _compressed_operator(
    kind: Any, args: tuple, comm: Any, timings: dict[str, float] | None, *, tol: float, **params
) -> SteklovPoincareOperator:
    """The H-matrix S_h of the compiled class ``kind`` on the geometry ``args``, with the
    solver defaults of ``bem_cpp.defaults``, distributed by rows over ``comm`` (or serial);
    its set-up time into ``timings``."""
    allgather, allreduce = mpi_collectives(comm) if comm is not None else (None, None)
    op = SteklovPoincareOperator(
        kind(
            *args,
            tol=tol,
            solver_tol=defaults.HMATRIX_SOLVER_TOL_FACTOR * tol,
            max_iterations=defaults.HMATRIX_MAX_ITERATIONS,
            product_threads=defaults.HMATRIX_PRODUCT_THREADS,
            rank=0 if comm is None else comm.rank,
            size=1 if comm is None else comm.size,
            allgather=allgather,
            allreduce=allreduce,
            **params,
        ),
        single_precision=params.get("single_precision", False),
    )
    release_free_heap()  # the set-up's freed scratch back to the system
    if timings is not None:
        timings.update(setup=op.info.setup_seconds)
    return op


def _lame_steklov_poincare(
    geometry: tuple,
    flux: str,
    lame: _bem.Lame,
    compression: str,
    tol: float,
    timings: dict[str, float] | None,
    comm: Any,
) -> NDArray[np.float64] | SteklovPoincareOperator:
    """:func:`steklov_poincare` with Kelvin's kernel ``lame``: dense, or H-matrices
    (``"auto"``: from ``HMATRIX_LAME_AUTO_NODES`` nodes of a polygon on, from
    ``HMATRIX_SURFACE_AUTO_DOFS`` vertices of a surface, as for Laplace's kernel)."""
    space = checks.space(flux, "flux")
    if compression not in defaults.SURFACE_COMPRESSIONS:
        raise ValueError(
            f"compression must be one of {defaults.SURFACE_COMPRESSIONS}, got {compression!r}"
        )
    surface = len(geometry) == 2
    if compression == "auto":
        auto = defaults.HMATRIX_SURFACE_AUTO_DOFS if surface else defaults.HMATRIX_LAME_AUTO_NODES
        compression = "hmatrix" if geometry[0].shape[0] >= auto else "none"
    if comm is not None and compression != "hmatrix":
        raise ValueError('comm needs compression="hmatrix"')
    if compression == "hmatrix":
        if surface and flux != "p1":
            raise ValueError('compression="hmatrix" on a surface needs flux="p1"')
        tol = checks.tolerance(tol)
        layout = dict(
            leaf_size=defaults.HMATRIX_SURFACE_LEAF_SIZE,
            eta=defaults.HMATRIX_SURFACE_ETA,
            single_precision=tol >= defaults.HMATRIX_SINGLE_PRECISION_MIN_TOL,
        )
        if not surface:
            layout = dict(
                leaf_size=defaults.HMATRIX_LEAF_SIZE,
                eta=defaults.HMATRIX_ETA,
                preconditioner_tol=defaults.HMATRIX_PRECONDITIONER_TOL,
            )
        return _compressed_operator(
            _bem.LameSteklovOperator,
            (*geometry, lame, space),
            comm,
            timings,
            tol=tol,
            **layout,
        )
    d = checks.components(lame, geometry)
    return _dense_steklov_poincare(
        lambda: _bem.lame_operators(*geometry, lame, space),
        lambda: np.kron(_bem.mass(*geometry, space), np.eye(d)),
        timings,
        lambda V: lame_cholesky(V, geometry, lame, space),
    )


def _dense_surface_steklov_poincare(
    geometry: tuple[NDArray[np.float64], NDArray[np.int64]],
    space: _bem.Space,
    timings: dict[str, float] | None,
) -> NDArray[np.float64]:
    """S_h of Laplace's kernel on a surface (dense)."""
    return _dense_steklov_poincare(
        lambda: _bem.surface_operators(*geometry, space),
        lambda: _bem.mass(*geometry, space),
        timings,
        cholesky,
    )


def _dense_steklov_poincare(
    operators: Any, mass: Any, timings: dict[str, float] | None, factor: Any
) -> NDArray[np.float64]:
    """S_h = 1/2 (W_h + Y^T Y), Y = L^{-1} (K_h - M_h), V_h = L L^T (dense), from
    ``operators()`` = (V_h, K_h, W_h), ``mass()`` = M_h and ``factor(V_h)`` = L."""
    t0 = time.perf_counter()
    V, K, W = operators()
    B = K - mass()
    t1 = time.perf_counter()
    L = factor(V)
    t2 = time.perf_counter()
    Y = scipy.linalg.solve_triangular(L, B, lower=True)
    t3 = time.perf_counter()
    S = 0.5 * (W + Y.T @ Y)
    S = 0.5 * (S + S.T)
    if timings is not None:
        timings.update(
            assembly=t1 - t0,
            cholesky=t2 - t1,
            triangular_solve=t3 - t2,
            rank_update=time.perf_counter() - t3,
        )
    return S
