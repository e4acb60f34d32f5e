"""The geometric multigrid of the box's vertex lattice (coupling/preconditioners/
lattice_multigrid.py): its levels, the trilinear prolongation, and one V-cycle as a fixed
symmetric positive definite operator, spectrally close to B_Omega^{-1} and the same on 1, 2
and 3 ranks."""
from __future__ import annotations

import numpy as np
import pytest
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from conftest import ROOT, run_mpi
from coupling.options import AMG_MAX_ITERATIONS, AMG_RTOL
from coupling.preconditioners.lattice_multigrid import (
    gershgorin_bound,
    lattice_levels,
    trilinear_prolongation,
)
from coupling.preconditioners.multigrid import MultigridPreconditioner
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
    P = trilinear_prolongation(MPI.COMM_SELF, fine, fine.shape[0], m)
    x, y = P.createVecs()
    x.array[:] = values
    P.mult(x, y)
    assert np.allclose(y.array, trilinear(fine / 2), rtol=0, atol=1e-13 * np.abs(values).max())
    # one weight 1 at the coarse points, weights summing to 1 everywhere
    indptr, _, weights = P.getValuesCSR()
    assert np.allclose(np.add.reduceat(weights, indptr[:-1]), 1.0, rtol=0, atol=1e-15)
    for obj in (P, x, y):
        obj.destroy()


@pytest.fixture(scope="module")
def box16():
    domain = build_domain(COMM, GeometrySpec("box", width=0.5, h=0.5 / 16, signorini=["bottom"]))
    V = fem.FunctionSpace(domain.mesh, ("CG", 1))
    B = MultigridPreconditioner(
        V,
        0.7,
        np.zeros((0, 0)),
        lattice=domain.lattice,
        rtol=AMG_RTOL,
        max_iterations=AMG_MAX_ITERATIONS,
    )
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


@pytest.mark.mpi
def test_the_cycle_is_the_same_on_any_number_of_ranks(tmp_path):
    runs = {}
    for ranks in (1, 2, 3):
        out = tmp_path / f"r{ranks}.npz"
        run_mpi(ranks, str(ROOT / "tests" / "mpi" / "lattice_multigrid_check.py"), str(out), "16")
        runs[ranks] = np.load(out)
    one = runs[1]["cycle"]
    for ranks in (2, 3):
        # the sums of the distributed products are ordered differently: round-off
        assert np.linalg.norm(runs[ranks]["cycle"] - one) <= 1e-13 * np.linalg.norm(one)
        assert np.allclose(runs[ranks]["bounds"], runs[1]["bounds"], rtol=1e-14, atol=0)
