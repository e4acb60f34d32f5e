"""Galerkin BEM for the 2D Laplace operator on a closed polygon.

Operators follow the factor-2 convention of METHOD.md section 2 with
G(x, y) = -(1/2 pi) log|x - y|::

    V psi(x) = 2 int G(x, y) psi(y) ds_y,     K v(x) = 2 int d/dn_y G(x, y) v(y) ds_y,
    W v      = -d/dn (K v)   (Galerkin form via Maue's identity, METHOD.md section 9).

Geometry: ``nodes`` is an (n, 2) float64 array of the boundary nodes of Omega in
counter-clockwise order, the first node not repeated at the end; panel j runs from
node j to node j+1 (mod n) and n_j = (t_y, -t_x) is its outward normal (pointing into
the exterior Omega_e). Trace space: continuous piecewise linear hats v_j of the nodes
(P1). Flux space ``"p1"`` (the same hats) or ``"p0"`` (indicator of panel j). Both have
n degrees of freedom.

All functions validate their input and raise ``ValueError`` with a one-line message:
fewer than 3 nodes, wrong shape, non-finite values, repeated consecutive nodes (also
last == first), clockwise orientation, self-intersection, and, where V_h is factorised,
a logarithmic capacity of Gamma >= 1 (V_h not positive definite).

Integration (bem_cpp/include/bem/log_integrals.hpp): coincident and adjacent panel
pairs in closed form (Duffy split of the adjacent square, after which every integral is
an analytic point-segment moment), nearby pairs with an analytic inner integral and a
Gauss outer rule on pieces at least their own length away, distant pairs with tensor
Gauss rules whose size follows from distance/length. Matrix entries agree with 30-digit
mpmath references to better than 1e-12 relative (measured worst cases: 7e-16 for V and
7e-15 for K on polygons with angles from 1 to 311 degrees and on far pairs; 1.3e-14 and
3.4e-13 on a sliver with panel length ratio 5800; tests/test_bem_quadrature.py).
"""
from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bem_cpp import _bem
from bem_cpp._bem import version
from bem_cpp.collectives import mpi_collectives

__all__ = [
    "boundary_operators",
    "BoundaryOperators",
    "double_layer",
    "exterior_flux",
    "exterior_potential",
    "hypersingular",
    "mass",
    "single_layer",
    "steklov_poincare",
    "SteklovPoincareOperator",
    "version",
]

_SPACES = {"p0": _bem.Space.P0, "p1": _bem.Space.P1}


def _space(value: str, name: str) -> _bem.Space:
    try:
        return _SPACES[value]
    except (KeyError, TypeError):
        raise ValueError(f"{name} must be 'p0' or 'p1', got {value!r}") from None


def _points(value: ArrayLike, name: str, rows: str = "m") -> NDArray[np.float64]:
    try:
        arr = np.ascontiguousarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real ({rows}, 2) array") from None
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise ValueError(f"{name} must have shape ({rows}, 2), got {arr.shape}")
    return arr


def _nodes(value: ArrayLike) -> NDArray[np.float64]:
    return _points(value, "nodes", "n")


def _vector(value: ArrayLike, n: int, name: str) -> NDArray[np.float64]:
    try:
        arr = np.ascontiguousarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real array of shape ({n},)") from None
    if arr.shape != (n,):
        raise ValueError(f"{name} must have shape ({n},) (one value per node), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains non-finite values")
    return arr


def _tolerance(value: float) -> float:
    """The relative accuracy ``tol`` of H-matrix blocks: a real number in (0, 1)."""
    tol = _scalar(value, "tol")
    if not 0 < tol < 1:
        raise ValueError(f"tol must lie in (0, 1), got {tol!r}")
    return tol


def _scalar(value: float, name: str) -> float:
    try:
        a = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real number, got {value!r}") from None
    if not np.isfinite(a):
        raise ValueError(f"{name} must be finite, got {a}")
    return a


