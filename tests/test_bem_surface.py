"""bem_cpp on closed triangulated surfaces (3D; docs/method.md section 11): input checks, the
dense operators' identities, the Steklov-Poincare operator, the exterior flux and
potential of a decaying harmonic, and the H-matrix operator against the dense one."""
from __future__ import annotations

import numpy as np
import pytest

import bem_cpp
from bem_cpp.surfaces import cube, fichera, icosphere

R = 0.8
X0 = np.array([0.1, -0.2, 0.15])  # inside every surface below


def _zonal(X: np.ndarray, degree: int) -> np.ndarray:
    z = X[:, 2] / np.linalg.norm(X, axis=1)
    return [np.ones_like(z), z, 1.5 * z**2 - 0.5, 2.5 * z**3 - 1.5 * z][degree]


def _orders(errors: list[float]) -> np.ndarray:
    """Orders between successive refinements (the mesh size halves)."""
    return np.log2(np.array(errors[:-1]) / np.array(errors[1:]))


@pytest.mark.parametrize(
    "change,message",
    [
        (lambda X, T: (X, T[:-1]), "open surface: boundary edge"),
        (lambda X, T: (X, np.vstack([T[:5], T[5:6, ::-1], T[6:]])), "inconsistent orientation"),
        (lambda X, T: (X, T[:, ::-1]), "inward orientation"),
        (lambda X, T: (np.vstack([X, X[:1]]), T), "duplicate vertices 0 and 42"),
        (lambda X, T: (np.where(np.arange(len(X))[:, None] == 3, np.nan, X), T), "non-finite"),
        (lambda X, T: (X, np.vstack([T[:7], [[T[7, 0], T[7, 1], T[7, 0]]], T[8:]])), "zero-area"),
        (
            lambda X, T: (
                np.vstack([X, [[3.0, 3.0, 3.0]]]),
                np.vstack([T, [[T[0, 0], T[0, 1], 42]]]),
            ),
            "non-manifold edge",
        ),
        (lambda X, T: (X, T.astype(float)), "integer vertex indices"),
        (lambda X, T: (X[:, :2], T), "vertices must have shape (n, 3)"),
    ],
)
def test_bad_surfaces_are_refused_in_one_line(change, message):
    X, T = change(*icosphere(1))
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")) as e:
        bem_cpp.single_layer(X, "p1", triangles=T)
    assert "\n" not in str(e.value)


def test_vertices_without_triangles_are_named():
    X, _ = icosphere(1)
    with pytest.raises(ValueError, match="vertices of a surface need triangles="):
        bem_cpp.single_layer(X)


@pytest.mark.parametrize("surface", [cube(3), fichera(4)], ids=["cube", "fichera"])
@pytest.mark.parametrize("space", ["p1", "p0"])
def test_double_layer_of_one_is_minus_the_mass(surface, space):
    X, T = surface
    K = bem_cpp.double_layer(X, space, triangles=T)
    M = bem_cpp.mass(X, space, triangles=T)
    one = np.ones(len(X))
    # K 1 = -1 on every face: the error is the quadrature's (docs/design/bem3d.md)
    assert np.max(np.abs(K @ one + M @ one)) <= 2e-4 * np.max(np.abs(M @ one))


def test_symmetry_and_kernel_of_w():
    X, T = icosphere(2, R)
    V = bem_cpp.single_layer(X, "p1", triangles=T)
    V0 = bem_cpp.single_layer(X, "p0", triangles=T)
    W = bem_cpp.hypersingular(X, triangles=T)
    for A in (V, V0, W):
        assert np.max(np.abs(A - A.T)) <= 1e-14 * np.max(np.abs(A))
    assert np.max(np.abs(W @ np.ones(len(X)))) <= 1e-13 * np.max(np.abs(W))
    assert np.linalg.eigvalsh(V)[0] > 0 and np.linalg.eigvalsh(V0)[0] > 0


def test_steklov_poincare_rayleigh_quotients_converge_at_order_two():
    errors = {degree: [] for degree in range(4)}
    for level in (1, 2, 3):
        X, T = icosphere(level, R)
        S = bem_cpp.steklov_poincare(X, triangles=T)
        M = bem_cpp.mass(X, triangles=T)
        if level == 1:
            assert np.array_equal(S, S.T) and np.linalg.eigvalsh(S)[0] > 0
        for degree in range(4):
            u = _zonal(X, degree)
            errors[degree].append(abs(u @ S @ u / (u @ M @ u) - (degree + 1) / R))
    for degree, e in errors.items():
        assert np.all(_orders(e) >= 1.8), (degree, e)


