"""The geometric multigrid of a vertex lattice, the box's or the structured square's
(coupling/preconditioners/lattice_multigrid.py): its levels, the bilinear / trilinear
prolongation and its Kronecker product with I_d for elasticity, and one V-cycle as a fixed
symmetric positive definite operator, spectrally close to B_Omega^{-1} and the same on 1, 2
and 3 ranks, for the scalar problem and elasticity."""
from __future__ import annotations

import numpy as np
import pytest
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from conftest import ROOT, run_mpi
from coupling.options import AMG_MAX_ITERATIONS, AMG_RTOL, SolverOptions
from coupling.preconditioners import build_preconditioner
from coupling.preconditioners.lattice_multigrid import (
    gershgorin_bound,
    lattice_levels,
    multilinear_prolongation,
)
from coupling.preconditioners.multigrid import MultigridPreconditioner
from coupling.problem import SignoriniProblem
from coupling.solvers import solve
from fem_py.forms import make_material
from fem_py.forms.elasticity import linear_elastic
from fem_py.mesh import GeometrySpec, build_domain

COMM = MPI.COMM_WORLD


def test_levels():
    assert lattice_levels(64) == [64, 32, 16, 8, 4]
    assert lattice_levels(96) == [96, 48, 24, 12, 6, 3]
    assert lattice_levels(10) == [10, 5]
    assert lattice_levels(4) is None  # nothing coarser
    assert lattice_levels(45) is None  # odd: not halved
    assert lattice_levels(34) is None  # a coarsest lattice of 17 cubes per side
    assert lattice_levels(34, coarsest=17) == [34, 17]


def test_prolongation_is_exact_on_trilinear_functions():
    m = 3
    coarse = np.stack(np.meshgrid(*[np.arange(m + 1)] * 3, indexing="ij"), -1).reshape(-1, 3)
    fine = np.stack(np.meshgrid(*[np.arange(2 * m + 1)] * 3, indexing="ij"), -1).reshape(-1, 3)

    def trilinear(p):  # products of affine functions of each coordinate
        x, y, z = p.T.astype(float)
        return (1 + 2 * x) * (3 - y) * (0.5 + z) + x * y - 4 * z

    # the coarse values in lexicographic order (i fastest), the columns' numbering
    lexicographic = coarse[np.lexsort(coarse.T[::-1])][:, ::-1]
    values = trilinear(lexicographic)
    P = multilinear_prolongation(MPI.COMM_SELF, fine, fine.shape[0], m)
    x, y = P.createVecs()
    x.array[:] = values
    P.mult(x, y)
    assert np.allclose(y.array, trilinear(fine / 2), rtol=0, atol=1e-13 * np.abs(values).max())
    # one weight 1 at the coarse points, weights summing to 1 everywhere
    indptr, _, weights = P.getValuesCSR()
    assert np.allclose(np.add.reduceat(weights, indptr[:-1]), 1.0, rtol=0, atol=1e-15)
    for obj in (P, x, y):
        obj.destroy()


def _lattice_points(m: int, dim: int) -> np.ndarray:
    """The points of the lattice of ``m`` cells per side in lexicographic order (the
    first index fastest): the coarse columns' numbering."""
    grid = np.meshgrid(*[np.arange(m + 1)] * dim, indexing="ij")
    return np.stack([g.ravel(order="F") for g in grid], axis=1)


def _dense(matrix: PETSc.Mat) -> np.ndarray:
    rows, columns = matrix.getSize()
    return matrix.getValues(range(rows), range(columns))


def _rigid_motions(x: np.ndarray) -> np.ndarray:
    """(modes, nodes, dim): the translations e_k and the rotations x_i e_j - x_j e_i."""
    dim = x.shape[1]
    modes = [np.broadcast_to(np.eye(dim)[k], x.shape) for k in range(dim)]
    for i in range(dim):
        for j in range(i + 1, dim):
            rotation = np.zeros_like(x, dtype=float)
            rotation[:, j], rotation[:, i] = x[:, i], -x[:, j]
            modes.append(rotation)
    return np.stack(modes)


