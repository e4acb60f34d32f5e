"""The exterior solution at points of Omega_e by the representation formula
(docs/method.md section 2), by direct panel sums or rectangular H-matrices."""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

import bem_cpp._bem as _bem
from bem_cpp import checks, defaults


def exterior_potential(
    nodes: ArrayLike,
    dirichlet: ArrayLike,
    flux_coefficients: ArrayLike,
    points: ArrayLike,
    a: float = 0.0,
    flux: str = "p1",
    compression: str = "none",
    tol: float = 1e-10,
    *,
    triangles: ArrayLike | None = None,
    kernel: str | tuple = "laplace",
) -> NDArray[np.float64]:
    r"""Exterior solution at points of Omega_e by the representation formula
    (docs/method.md section 2).

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
    Measured errors: docs/design/quadrature.md, "Potentials near Gamma".

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
    triangles : (m, 3) array_like of int, optional
        3D: the triangles of the surface whose vertices are ``nodes`` (n, 3); ``points``
        (k, 3); G = 1/(4 pi |x - y|), each triangle split into four until z is 1.5 of
        its diameters from every piece (docs/design/bem3d.md). "none": direct sums over
        the triangles, points inside Omega or on Gamma found by the solid angle of Gamma
        (4 pi inside, 0 outside); "hmatrix": rectangular H-matrices of the same
        point-triangle integrals, the solid angle from the compressed double layer of
        the constant 1; "auto": "hmatrix" from
        ``HMATRIX_SURFACE_POTENTIAL_VERTICES`` vertices and
        ``HMATRIX_SURFACE_POTENTIAL_POINTS`` points on (the measured break-even,
        docs/design/bem3d.md, "The exterior potential").
    kernel : "laplace" or ("lame", E, nu)
        Kelvin's kernel (:func:`exterior_stress`): u_e is the displacement of the exterior
        elastic medium, ``dirichlet`` (n, d) and ``flux_coefficients`` (n or m, d) its
        trace and traction sigma(u_e) n, ``a`` (d,) the translation at infinity; the
        double-layer kernel is the traction of Kelvin's solution (Somigliana's identity).
        Direct sums only (``compression="none"``), every panel or triangle split near z as
        above.

    Returns
    -------
    (m,) ndarray, or (m, d) for the Lame kernel
        u_e(z).

    Raises
    ------
    ValueError
        If a point lies inside Omega or on Gamma (closer than 1e-12 times the
        bounding-box diameter of Gamma). The formula does not give u_e there (inside it
        gives a, on Gamma the jump of the double layer is undefined), so such points are
        rejected rather than flagged; the message counts them and names the first.
    """
    if compression not in defaults.POTENTIAL_COMPRESSIONS:
        raise ValueError(
            f"compression must be one of {defaults.POTENTIAL_COMPRESSIONS}, got {compression!r}"
        )
    tol = checks.tolerance(tol)
    lame = checks.kernel(kernel)
    if lame is not None:
        if compression == "hmatrix":
            raise ValueError(
                'the Lame kernel\'s potential is summed directly: use compression="none"'
            )
        return _lame(
            "displacement", nodes, triangles, lame, dirichlet, flux_coefficients, points, a, flux
        )
    if triangles is not None:
        return _surface_potential(
            checks.surface(nodes, triangles),
            dirichlet,
            flux_coefficients,
            points,
            a,
            flux,
            compression,
            tol,
        )
    X = checks.nodes(nodes)
    n = X.shape[0]
    v = checks.vector(dirichlet, n, "dirichlet")
    psi = checks.vector(flux_coefficients, n, "flux_coefficients")
    Z = checks.points(points, "points")
    if not np.all(np.isfinite(Z)):
        raise ValueError("points contains non-finite values")
    args = (X, v, psi, Z, checks.scalar(a, "a"), checks.space(flux, "flux"))
    m = Z.shape[0]
    cost = (
        defaults.HMATRIX_POTENTIAL_CROSSOVER_DOFS * m
        + defaults.HMATRIX_POTENTIAL_CROSSOVER_POINTS * n
    )
    layout = (defaults.HMATRIX_LEAF_SIZE, defaults.HMATRIX_ETA)
    return _evaluate(args, m, compression, m * n >= cost, layout, tol)


def _evaluate(
    args: tuple, points: int, compression: str, large: bool, layout: tuple[int, float], tol: float
) -> NDArray[np.float64]:
    """The direct sums or the H-matrices (leaf size and eta ``layout``) on the checked
    ``args`` of ``points`` points; "auto" takes the H-matrices when ``large``."""
    if compression == "auto":
        compression = "hmatrix" if large else "none"
    if compression == "none" or points == 0:
        return _bem.exterior_potential(*args)
    return _bem.exterior_potential_hmatrix(*args, *layout, tol, defaults.HMATRIX_PRODUCT_THREADS)