def _harmonic(X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """u = 1/|x - x0| and its normal derivative on the sphere |x| = R (n = x/R)."""
    d = X - X0
    r = np.linalg.norm(d, axis=1)
    return 1.0 / r, -np.einsum("ij,ij->i", d, X / R) / r**3


def test_traces_and_potential_of_a_decaying_harmonic_converge_at_order_two():
    residuals, near_errors, close_errors = [], [], []
    for level in (1, 2, 3):
        X, T = icosphere(level, R)
        v, dudn = _harmonic(X)
        # the traces satisfy V psi = (K - I) v up to the O(h^2) of P1 on flat triangles
        V = bem_cpp.single_layer(X, triangles=T)
        rhs = (bem_cpp.double_layer(X, triangles=T) - bem_cpp.mass(X, triangles=T)) @ v
        residuals.append(np.linalg.norm(V @ dudn - rhs) / np.linalg.norm(rhs))
        psi = bem_cpp.exterior_flux(X, v, triangles=T)
        h = 1.1 * R / 2**level
        directions = np.array([[0.3, 0.5, 0.81], [-0.7, 0.1, 0.2], [0.05, -0.9, -0.4]])
        directions /= np.linalg.norm(directions, axis=1)[:, None]
        for distance, out in ((h, near_errors), (h / 10, close_errors)):
            Z = (R + distance) * directions
            u = bem_cpp.exterior_potential(X, v, psi, Z, triangles=T)
            exact = 1.0 / np.linalg.norm(Z - X0, axis=1)
            out.append(np.max(np.abs(u - exact) / exact))
    assert np.all(_orders(residuals) >= 1.8), residuals
    # at distance >= h from Gamma the potential converges like the data
    assert np.all(_orders(near_errors) >= 1.8), near_errors
    # at h/10, within 10 times the error at h
    assert np.all(np.array(close_errors) <= 10 * np.array(near_errors)), (close_errors, near_errors)


@pytest.mark.parametrize("compression", ["none", "hmatrix"])
def test_potential_refuses_points_inside_or_on_the_surface(compression):
    X, T = icosphere(1, R)
    v, _ = _harmonic(X)
    Z = [[2.0, 0, 0], [0.1, 0, 0]]
    with pytest.raises(ValueError, match=r"point 1 \(.*inside Omega or on Gamma"):
        bem_cpp.exterior_potential(X, v, v, Z, triangles=T, compression=compression)
    with pytest.raises(ValueError, match="point 0"):
        bem_cpp.exterior_potential(X, v, v, X[:1], triangles=T, compression=compression)


@pytest.mark.parametrize("flux", ["p1", "p0"])
def test_compressed_potential_agrees_with_the_direct_sums(flux):
    """The H-matrix potential's admissible blocks take the rule of their closest pair, the
    direct evaluation's or finer, so the two differ by tol and by the direct evaluation's
    quadrature error (about 1e-8 relative at most, at any tol; docs/design/bem3d.md)."""
    X, T = icosphere(4, R)
    v, _ = _harmonic(X)
    psi = np.cos(0.7 * np.arange(len(X) if flux == "p1" else len(T)))
    g = np.linspace(-2.0, 2.0, 40) * R + 0.01
    Z = np.column_stack([c.ravel() for c in np.meshgrid(g, g)] + [np.full(40 * 40, 0.1)])
    Z = Z[np.linalg.norm(Z, axis=1) > 1.01 * R]
    args = (X, v, psi, Z)
    direct = bem_cpp.exterior_potential(*args, a=0.2, flux=flux, triangles=T)
    for tol, bound in ((1e-6, 1e-6), (1e-8, 3e-8)):
        compressed = bem_cpp.exterior_potential(
            *args, a=0.2, flux=flux, triangles=T, compression="hmatrix", tol=tol
        )
        assert np.abs(compressed - direct).max() <= bound * np.abs(direct).max()


@pytest.mark.parametrize(
    "surface,compressed",
    [(icosphere(4, R), True), (icosphere(3, R), False), (cube(16), True), (fichera(16), True)],
    ids=["sphere", "small-sphere", "cube", "fichera"],
)
def test_hmatrix_steklov_poincare_agrees_with_the_dense_one(surface, compressed):
    """(Below about 1,000 vertices the admissible blocks are too small for a low-rank block
    to pay at tol 1e-10: the small sphere checks the tree, the near field and the far pairs
    of the dense blocks. On the flat faces of the cube and Fichera's corner the double
    layer's kernel vanishes between coplanar points, which ACA on that kernel missed:
    products were 2e-4 .. 2e-3 off at any tol until ACA ran on the sub-blocks between
    different planes only.)"""
    X, T = surface
    S = bem_cpp.steklov_poincare(X, triangles=T)
    op = bem_cpp.steklov_poincare(X, triangles=T, compression="hmatrix")
    x = np.random.default_rng(3).standard_normal((len(X), 2))
    assert op.shape == S.shape and (op.info.max_rank > 0) == compressed
    assert np.linalg.norm(op @ x - S @ x) <= 1e-8 * np.linalg.norm(S @ x)
    if compressed:  # (S x holds V^-1 (K - M) x; the dense flux would assemble V, K again)
        return
    psi = bem_cpp.exterior_flux(X, x[:, 0], triangles=T)
    assert np.linalg.norm(op.flux(x[:, 0]) - psi) <= 1e-8 * np.linalg.norm(psi)


@pytest.mark.parametrize("planar", [False, True], ids=["cube", "circle"])
def test_a_looser_solver_tol_gives_a_cheaper_product_within_it(planar):
    """S.apply(x, solver_tol): the V solve of the product to solver_tol where that is looser
    than the operator's own (fewer iterations, the product within solver_tol times the
    preconditioned V's conditioning, tens, of S @ x); None or a tighter one is S @ x."""
    if planar:
        theta = 2 * np.pi * np.arange(2400) / 2400
        op = bem_cpp.steklov_poincare(
            0.4 * np.stack([np.cos(theta), np.sin(theta)], 1), compression="hmatrix"
        )
    else:
        X, T = cube(12)
        op = bem_cpp.steklov_poincare(X, triangles=T, compression="hmatrix", tol=1e-6)
    x = np.random.default_rng(4).standard_normal(op.shape[0])
    exact = op @ x
    own = op.last_iterations
    for solver_tol in (1e-3, 1e-6):
        y = op.apply(x, solver_tol)
        assert op.last_iterations < own
        assert 0 < np.linalg.norm(y - exact) <= 100 * solver_tol * np.linalg.norm(exact)
    np.testing.assert_array_equal(op.apply(x), exact)
    np.testing.assert_array_equal(op.apply(x, 1e-30), exact)
    with pytest.raises(ValueError, match="solver_tol must lie in"):
        op.apply(x, 2.0)
    if not planar:  # S 0 = 0 with no V solve (a Newton step's first product often is one)
        np.testing.assert_array_equal(op.apply(np.zeros_like(x), 1e-3), 0.0)
        assert op.last_iterations == 0


def test_preconditioned_single_layer_solves_take_a_bounded_number_of_iterations():
    iterations = []
    for level in (1, 2, 3):
        X, T = icosphere(level, R)
        op = bem_cpp.steklov_poincare(X, triangles=T, compression="hmatrix")
        op @ (_zonal(X, 1) + np.sin(3 * X[:, 0]))
        iterations.append(op.last_iterations)
    assert max(iterations) <= iterations[0] + 3, iterations


def test_hypersingular_block_read_from_the_hmatrix_equals_the_integrated_one():
    """E^T W_h E on the interior nodes of a face of the cube (Gamma_s of a box), read from
    the blocks of S_h's H-matrix of W_h: the integrated block to the H-matrix tolerance,
    symmetric (symmetric storage; the diagonal blocks to round-off); bad indices and an
    S_h without W_h on P1 nodes (a polygon's) are refused."""
    X, T = cube(16)
    low = X[:, 2].min()
    edge = np.abs(X[:, :2]).max(axis=0) - 1e-9
    face = np.flatnonzero((X[:, 2] == low) & (np.abs(X[:, :2]) < edge).all(axis=1))
    assert len(face) == 15**2
    op = bem_cpp.steklov_poincare(X, triangles=T, compression="hmatrix", tol=1e-10)
    block = op.hypersingular_block(face)
    integrated = bem_cpp.hypersingular(X, triangles=T, block=face)
    assert np.linalg.norm(block - integrated) <= 1e-8 * np.linalg.norm(integrated)
    assert np.abs(block - block.T).max() <= 1e-15 * np.abs(block).max()
    with pytest.raises(ValueError, match="distinct"):
        op.hypersingular_block([0, 0])
    circle = np.c_[np.cos(np.linspace(0, 2 * np.pi, 64, endpoint=False)), np.zeros(64)]
    circle[:, 1] = np.sin(np.linspace(0, 2 * np.pi, 64, endpoint=False))
    planar = bem_cpp.steklov_poincare(circle, compression="hmatrix")
    assert not planar.holds_hypersingular
    with pytest.raises(TypeError, match="no H-matrix of W_h"):
        planar.hypersingular_block([0, 1])
