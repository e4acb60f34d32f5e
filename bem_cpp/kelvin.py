"""Kelvin's solution of linear isotropic elastostatics: the field of a point force in the
whole plane (plane strain) or space, the fundamental solution of the Lame boundary
operators (``kernel=("lame", E, nu)``; docs/method.md section 12). For manufactured
solutions and checks: an exterior field u_e = a + sum of point forces from inside Omega."""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

import bem_cpp._bem as _bem
from bem_cpp import checks


def kelvin_field(
    points: ArrayLike, source: ArrayLike, force: ArrayLike, E: float, nu: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""Displacement and stress of a point force F at x0: :math:`u(x) = U(x - x0) F`,

    .. math:: U(r) = \frac{1}{16\pi\mu(1-\nu)|r|}\Big[(3-4\nu) I + \frac{r r^T}{|r|^2}\Big]
              \ \text{(3D)},\qquad
              U(r) = -\frac{1}{8\pi\mu(1-\nu)}\Big[(3-4\nu)\log|r|\, I
              - \frac{r r^T}{|r|^2}\Big]\ \text{(2D, plane strain)},

    :math:`\mu = E / (2(1+\nu))`, and :math:`\sigma(u) = \lambda\,\mathrm{tr}\,\varepsilon(u) I
    + 2\mu\varepsilon(u)`. It solves :math:`-\mathrm{div}\,\sigma(u) = F\delta_{x_0}`.

    Parameters
    ----------
    points : (k, d) array_like
        Field points x, d = 2 or 3, none at x0.
    source, force : (d,) array_like
        The point x0 and the force F.
    E, nu : float
        Young's modulus (> 0) and Poisson ratio (in (-1, 1/2)).

    Returns
    -------
    u : (k, d) ndarray
    sigma : (k, d, d) ndarray
        Symmetric stress tensors.
    """
    lame = checks.kernel(("lame", E, nu))
    X = np.asarray(points, dtype=np.float64)
    if X.ndim != 2 or X.shape[1] not in (2, 3):
        raise ValueError(f"points must have shape (k, 2) or (k, 3), got {X.shape}")
    d = X.shape[1]
    X = checks.field(X, X.shape[0], d, "points")
    x0 = checks.field(np.reshape(source, (1, -1)), 1, d, "source")[0]
    F = checks.field(np.reshape(force, (1, -1)), 1, d, "force")[0]
    u, sigma = _bem.kelvin_field(lame, X, x0, F)
    return u, sigma.reshape(-1, d, d)
