"""The Lame boundary operators through the Python API (``kernel=("lame", E, nu)``,
docs/method.md section 12): shapes and node-major dofs, the rigid motions, symmetry and
definiteness, the Laplace operators unchanged, the refusals, and the exterior elastic
field of a point force (Kelvin's solution) from inside Omega: its traction from its trace
(exterior_flux) and the field outside from both (the representation formula), at O(h^2).
The compiled operators' own checks (Calderon identities, nu -> 1/2) are GoogleTests
(bem_cpp/tests/test_lame_polygon.cpp, test_lame_surface.cpp, test_lame_potentials.cpp)."""
from __future__ import annotations

import numpy as np
import pytest

import bem_cpp
from bem_cpp.kelvin import kelvin_field
from bem_cpp.polygons import circle, l_shape
from bem_cpp.surfaces import fichera, icosphere
from test_bem_operators import observed_order

E, NU = 2.0, 0.3
LAME = ("lame", E, NU)


def rigid_motions(x: np.ndarray) -> np.ndarray:
    """(d n, 3) in 2D or (d n, 6) in 3D: the translations and rotations at the nodes x,
    node-major."""
    n, d = x.shape
    modes = [np.tile(np.eye(d)[k], n) for k in range(d)]
    if d == 2:
        modes.append(np.c_[-x[:, 1], x[:, 0]].ravel())
    else:
        for k in range(3):
            w = np.eye(3)[k]
            modes.append(np.cross(w, x).ravel())
    return np.array(modes).T


GEOMETRIES = {
    "circle": lambda: (circle(48), None),
    "l_shape": lambda: (l_shape(48), None),
    "sphere": lambda: icosphere(1, radius=0.5),
    "fichera": lambda: fichera(2, side=0.6),
}


@pytest.fixture(scope="module", params=list(GEOMETRIES))
def operators(request):
    x, triangles = GEOMETRIES[request.param]()
    kw = dict(triangles=triangles, kernel=LAME)
    V = bem_cpp.single_layer(x, "p1", **kw)
    K = bem_cpp.double_layer(x, "p1", **kw)
    W = bem_cpp.hypersingular(x, **kw)
    M = bem_cpp.mass(x, "p1", **kw)
    S = bem_cpp.steklov_poincare(x, "p1", **kw)
    return x, triangles, V, K, W, M, S


def test_shapes_symmetry_and_definiteness(operators):
    x, triangles, V, K, W, M, S = operators
    n, d = x.shape
    for A in (V, K, W, M, S):
        assert A.shape == (d * n, d * n)
    # V and W are symmetric to round-off, S exactly (symmetrised)
    assert np.abs(V - V.T).max() <= 1e-13 * np.abs(V).max()
    assert np.abs(W - W.T).max() <= 1e-13 * np.abs(W).max()
    assert np.array_equal(S, S.T)
    assert np.linalg.eigvalsh(V).min() > 0
    assert np.linalg.eigvalsh(S).min() > 0
    # the mass matrix is the scalar one on each component
    assert np.array_equal(M[::d, ::d], bem_cpp.mass(x, "p1", triangles=triangles))


def test_rigid_motions(operators):
    """W r = 0 and K r = -M r for every rigid motion r; the exterior fixes them:
    <S r, r> > 0. To round-off in 2D, and for the translations in 3D (their Gunter
    derivatives and surface curls vanish triangle by triangle); in 3D a rotation's do not,
    and W r, K r + M r vanish through integrals over the whole surface: to the Sauter-Schwab
    rules' accuracy (measured 6e-8 on the sphere, 9e-6 on the cube relative to ||W|| ||r||;
    K r + M r 2e-5 of M r, bem_cpp/tests/test_lame_surface.cpp)."""
    x, _, V, K, W, M, S = operators
    d = x.shape[1]
    R = rigid_motions(x)
    scale = np.linalg.norm(W, 2) * np.linalg.norm(R, axis=0)
    rotations = 1e-12 if d == 2 else 2e-5
    assert (np.linalg.norm(W @ R[:, :d], axis=0) <= 1e-12 * scale[:d]).all()
    assert (np.linalg.norm(W @ R[:, d:], axis=0) <= rotations * scale[d:]).all()
    tol = 1e-12 if d == 2 else 5e-5
    assert np.linalg.norm(K @ R + M @ R, axis=0).max() <= tol * np.linalg.norm(M @ R, axis=0).min()
    assert (np.einsum("ik,ij,jk->k", R, S, R) > 0).all()