def single_layer(nodes: ArrayLike, space: str = "p1") -> NDArray[np.float64]:
    r"""Galerkin matrix of the single-layer operator V (METHOD.md section 2).

    .. math:: V_h[i, j] = \langle V\psi_j, \psi_i\rangle
              = -\frac{1}{\pi}\int_\Gamma\int_\Gamma \log|x-y|\,\psi_j(y)\psi_i(x)\,ds_y\,ds_x

    Parameters
    ----------
    nodes : (n, 2) array_like
        Boundary nodes, counter-clockwise, first node not repeated.
    space : {"p1", "p0"}
        Flux space of rows and columns: P1 hats of the nodes or P0 indicators of panels.

    Returns
    -------
    (n, n) ndarray
        Symmetric; positive definite when the logarithmic capacity of Gamma is below 1
        (diam(Omega) < 1 suffices). On the circle of radius R:
        V cos(m theta) = (R/m) cos(m theta), V 1 = -2 R log R.

    Raises
    ------
    ValueError
        Invalid polygon (see the module docstring) or space.
    """
    return _bem.single_layer(_nodes(nodes), _space(space, "space"))


def double_layer(nodes: ArrayLike, space: str = "p1") -> NDArray[np.float64]:
    r"""Galerkin matrix of the double-layer operator K (METHOD.md section 2).

    .. math:: K_h[i, j] = \langle K v_j, \psi_i\rangle
              = \frac{1}{\pi}\int_\Gamma\psi_i(x)\int_\Gamma
                \frac{(x-y)\cdot n_y}{|x-y|^2}\,v_j(y)\,ds_y\,ds_x

    Parameters
    ----------
    nodes : (n, 2) array_like
        Boundary nodes, counter-clockwise, first node not repeated.
    space : {"p1", "p0"}
        Space of the rows (test functions psi_i); the columns are always the P1 hats v_j.

    Returns
    -------
    (n, n) ndarray
        On a polygon K 1 = -1 at every point inside a panel, so
        ``double_layer(nodes, s) @ ones == -mass(nodes, s) @ ones`` up to round-off.

    Raises
    ------
    ValueError
        Invalid polygon (see the module docstring) or space.
    """
    return _bem.double_layer(_nodes(nodes), _space(space, "space"))


def hypersingular(nodes: ArrayLike) -> NDArray[np.float64]:
    r"""Galerkin matrix of the hypersingular operator W on P1 (METHOD.md sections 2, 9).

    Maue's identity on a closed curve, :math:`\langle W u, v\rangle = \langle V u', v'\rangle`
    (u' the arc-length derivative), gives

    .. math:: W_h = D^T V^{(0)}_h D,

    with :math:`V^{(0)}_h` the P0 single-layer matrix and D (n x n) the derivative of the
    hats: row i has -1/h_i at the start node and +1/h_i at the end node of panel i.

    Parameters
    ----------
    nodes : (n, 2) array_like
        Boundary nodes, counter-clockwise, first node not repeated.

    Returns
    -------
    (n, n) ndarray
        Symmetric positive semi-definite, W_h 1 = 0. On the circle of radius R:
        W cos(m theta) = (m/R) cos(m theta).

    Raises
    ------
    ValueError
        Invalid polygon (see the module docstring) or space.
    """
    return _bem.hypersingular(_nodes(nodes))


def mass(nodes: ArrayLike, space: str = "p1") -> NDArray[np.float64]:
    r"""Boundary mass matrix :math:`M_h[i, j] = \int_\Gamma v_j \psi_i\,ds` (METHOD.md section 4).

    Parameters
    ----------
    nodes : (n, 2) array_like
        Boundary nodes, counter-clockwise, first node not repeated.
    space : {"p1", "p0"}
        Space of the rows; columns are the P1 hats. ``"p1"`` gives the P1 Gram matrix
        (element matrix h/6 [[2, 1], [1, 2]]), ``"p0"`` the P0-by-P1 matrix with
        M[i, i] = M[i, i+1] = h_i/2.

    Returns
    -------
    (n, n) ndarray (dense)

    Raises
    ------
    ValueError
        Invalid polygon (see the module docstring) or space.
    """
    return _bem.mass(_nodes(nodes), _space(space, "space"))


