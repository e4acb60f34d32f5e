"""Dense Galerkin matrices of the boundary integral operators (V_h, K_h, W_h, M_h) and the
exterior Neumann data from a Dirichlet trace (docs/method.md sections 2 and 11).

Every function takes the boundary of a 2D domain, ``nodes`` (n, 2) of a polygon, or of a
3D domain, ``nodes`` (n, 3) the vertices of a closed triangulated surface with
``triangles`` (m, 3) (counter-clockwise seen from outside). In 3D G = 1/(4 pi |x - y|)
with the same factor-2 convention (V = 2 int G psi), P1 has n dofs (the vertices), P0 m
(the triangles); pairs of triangles sharing a vertex, an edge or the triangle are
integrated by Sauter-Schwab rules, the others by Gauss rules raised for near pairs
(docs/design/bem3d.md). ``ValueError`` names an open, non-manifold, inconsistently or
inward oriented surface, duplicate vertices, zero-area triangles, non-finite coordinates.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg
from typing import Callable

from numpy.typing import ArrayLike, NDArray

import bem_cpp._bem as _bem
from bem_cpp import checks


def single_layer(
    nodes: ArrayLike,
    space: str = "p1",
    *,
    triangles: ArrayLike | None = None,
    kernel: str | tuple = "laplace",
) -> NDArray[np.float64]:
    r"""Galerkin matrix of the single-layer operator V (docs/method.md section 2).

    .. math:: V_h[i, j] = \langle V\psi_j, \psi_i\rangle
              = -\frac{1}{\pi}\int_\Gamma\int_\Gamma \log|x-y|\,\psi_j(y)\psi_i(x)\,ds_y\,ds_x

    Parameters
    ----------
    nodes : (n, 2) array_like
        Boundary nodes, counter-clockwise, first node not repeated.
    space : {"p1", "p0"}
        Flux space of rows and columns: P1 hats of the nodes or P0 indicators of panels.
    triangles : (m, 3) array_like of int, optional
        3D: the triangles of the surface whose vertices are ``nodes`` (n, 3).
    kernel : "laplace" or ("lame", E, nu)
        Laplace's kernel, or Kelvin's of linear elasticity with Young's modulus E and
        Poisson ratio nu (plane strain in 2D; :mod:`bem_cpp` module docstring): then every
        node carries d components, dof ``d * node + component``, and the matrix is
        (d rows, d columns) times as large.

    Returns
    -------
    (n, n) ndarray
        Symmetric; positive definite when the logarithmic capacity of Gamma is below 1
        (diam(Omega) < 1 suffices). On the circle of radius R:
        V cos(m theta) = (R/m) cos(m theta), V 1 = -2 R log R. 3D: symmetric positive
        definite for every surface; on the sphere V Y_l = 2R/(2l+1) Y_l.

    Raises
    ------
    ValueError
        Invalid polygon (see the module docstring) or space.
    """
    geometry = checks.boundary(nodes, triangles)
    return _compiled("single_layer", geometry, checks.kernel(kernel), checks.space(space, "space"))


def double_layer(
    nodes: ArrayLike,
    space: str = "p1",
    *,
    triangles: ArrayLike | None = None,
    kernel: str | tuple = "laplace",
) -> NDArray[np.float64]:
    r"""Galerkin matrix of the double-layer operator K (docs/method.md section 2).

    .. math:: K_h[i, j] = \langle K v_j, \psi_i\rangle
              = \frac{1}{\pi}\int_\Gamma\psi_i(x)\int_\Gamma
                \frac{(x-y)\cdot n_y}{|x-y|^2}\,v_j(y)\,ds_y\,ds_x

    Parameters
    ----------
    nodes : (n, 2) or (n, 3) array_like
        The boundary, as in :func:`single_layer`.
    space : {"p1", "p0"}
        Space of the rows (test functions psi_i); the columns are always the P1 hats v_j.
    triangles : (m, 3) array_like of int, optional
        3D: the surface's triangles, as in :func:`single_layer`.
    kernel : "laplace" or ("lame", E, nu)
        As in :func:`single_layer` (Lame: d dofs a node, the matrix d x d times as large).

    Returns
    -------
    (n, n) ndarray
        On a polygon K 1 = -1 at every point inside a panel, so
        ``double_layer(nodes, s) @ ones == -mass(nodes, s) @ ones`` up to round-off. 3D:
        (dofs of the rows, n); K 1 = -1 on Gamma, so the same holds to the quadrature's
        accuracy; on the sphere K Y_l = -1/(2l+1) Y_l.

    Raises
    ------
    ValueError
        Invalid polygon (see the module docstring) or space.
    """
    geometry = checks.boundary(nodes, triangles)
    return _compiled("double_layer", geometry, checks.kernel(kernel), checks.space(space, "space"))


def hypersingular(
    nodes: ArrayLike,
    *,
    triangles: ArrayLike | None = None,
    block: ArrayLike | None = None,
    kernel: str | tuple = "laplace",
) -> NDArray[np.float64]:
    r"""Galerkin matrix of the hypersingular operator W on P1 (docs/method.md sections 2, 9).

    Maue's identity on a closed curve, :math:`\langle W u, v\rangle = \langle V u', v'\rangle`
    (u' the arc-length derivative), gives

    .. math:: W_h = D^T V^{(0)}_h D,

    with :math:`V^{(0)}_h` the P0 single-layer matrix and D (n x n) the derivative of the
    hats: row i has -1/h_i at the start node and +1/h_i at the end node of panel i.

    Parameters
    ----------
    nodes : (n, 2) or (n, 3) array_like
        The boundary, as in :func:`single_layer`.
    triangles : (m, 3) array_like of int, optional
        3D: the surface's triangles, as in :func:`single_layer`.
    block : (k,) array_like of int, optional
        Distinct node indices: only W_h[block, block] = E^T W_h E is returned (E the
        injection of the hats of ``block``). In 3D it is integrated over the triangles
        that touch those nodes alone, at a cost set by their number, not the surface's
        (for the nodes inside a surface patch, the H~^{1/2} metric of the patch).
        Lame: the d components of each of those nodes (sliced from the whole matrix).
    kernel : "laplace" or ("lame", E, nu)
        As in :func:`single_layer` (Lame: d dofs a node, the matrix d x d times as large).

    Returns
    -------
    (n, n) ndarray, or (k, k) with ``block``
        Symmetric positive semi-definite, W_h 1 = 0. On the circle of radius R:
        W cos(m theta) = (m/R) cos(m theta). 3D: by Nedelec's identity
        <W u, v> = <V curl u, curl v> (docs/method.md section 11); on the sphere
        W Y_l = 2 l (l+1) / ((2l+1) R) Y_l.

    Raises
    ------
    ValueError
        Invalid polygon (see the module docstring) or space.
    """
    geometry = checks.boundary(nodes, triangles)
    lame = checks.kernel(kernel)
    if block is None:
        return _compiled("hypersingular", geometry, lame)
    rows = checks.indices(block, geometry[0].shape[0], "block")
    if triangles is not None and lame is None:
        return _bem.hypersingular_block(*geometry, rows)
    d = checks.components(lame, geometry)
    rows = (d * rows[:, None] + np.arange(d)).ravel()
    return np.ascontiguousarray(_compiled("hypersingular", geometry, lame)[np.ix_(rows, rows)])


def mass(
    nodes: ArrayLike,
    space: str = "p1",
    *,
    triangles: ArrayLike | None = None,
    kernel: str | tuple = "laplace",
) -> NDArray[np.float64]:
    r"""Boundary mass matrix :math:`M_h[i, j] = \int_\Gamma v_j \psi_i\,ds`
    (docs/method.md section 4).

    Parameters
    ----------
    nodes : (n, 2) or (n, 3) array_like
        The boundary, as in :func:`single_layer`.
    space : {"p1", "p0"}
        Space of the rows; columns are the P1 hats. ``"p1"`` gives the P1 Gram matrix
        (element matrix h/6 [[2, 1], [1, 2]]), ``"p0"`` the P0-by-P1 matrix with
        M[i, i] = M[i, i+1] = h_i/2.
    triangles : (m, 3) array_like of int, optional
        3D: the surface's triangles, as in :func:`single_layer`.
    kernel : "laplace" or ("lame", E, nu)
        As in :func:`single_layer` (Lame: d dofs a node, the matrix d x d times as large).

    Returns
    -------
    (n, n) ndarray (dense)

    Raises
    ------
    ValueError
        Invalid polygon (see the module docstring) or space.
    """
    geometry = checks.boundary(nodes, triangles)
    d = checks.components(checks.kernel(kernel), geometry)
    M = _bem.mass(*geometry, checks.space(space, "space"))
    return M if d == 1 else np.kron(M, np.eye(d))


def exterior_flux(
    nodes: ArrayLike,
    dirichlet: ArrayLike,
    a: float = 0.0,
    flux: str = "p1",
    *,
    triangles: ArrayLike | None = None,
    kernel: str | tuple = "laplace",
) -> NDArray[np.float64]:
    r"""Neumann data of the exterior problem from its Dirichlet trace (docs/method.md section 2).

    Solves the Galerkin system

    .. math:: V_h \psi_h = (K_h - M_h)(v - a)

    for the coefficients of :math:`\psi_h \approx \partial u_e/\partial n` (n pointing
    into the exterior), where u_e is harmonic in Omega_e, u_e = v on Gamma and
    :math:`u_e(x) = a + b\log|x| + o(1)` at infinity with
    :math:`b = \frac{1}{2\pi}\int_\Gamma \psi\,ds` (docs/method.md section 1, note on (1.3)).

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
    triangles : (m, 3) array_like of int, optional
        3D: the triangles of the surface whose vertices are ``nodes`` (n, 3); there
        u_e = a + O(1/|x|) at infinity and V_h is factorised by Cholesky (dense).
    kernel : "laplace" or ("lame", E, nu)
        Kelvin's kernel: u_e is the displacement of the exterior elastic medium (Young's
        modulus E, Poisson ratio nu, plane strain in 2D), ``dirichlet`` (n, d) its nodal
        values, ``a`` (d,) the translation at infinity, and psi_h its traction
        sigma(u_e) n; in 2D u_e = a + U(x) F + O(1/|x|) with F the net force on Gamma
        (docs/method.md section 12). V_h by Cholesky (dense).

    Returns
    -------
    (n,) ndarray, or (n, d) for the Lame kernel
        Coefficients of psi_h (P0: one per panel or triangle). For a smooth u_e on a
        circle the L2(Gamma) error converges at O(h^2) (p1) and O(h) (p0);
        tests/test_bem_exterior.py measures it.
    """
    geometry = checks.boundary(nodes, triangles)
    space, lame = checks.space(flux, "flux"), checks.kernel(kernel)
    if lame is not None:
        d = checks.components(lame, geometry)
        v = checks.field(dirichlet, geometry[0].shape[0], d, "dirichlet")
        a = checks.translation(a, d)
        B = _compiled("double_layer", geometry, lame, space)
        B -= np.kron(_bem.mass(*geometry, space), np.eye(d))
        L = lame_cholesky(_compiled("single_layer", geometry, lame, space), geometry, lame, space)
        return scipy.linalg.cho_solve((L, True), B @ (v - a).ravel()).reshape(-1, d)
    v = checks.vector(dirichlet, geometry[0].shape[0], "dirichlet")
    a = checks.scalar(a, "a")
    if triangles is None:
        return _bem.exterior_flux(*geometry, v, a, space)
    V, K, _ = _bem.surface_operators(*geometry, space)
    rhs = (K - _bem.mass(*geometry, space)) @ (v - a)
    return scipy.linalg.cho_solve(scipy.linalg.cho_factor(V), rhs)


def cholesky(
    V: NDArray[np.float64], critical_scale: Callable[[], float] | None = None
) -> NDArray[np.float64]:
    """The lower Cholesky factor of the single-layer matrix V_h, or a one-line ``ValueError``
    when V_h is not positive definite: in 2D the boundary is then too large for the
    kernel's capacity condition (docs/method.md sections 2 and 12). ``critical_scale()``:
    the factor s* below which the scaled boundary has a positive definite V_h (named in
    the message)."""
    try:
        return scipy.linalg.cholesky(V, lower=True)
    except np.linalg.LinAlgError:
        fix = "scale the geometry down (diameter below 1)"
        if critical_scale is not None:
            fix = f"scale the geometry by a factor below {critical_scale():.4g}"
        raise ValueError(
            "the single-layer matrix V_h is not positive definite on this boundary: in 2D the"
            f" boundary is too large for the kernel's capacity condition; {fix} and the data"
            " with it"
        ) from None


def lame_cholesky(
    V: NDArray[np.float64], geometry: tuple, lame: _bem.Lame, space: _bem.Space
) -> NDArray[np.float64]:
    """:func:`cholesky` of the Lame V_h, whose refusal on a plane boundary names the
    critical scale (docs/method.md section 12)."""
    if len(geometry) == 2:
        return cholesky(V)
    return cholesky(V, lambda: _bem.lame_critical_scale(*geometry, lame, space))


def _compiled(name: str, geometry: tuple, lame: _bem.Lame | None, *args):
    """The compiled function ``name`` on the checked ``geometry``: Laplace's (``lame`` None),
    or its Lame twin ``lame_<name>`` with the medium after the geometry."""
    if lame is None:
        return getattr(_bem, name)(*geometry, *args)
    return getattr(_bem, "lame_" + name)(*geometry, lame, *args)