def test_laplace_is_the_default_and_unchanged():
    x = circle(24)
    assert np.array_equal(bem_cpp.single_layer(x), bem_cpp.single_layer(x, kernel="laplace"))
    X, T = icosphere(1, radius=0.5)
    assert np.array_equal(
        bem_cpp.hypersingular(X, triangles=T),
        bem_cpp.hypersingular(X, triangles=T, kernel="laplace"),
    )


@pytest.mark.parametrize(
    "kernel, message",
    [
        ("lame", "kernel must be"),
        (("lame", 2.0), "kernel must be"),
        (("helmholtz", 1.0, 0.3), "kernel must be"),
        (("lame", 0.0, 0.3), "Young's modulus"),
        (("lame", 1.0, 0.5), "Poisson's ratio"),
        (("lame", 1.0, -1.0), "Poisson's ratio"),
        (("lame", "x", 0.3), "E must be a real number"),
    ],
)
def test_bad_kernels_are_refused_in_one_line(kernel, message):
    with pytest.raises(ValueError, match=message) as err:
        bem_cpp.single_layer(circle(12), kernel=kernel)
    assert "\n" not in str(err.value)


def test_a_large_plane_boundary_is_refused_with_the_fix():
    """The 2D Lame V_h is elliptic only on a small enough boundary (as the Laplace V_h
    below logarithmic capacity 1): a circle of radius 5 is refused in one line that names
    the factor s* to scale it by; on the circle s* R -> exp(1 / (2 (3 - 4 nu))) = 1.3202,
    and the circle scaled by just below s* is accepted, just above it refused."""
    x = circle(32, radius=5.0)
    with pytest.raises(ValueError, match="scale the geometry by a factor below") as err:
        bem_cpp.steklov_poincare(x, kernel=LAME)
    factor = float(str(err.value).split("factor below ")[1].split()[0])
    assert factor * 5.0 == pytest.approx(np.exp(1 / (2 * (3 - 4 * NU))), rel=5e-3)
    assert np.linalg.eigvalsh(bem_cpp.steklov_poincare(0.999 * factor * x, kernel=LAME)).min() > 0
    with pytest.raises(ValueError, match="not positive definite"):
        bem_cpp.exterior_flux(1.001 * factor * x, np.zeros((32, 2)), kernel=LAME)


def test_data_of_the_wrong_shape_is_refused():
    x = circle(16)
    with pytest.raises(ValueError, match=r"dirichlet must have shape \(16, 2\)"):
        bem_cpp.exterior_flux(x, np.zeros(16), kernel=LAME)
    with pytest.raises(ValueError, match="a must have 2 components"):
        bem_cpp.exterior_flux(x, np.zeros((16, 2)), a=[1.0, 2.0, 3.0], kernel=LAME)
    with pytest.raises(ValueError, match="comm needs compression"):
        bem_cpp.steklov_poincare(x, kernel=LAME, comm=object())


@pytest.mark.parametrize("make, flux", [(circle, "p1"), (l_shape, "p1"), (l_shape, "p0")])
def test_the_compressed_plane_operator_agrees_with_the_dense_one(make, flux):
    """S_h as H-matrices (compression="hmatrix", tol 1e-10) against the dense S_h: products
    and tractions to a few times tol; its V solves' CG counts stay bounded as h -> 0."""
    iterations = []
    for n in (200, 400, 800):
        x = make(n)
        S = bem_cpp.steklov_poincare(x, flux, kernel=LAME)
        H = bem_cpp.steklov_poincare(x, flux, kernel=LAME, compression="hmatrix", tol=1e-10)
        assert H.shape == S.shape == (2 * n, 2 * n)
        z = np.random.default_rng(n).standard_normal((2 * n, 2))
        assert np.linalg.norm(H @ z - S @ z) <= 1e-8 * np.linalg.norm(S @ z)
        iterations.append(H.last_iterations)
        t = bem_cpp.exterior_flux(x, z[:, 0].reshape(n, 2), flux=flux, kernel=LAME)
        assert np.linalg.norm(H.flux(z[:, 0]) - t.ravel()) <= 1e-8 * np.linalg.norm(t)
    # measured 10 (circle, P1), 12 (P0), 21-23 (L-shape) from 200 to 3,200 nodes
    assert max(iterations) <= iterations[0] + 3, iterations