_COMPRESSIONS = ("none", "hmatrix")

# H-matrix parameters (docs/design/hmatrix.md explains the choice).
HMATRIX_LEAF_SIZE = 48
HMATRIX_ETA = 2.0
# OpenMP threads of a product (0: all); the set-up uses all. A product is many short
# parallel loops: one thread was 2-3 times faster than two at load 8 on 2 cores
# (docs/design/hmatrix.md); two can be at most 2 times faster on an idle machine.
HMATRIX_PRODUCT_THREADS = 1
# V solves: relative residual solver_tol = HMATRIX_SOLVER_TOL_FACTOR * tol.
HMATRIX_SOLVER_TOL_FACTOR = 1e-3
HMATRIX_MAX_ITERATIONS = 1000
# flux "p0": accuracy of the refined-mesh V0 inside the Calderon preconditioner.
HMATRIX_PRECONDITIONER_TOL = 1e-4
# exterior_potential(compression="auto"): the H-matrix for m points and n dofs when
# m n >= DOFS m + POINTS n, i.e. DOFS / n + POINTS / m <= 1 (the direct sums cost ~ m n,
# the H-matrix ~ DOFS m + POINTS n of those units; fitted to the measured break-even,
# docs/design/hmatrix.md, "Potentials").
HMATRIX_POTENTIAL_CROSSOVER_DOFS = 1300
HMATRIX_POTENTIAL_CROSSOVER_POINTS = 1000
_POTENTIAL_COMPRESSIONS = ("none", "hmatrix", "auto")