@pytest.mark.parametrize("dim", [2, 3])
def test_the_vector_prolongation_is_the_scalar_one_kronecker_the_identity(dim):
    m, rng = 3, np.random.default_rng(dim)
    coarse, fine = _lattice_points(m, dim), _lattice_points(2 * m, dim)
    fine = fine[rng.permutation(len(fine))]  # any order of the fine rows
    scalar = multilinear_prolongation(MPI.COMM_SELF, fine, len(fine), m)
    vector = multilinear_prolongation(MPI.COMM_SELF, fine, dim * len(fine), m, block_size=dim)
    assert vector.getBlockSize() == dim
    assert vector.getSize() == (dim * len(fine), dim * len(coarse))
    # dof = node * dim + component, as DOLFINx's blocked spaces number them
    kronecker = np.kron(_dense(scalar), np.eye(dim))
    assert np.array_equal(_dense(vector), kronecker)
    # the rigid motions (linear fields) of the coarse lattice interpolate to the fine ones
    for mode, fine_mode in zip(_rigid_motions(coarse - 1.3), _rigid_motions(fine / 2 - 1.3)):
        x, y = vector.createVecs()
        x.array[:] = mode.ravel()
        vector.mult(x, y)
        assert np.allclose(y.array, fine_mode.ravel(), rtol=0, atol=1e-13)
        for obj in (x, y):
            obj.destroy()
    for obj in (scalar, vector):
        obj.destroy()


def _lattice_preconditioner(V, lattice, material=None) -> MultigridPreconditioner:
    """B_Omega on ``lattice`` (the stiffness of ``material``, an elastic one, or the Laplace
    one), no Signorini block."""
    stiffness = None if material is None else material.stiffness_integrand
    return MultigridPreconditioner(
        V,
        0.7,
        np.zeros((0, 0)),
        lattice=lattice,
        rtol=AMG_RTOL,
        max_iterations=AMG_MAX_ITERATIONS,
        stiffness=stiffness,
    )


@pytest.fixture(scope="module")
def box16():
    domain = build_domain(COMM, GeometrySpec("box", width=0.5, h=0.5 / 16, signorini=["bottom"]))
    V = fem.FunctionSpace(domain.mesh, ("CG", 1))
    B = _lattice_preconditioner(V, domain.lattice)
    yield V, B
    B.destroy()


def test_the_cycle_is_symmetric_positive_definite_and_close_to_the_inverse(box16):
    V, B = box16
    pc = B._ksp.getPC()
    assert pc.getType() == "mg" and pc.getMGLevels() == 3  # 16, 8, 4
    # Chebyshev + Jacobi on every level: pointwise, so independent of the partition
    for level in range(1, 3):
        smoother = pc.getMGSmoother(level)
        assert (smoother.getType(), smoother.getPC().getType()) == ("chebyshev", "jacobi")
    # the Gershgorin bound of every level: 2 (the 7-point stencil and its Galerkin products)
    for operator in B._hierarchy.operators:
        assert gershgorin_bound(operator) == pytest.approx(2.0, abs=1e-12)
    rng = np.random.default_rng(3)
    a, b = rng.standard_normal((2, B.n_omega))
    # symmetric (pre- and post-smoothing alike, an exact coarsest solve), to round-off
    assert abs(a @ B.cycle_omega(b) - b @ B.cycle_omega(a)) <= 1e-12 * abs(a @ B.cycle_omega(a))
    # the spectrum of C B_Omega: Lanczos of CG preconditioned by the cycle (measured
    # [0.849, 0.996] at 16^3 and 64^3 cubes: the multigrid bound does not depend on h)
    ksp = PETSc.KSP().create(COMM)
    ksp.setOperators(B._matrix)
    ksp.setType("cg")
    ksp.setPC(pc)
    ksp.setComputeEigenvalues(True)
    ksp.setTolerances(rtol=1e-10, max_it=100)
    rhs, solution = B._matrix.createVecs()
    rhs.array[:] = a
    ksp.solve(rhs, solution)
    eigenvalues = ksp.computeEigenvalues().real
    assert eigenvalues.min() > 0.8 and eigenvalues.max() < 1.0 + 1e-8
    # and the tight solve inverts B_Omega in 7-9 cycles (GAMG: 18)
    u = B.apply_omega(B.matvec_omega(a))
    assert np.linalg.norm(u - a) <= 1e-9 * np.linalg.norm(a)
    assert B.iterations[-1] <= 10
    for obj in (ksp, rhs, solution):
        obj.destroy()


def _cycle_spectrum(B: MultigridPreconditioner, rhs_values: np.ndarray) -> tuple[np.ndarray, int]:
    """The extreme eigenvalues of C B_Omega (C one V-cycle) from the Lanczos of CG
    preconditioned by the cycle, and CG's iterations to the relative residual 1e-10."""
    ksp = PETSc.KSP().create(COMM)
    ksp.setOperators(B._matrix)
    ksp.setType("cg")
    ksp.setPC(B._ksp.getPC())
    ksp.setComputeEigenvalues(True)
    ksp.setTolerances(rtol=1e-10, max_it=100)
    rhs, solution = B._matrix.createVecs()
    rhs.array[:] = rhs_values
    ksp.solve(rhs, solution)
    eigenvalues, iterations = ksp.computeEigenvalues().real, ksp.getIterationNumber()
    for obj in (ksp, rhs, solution):
        obj.destroy()
    return eigenvalues, iterations