# A point force and a force dipole from inside Omega: u_e = a + U(x - x0) F + (a dipole)
SOURCES = {2: ([0.05, -0.03], [1.0, -0.5]), 3: ([0.05, -0.03, 0.02], [1.0, -0.5, 0.3])}
DIPOLE = 1e-2


def kelvin_exterior(x: np.ndarray, a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """u_e and sigma(u_e) at the points x of a point force F at x0 and a force dipole (F at
    x0 + eps e_1 against -F at x0 - eps e_1, divided by 2 eps), plus the translation a."""
    d = x.shape[1]
    x0, F = (np.array(v) for v in SOURCES[d])
    e = DIPOLE * np.eye(d)[0]
    u, s = kelvin_field(x, x0, F, E, NU)
    up, sp = kelvin_field(x, x0 + e, F, E, NU)
    um, sm = kelvin_field(x, x0 - e, F, E, NU)
    return a + u + (up - um) / (2 * DIPOLE), s + (sp - sm) / (2 * DIPOLE)


def outward_normals(x: np.ndarray, triangles) -> np.ndarray:
    """Area-weighted nodal normals (polygon: of the two panels; surface: of the star)."""
    if triangles is None:
        t = np.roll(x, -1, axis=0) - x
        n = np.c_[t[:, 1], -t[:, 0]]
        n = n + np.roll(n, 1, axis=0)
    else:
        p = x[triangles]
        f = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        n = np.zeros_like(x)
        for k in range(3):
            np.add.at(n, triangles[:, k], f)
    return n / np.linalg.norm(n, axis=1)[:, None]


@pytest.mark.parametrize("dim", [2, 3])
def test_kelvin_field_outside_from_its_trace_at_order_two(dim):
    """The exterior problem of a Kelvin field: the traction from the trace (exterior_flux,
    V t = (K - I)(v - a)), then u_e and sigma(u_e) at fixed exterior points by the
    representation formula (exterior_potential, exterior_stress) converge at O(h^2)."""
    a = np.array([0.2, -0.1, 0.3][:dim])
    Z = np.array([[0.9, 0.2, -0.3], [-0.4, -0.8, 0.5], [0.2, 0.9, 0.9]])[:, :dim]
    u_ex, s_ex = kelvin_exterior(Z, a)
    h, errors, stress_errors = [], [], []
    for level in range(3):
        if dim == 2:
            x, triangles = circle(32 * 2**level, radius=0.4), None
        else:
            x, triangles = icosphere(level + 1, radius=0.4)
        kw = dict(triangles=triangles, kernel=LAME)
        v, _ = kelvin_exterior(x, a)
        t = bem_cpp.exterior_flux(x, v, a, **kw)
        u = bem_cpp.exterior_potential(x, v, t, Z, a, **kw)
        s = bem_cpp.exterior_stress(x, v, t, Z, a, **kw)
        assert u.shape == (3, dim) and s.shape == (3, dim, dim)
        assert np.abs(s - s.transpose(0, 2, 1)).max() <= 1e-12 * np.abs(s).max()
        h.append(0.4 * 2 * np.pi / (32 * 2**level) if dim == 2 else 0.45 / 2**level)
        errors.append(np.abs(u - u_ex).max())
        stress_errors.append(np.abs(s - s_ex).max())
    assert observed_order(h, errors) >= 1.8, errors
    assert observed_order(h, stress_errors) >= 1.8, stress_errors
    assert errors[-1] <= 1e-2 * np.abs(u_ex - a).max()


def test_rigid_data_give_the_translation_outside():
    """Dirichlet data a (a translation) give no traction and u_e = a outside; a rotation
    of the trace is no exterior field (rotations at infinity are excluded): its traction
    is not zero."""
    x = circle(48)
    a = np.array([0.3, -0.2])
    t = bem_cpp.exterior_flux(x, np.tile(a, (48, 1)), a, kernel=LAME)
    assert np.abs(t).max() <= 1e-12
    u = bem_cpp.exterior_potential(x, np.tile(a, (48, 1)), t, [[1.0, 1.0]], a, kernel=LAME)
    assert np.abs(u - a).max() <= 1e-14
    rotation = np.c_[-x[:, 1], x[:, 0]]
    assert np.abs(bem_cpp.exterior_flux(x, rotation, kernel=LAME)).max() > 0.1


def test_the_compressed_surface_operator_agrees_with_the_dense_one():
    """The 3D Lame S_h as H-matrices (tol 1e-8) against the dense S_h on the sphere and the
    Fichera corner: products to a few times tol (measured 2e-9 on the level-3 sphere), the
    V solves' CG counts bounded over the sphere's refinements. At tol 1e-5 (the 3D runs'
    tolerances: ``coupling.options.hmatrix_tol``) the blocks are held in single precision
    (round-off 6e-8, far below tol) and the products still agree to a few times tol."""
    iterations = []
    for X, T in (icosphere(1, radius=0.5), icosphere(2, radius=0.5), fichera(4, side=0.6)):
        S = bem_cpp.steklov_poincare(X, triangles=T, kernel=LAME)
        z = np.random.default_rng(len(X)).standard_normal((S.shape[0], 2))
        for tol in (1e-8, 1e-5):
            H = bem_cpp.steklov_poincare(
                X, triangles=T, kernel=LAME, compression="hmatrix", tol=tol
            )
            assert H.single_precision == (tol >= 1e-6)
            assert np.linalg.norm(H @ z - S @ z) <= 10 * tol * np.linalg.norm(S @ z)
        iterations.append(H.last_iterations)
    assert iterations[1] <= iterations[0] + 3, iterations
    with pytest.raises(ValueError, match='needs flux="p1"'):
        bem_cpp.steklov_poincare(X, "p0", triangles=T, kernel=LAME, compression="hmatrix")


def test_the_surface_operators_hypersingular_block_equals_the_integrated_one():
    """The 3D Lame W_h's block on the vector dofs of some nodes (a cap of the sphere of 642
    vertices, 101 nodes in a scattered order), read from S_h's H-matrices of Z and W_L (tol
    1e-6: low-rank far blocks, largest rank 44): the integrated block
    (``bem_cpp.hypersingular(..., block=)``) to the H-matrix tolerance (measured 2.2e-9
    relative; the blocks in single precision), a float64 array, node-major, symmetric to
    round-off (5e-17); bad nodes are refused, and the
    polygon's operator (W_h = D^T X0 D, not held on the nodes) holds none."""
    X, T = icosphere(3, radius=0.5)
    cap = np.flatnonzero(X[:, 2] < X[:, 2].min() + 0.15)[::-1]
    H = bem_cpp.steklov_poincare(X, triangles=T, kernel=LAME, compression="hmatrix", tol=1e-6)
    assert H.holds_hypersingular and H.single_precision and H.info.max_rank > 0
    block = H.hypersingular_block(cap)
    integrated = bem_cpp.hypersingular(X, triangles=T, block=cap, kernel=LAME)
    assert block.shape == integrated.shape == (3 * len(cap), 3 * len(cap))
    assert np.linalg.norm(block - integrated) <= 1e-6 * np.linalg.norm(integrated)
    assert block.dtype == np.float64
    assert np.abs(block - block.T).max() <= 1e-14 * np.abs(block).max()
    with pytest.raises(ValueError, match="distinct"):
        H.hypersingular_block([0, 0])
    with pytest.raises(ValueError, match="must lie in"):
        H.hypersingular_block([len(X)])
    plane = bem_cpp.steklov_poincare(circle(200), kernel=LAME, compression="hmatrix")
    assert not plane.holds_hypersingular
    with pytest.raises(TypeError, match="no H-matrix of W_h"):
        plane.hypersingular_block([0, 1])