def _columnwise(apply, x: ArrayLike, n: int) -> NDArray[np.float64]:
    """``apply`` (of an (n, k) block) to x of shape (n,) or (n, k)."""
    arr = np.asarray(x, dtype=np.float64)
    if arr.ndim not in (1, 2) or arr.shape[0] != n:
        raise ValueError(f"x must have shape ({n},) or ({n}, k), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError("x contains non-finite values")
    y = apply(np.asfortranarray(arr.reshape(n, 1) if arr.ndim == 1 else arr))
    return y[:, 0] if arr.ndim == 1 else y


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
        return _columnwise(self._op.single_layer, x, self._op.size)

    def double_layer(self, x: ArrayLike) -> NDArray[np.float64]:
        """K_h x for x of shape (n,) or (n, k) (nodal values of a P1 trace)."""
        return _columnwise(self._op.double_layer, x, self._op.size)


def boundary_operators(
    nodes: ArrayLike, space: str = "p1", *, tol: float = 1e-10
) -> BoundaryOperators:
    """V_h and K_h of the closed polygon ``nodes`` (counter-clockwise) as H-matrices
    (:class:`BoundaryOperators`): products agree with ``single_layer(nodes, space) @ x``
    and ``double_layer(nodes, space) @ x`` to a few times ``tol``, in O(n log n) memory.

    Raises
    ------
    ValueError
        Bad ``nodes``, ``space`` or ``tol``.
    """
    X = _nodes(nodes)
    tol = _tolerance(tol)
    return BoundaryOperators(
        _bem.BoundaryOperators(
            X,
            _space(space, "space"),
            leaf_size=HMATRIX_LEAF_SIZE,
            eta=HMATRIX_ETA,
            tol=tol,
            product_threads=HMATRIX_PRODUCT_THREADS,
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

    @property
    def last_iterations(self) -> int:
        return int(self._op.last_iterations)

    @property
    def info(self) -> _bem.SteklovInfo:
        return self._op.info

    def __matmul__(self, x: ArrayLike) -> NDArray[np.float64]:
        """S_h x for x of shape (n,) or (n, k) (nodal values of P1 traces)."""
        return _columnwise(self._op.apply, x, self._op.size)

    def flux(self, dirichlet: ArrayLike) -> NDArray[np.float64]:
        """Coefficients of psi_h = V_h^{-1}(K_h - M_h) v (``exterior_flux`` with a = 0)."""
        return _columnwise(self._op.flux, dirichlet, self._op.size)

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
) -> NDArray[np.float64] | SteklovPoincareOperator:
    r"""Discrete Steklov-Poincare operator S_h of the exterior (METHOD.md (2.x), section 4).

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
        to the relative residual 1e-3 tol.
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
        rescale the geometry to diameter < 1).
    """
    args = (_nodes(nodes), _space(flux, "flux"))
    if compression not in _COMPRESSIONS:
        raise ValueError(f"compression must be one of {_COMPRESSIONS}, got {compression!r}")
    if comm is not None and compression != "hmatrix":
        raise ValueError('comm needs compression="hmatrix"')
    if compression == "hmatrix":
        tol = _tolerance(tol)
        allgather, allreduce = mpi_collectives(comm) if comm is not None else (None, None)
        op = SteklovPoincareOperator(
            _bem.SteklovPoincareOperator(
                *args,
                leaf_size=HMATRIX_LEAF_SIZE,
                eta=HMATRIX_ETA,
                tol=tol,
                preconditioner_tol=HMATRIX_PRECONDITIONER_TOL,
                solver_tol=HMATRIX_SOLVER_TOL_FACTOR * tol,
                max_iterations=HMATRIX_MAX_ITERATIONS,
                product_threads=HMATRIX_PRODUCT_THREADS,
                rank=0 if comm is None else comm.rank,
                size=1 if comm is None else comm.size,
                allgather=allgather,
                allreduce=allreduce,
            )
        )
        if timings is not None:
            timings.update(setup=op.info.setup_seconds)
        return op
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


def exterior_flux(
    nodes: ArrayLike, dirichlet: ArrayLike, a: float = 0.0, flux: str = "p1"
) -> NDArray[np.float64]:
    r"""Neumann data of the exterior problem from its Dirichlet trace (METHOD.md section 2).

    Solves the Galerkin system

    .. math:: V_h \psi_h = (K_h - M_h)(v - a)

    for the coefficients of :math:`\psi_h \approx \partial u_e/\partial n` (n pointing
    into the exterior), where u_e is harmonic in Omega_e, u_e = v on Gamma and
    :math:`u_e(x) = a + b\log|x| + o(1)` at infinity with
    :math:`b = \frac{1}{2\pi}\int_\Gamma \psi\,ds` (METHOD.md section 1, note on (1.3)).

    Parameters
    ----------
    nodes : (n, 2) array_like
        Boundary nodes, counter-clockwise, first node not repeated, diam < 1.
    dirichlet : (n,) array_like
        Nodal values of the P1 Dirichlet trace v.
    a : float
        Constant term of u_e at infinity.
    flux : {"p1", "p0"}
        Space of psi_h: coefficient i belongs to node i ("p1") or panel i ("p0").

    Returns
    -------
    (n,) ndarray
        Coefficients of psi_h. For a smooth u_e on a circle the L2(Gamma) error
        converges at O(h^2) (p1) and O(h) (p0); tests/test_bem_exterior.py measures it.
    """
    X = _nodes(nodes)
    v = _vector(dirichlet, X.shape[0], "dirichlet")
    return _bem.exterior_flux(X, v, _scalar(a, "a"), _space(flux, "flux"))


def exterior_potential(
    nodes: ArrayLike,
    dirichlet: ArrayLike,
    flux_coefficients: ArrayLike,
    points: ArrayLike,
    a: float = 0.0,
    flux: str = "p1",
    compression: str = "none",
    tol: float = 1e-10,
) -> NDArray[np.float64]:
    r"""Exterior solution at points of Omega_e by the representation formula (METHOD.md section 2).

    .. math:: u_e(z) = \tfrac12\left(K(v - a) - V\psi\right)(z) + a, \qquad z \in \Omega_e,

    with the potentials :math:`K w(z) = \frac1\pi\int_\Gamma \frac{(z-y)\cdot n_y}{|z-y|^2}
    w(y)\,ds_y` and :math:`V\psi(z) = -\frac1\pi\int_\Gamma \log|z-y|\,\psi(y)\,ds_y`.
    Panels closer to z than a few of their lengths are integrated in closed form
    (analytic log and double-layer panel integrals), the others by Gauss-Legendre rules
    sized from distance/length; the evaluation is therefore exact to round-off for the
    discrete data at any distance from Gamma.

    Accuracy near Gamma: the evaluation is exact to round-off for the discrete data at
    any distance, so the error is that of the data (v, psi_h): O(h^2) at fixed points and
    O(h^2) uniformly up to Gamma, where the formula tends to the piecewise linear trace.
    Measured for u_e = a + b log|x - x0| + c.(x - x0)/|x - x0|^2 on the 256-gon inscribed
    in |x| = 0.4 ("p1"): 2.9e-5 at distance 0.1 from Gamma and at most 3.7e-5 at
    distances 1e-3 ... 1e-9 (off panel midpoints, nodes and other panel points); with
    64 panels 4.7e-4 and 6.0e-4 (tests/test_bem_exterior.py).

    Parameters
    ----------
    nodes : (n, 2) array_like
        Boundary nodes, counter-clockwise, first node not repeated.
    dirichlet : (n,) array_like
        Nodal values of the P1 Dirichlet trace v.
    flux_coefficients : (n,) array_like
        Coefficients of psi_h in the flux space, e.g. from :func:`exterior_flux`.
    points : (m, 2) array_like
        Evaluation points z in the exterior.
    a : float
        Constant term of u_e at infinity (the same as for :func:`exterior_flux`).
    flux : {"p1", "p0"}
        Space of the flux coefficients.
    compression : {"none", "hmatrix", "auto"}
        "none": the direct panel sums, O(m n). "hmatrix": the two potentials as
        rectangular H-matrices from a cluster tree on the points to the dofs (ACA of the
        same point-panel integrals in admissible blocks, the near blocks exact), then two
        products; agrees with "none" to about ``tol`` relative to max |u_e|. "auto":
        "hmatrix" when m n >= ``HMATRIX_POTENTIAL_CROSSOVER_DOFS`` m +
        ``HMATRIX_POTENTIAL_CROSSOVER_POINTS`` n (the measured break-even,
        docs/design/hmatrix.md, "Potentials").
    tol : float
        Relative accuracy of the H-matrix blocks, in (0, 1).

    Returns
    -------
    (m,) ndarray
        u_e(z).

    Raises
    ------
    ValueError
        If a point lies inside Omega or on Gamma (closer than 1e-12 times the
        bounding-box diameter of Gamma). The formula does not give u_e there (inside it
        gives a, on Gamma the jump of the double layer is undefined), so such points are
        rejected rather than flagged; the message counts them and names the first.
    """
    X = _nodes(nodes)
    n = X.shape[0]
    v = _vector(dirichlet, n, "dirichlet")
    psi = _vector(flux_coefficients, n, "flux_coefficients")
    Z = _points(points, "points")
    if not np.all(np.isfinite(Z)):
        raise ValueError("points contains non-finite values")
    if compression not in _POTENTIAL_COMPRESSIONS:
        raise ValueError(
            f"compression must be one of {_POTENTIAL_COMPRESSIONS}, got {compression!r}"
        )
    tol = _tolerance(tol)
    args = (X, v, psi, Z, _scalar(a, "a"), _space(flux, "flux"))
    if compression == "auto":
        m = Z.shape[0]
        cost = HMATRIX_POTENTIAL_CROSSOVER_DOFS * m + HMATRIX_POTENTIAL_CROSSOVER_POINTS * n
        large = m * n >= cost
        compression = "hmatrix" if large else "none"
    if compression == "none" or Z.shape[0] == 0:
        return _bem.exterior_potential(*args)
    return _bem.exterior_potential_hmatrix(
        *args, HMATRIX_LEAF_SIZE, HMATRIX_ETA, tol, HMATRIX_PRODUCT_THREADS
    )