def _surface_potential(
    geometry: tuple[NDArray[np.float64], NDArray[np.int64]],
    dirichlet: ArrayLike,
    flux_coefficients: ArrayLike,
    points: ArrayLike,
    a: float,
    flux: str,
    compression: str,
    tol: float,
) -> NDArray[np.float64]:
    """:func:`exterior_potential` of a closed surface (checked ``compression`` and ``tol``)."""
    space = checks.space(flux, "flux")
    v = checks.vector(dirichlet, geometry[0].shape[0], "dirichlet")
    psi = checks.vector(flux_coefficients, checks.dofs(geometry, space), "flux_coefficients")
    Z = checks.points(points, "points", "k", dim=3)
    if not np.all(np.isfinite(Z)):
        raise ValueError("points contains non-finite values")
    args = (*geometry, v, psi, Z, checks.scalar(a, "a"), space)
    large = (
        geometry[0].shape[0] >= defaults.HMATRIX_SURFACE_POTENTIAL_VERTICES
        and Z.shape[0] >= defaults.HMATRIX_SURFACE_POTENTIAL_POINTS
    )
    layout = (
        defaults.HMATRIX_SURFACE_POTENTIAL_LEAF_SIZE,
        defaults.HMATRIX_SURFACE_POTENTIAL_ETA,
    )
    return _evaluate(args, Z.shape[0], compression, large, layout, tol)


def exterior_stress(
    nodes: ArrayLike,
    dirichlet: ArrayLike,
    traction: ArrayLike,
    points: ArrayLike,
    a: ArrayLike = 0.0,
    flux: str = "p1",
    *,
    kernel: tuple,
    triangles: ArrayLike | None = None,
) -> NDArray[np.float64]:
    r"""Stress of the exterior elastic medium at points of Omega_e (docs/method.md
    section 12): :math:`\sigma(u_e)(z) = \lambda\,\mathrm{div}\,u_e\, I + \mu(\nabla u_e +
    \nabla u_e^T)` of the representation formula :math:`u_e = \tfrac12(K(v - a) - V t) + a`
    (:func:`exterior_potential` with the same arguments), by the second derivatives of
    Kelvin's solution, folded so that every kernel stays bounded as nu -> 1/2.

    Accuracy: O(h^2) at a fixed distance from Gamma for data (v, t) accurate to O(h^2);
    at a distance delta the data's error, which oscillates on the scale h, is amplified
    like h / delta (the stress is one derivative more than the displacement): O(h) at
    delta ~ h/10.

    Parameters
    ----------
    nodes, dirichlet, traction, points, a, flux, triangles
        As for :func:`exterior_potential` with the Lame kernel (``traction`` its
        ``flux_coefficients``).
    kernel : ("lame", E, nu)
        The exterior medium.

    Returns
    -------
    (m, d, d) ndarray
        Symmetric stress tensors.
    """
    lame = checks.kernel(kernel)
    if lame is None:
        raise ValueError('exterior_stress needs kernel=("lame", E, nu)')
    return _lame("stress", nodes, triangles, lame, dirichlet, traction, points, a, flux)


def _lame(
    what: str,
    nodes: ArrayLike,
    triangles: ArrayLike | None,
    lame: _bem.Lame,
    dirichlet: ArrayLike,
    traction: ArrayLike,
    points: ArrayLike,
    a: ArrayLike,
    flux: str,
) -> NDArray[np.float64]:
    """The displacement (m, d) or stress (m, d, d) of the exterior elastic medium ``lame``
    at ``points`` (direct sums, compiled)."""
    geometry = checks.boundary(nodes, triangles)
    d = checks.components(lame, geometry)
    space = checks.space(flux, "flux")
    v = checks.field(dirichlet, geometry[0].shape[0], d, "dirichlet")
    t = checks.field(traction, checks.dofs(geometry, space), d, "traction")
    Z = checks.points(points, "points", "k", dim=d)
    if not np.all(np.isfinite(Z)):
        raise ValueError("points contains non-finite values")
    args = (*geometry, lame, v.ravel(), t.ravel(), Z, checks.translation(a, d), space)
    if what == "displacement":
        return _bem.lame_exterior_displacement(*args)
    return _bem.lame_exterior_stress(*args).reshape(-1, d, d)