@pytest.mark.parametrize(
    "spec, levels, lowest",
    [
        # measured [0.550, 0.999] at 32^2 cells (bilinear P)
        (GeometrySpec("square", h=0.5 / 32, subdomain_size=0.125, signorini=["bottom"]), 4, 0.5),
        # measured [0.400, 0.9996] at 16^3 cubes: the Gershgorin bound is 1.5-1.7 times
        # lambda_max(D^{-1} A) on the coarse levels of elasticity (1.0 for the scalar box)
        (GeometrySpec("box", width=0.5, h=0.5 / 16, signorini=["bottom"]), 3, 0.35),
    ],
    ids=["square", "box"],
)
def test_the_elastic_cycle_is_symmetric_positive_definite(spec, levels, lowest):
    domain = build_domain(COMM, spec)
    V = fem.VectorFunctionSpace(domain.mesh, ("CG", 1))
    d = domain.dim
    assert V.dofmap.index_map_bs == d  # node-major dofs: node * d + component
    B = _lattice_preconditioner(V, domain.lattice, linear_elastic(2.5, 0.25, d))
    pc = B._ksp.getPC()
    assert pc.getType() == "mg" and pc.getMGLevels() == levels
    for level, p in enumerate(B._hierarchy.prolongations, start=1):
        assert p.getBlockSize() == d and pc.getMGSmoother(level).getType() == "chebyshev"
    rng = np.random.default_rng(5)
    a, b = rng.standard_normal((2, B.n_omega))
    assert abs(a @ B.cycle_omega(b) - b @ B.cycle_omega(a)) <= 1e-12 * abs(a @ B.cycle_omega(a))
    eigenvalues, iterations = _cycle_spectrum(B, a)
    # in (0, 1]: the smoothers converge (Chebyshev's interval ends above lambda_max)
    assert eigenvalues.min() > lowest and eigenvalues.max() < 1.0 + 1e-8
    assert iterations <= 16
    B.destroy()


@pytest.mark.mpi
@pytest.mark.parametrize("n, case", [("16", "box"), ("32", "elastic-square"), ("8", "elastic-box")])
def test_the_cycle_is_the_same_on_any_number_of_ranks(tmp_path, n, case):
    runs = {}
    script = str(ROOT / "tests" / "mpi" / "lattice_multigrid_check.py")
    for ranks in (1, 2, 3):
        out = tmp_path / f"r{ranks}.npz"
        run_mpi(ranks, script, str(out), n, case)
        runs[ranks] = np.load(out)
    one = runs[1]["cycle"]
    for ranks in (2, 3):
        # the sums of the distributed products are ordered differently: round-off
        assert np.linalg.norm(runs[ranks]["cycle"] - one) <= 1e-13 * np.linalg.norm(one)
        assert np.allclose(runs[ranks]["bounds"], runs[1]["bounds"], rtol=1e-14, atol=0)


def test_the_scalar_square_with_amg_solves_on_the_lattice():
    """The scalar problem on the structured square with ``preconditioner = "amg"``: the
    lattice's multigrid (bilinear P, 32 to 4 cells per side), the same minimiser as with
    the default substructuring preconditioner."""
    spec = GeometrySpec("square", h=0.5 / 32, subdomain_size=0.125, signorini=["bottom"])
    domain = build_domain(COMM, spec)
    lattice = domain.lattice
    assert lattice.dim == 2 and lattice.n == 32
    # every node is a lattice point: lower + spacing (i, j), 0 <= i, j <= n
    x = domain.mesh.geometry.x[:, :2]
    indices = lattice.indices(x)
    assert indices.min() >= 0 and indices.max() <= lattice.n
    assert np.abs(lattice.lower + lattice.spacing * indices - x).max() <= 1e-12
    problem = SignoriniProblem(
        domain, make_material("carstensen"), f="1", t0="-1", u0="0.02*x", boundary_operator="dense"
    )
    B = build_preconditioner(problem, SolverOptions(preconditioner="amg"))
    assert B._ksp.getPC().getType() == "mg" and B._ksp.getPC().getMGLevels() == 4
    B.destroy()
    reference = solve(problem, SolverOptions(nested=False))  # substructuring
    run = solve(problem, SolverOptions(preconditioner="amg", nested=False))
    assert reference.converged and run.converged
    assert np.array_equal(run.contact, reference.contact)
    assert np.abs(run.phi - reference.phi).max() <= 1e-4 * np.abs(reference.phi).max()
