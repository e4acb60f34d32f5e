"""fem_py.forms: energy, residual and the two Jacobians (docs/method.md 2.1, 4.1), loads and
the stiffness matrix, against exact values and finite differences."""
from __future__ import annotations

import numpy as np
import pytest
import ufl
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from conftest import TEST_MATERIALS
from fem_py.dofs import p1_space
from fem_py.forms import (
    InteriorForms,
    assemble_boundary_load,
    check_jacobian,
    compile_form,
    make_material,
)
from fem_py.mesh import GeometrySpec, build_domain

COMM = MPI.COMM_WORLD
MATERIALS = TEST_MATERIALS
AREA = 0.25  # square of width 0.5


@pytest.fixture(scope="module")
def domain():
    return build_domain(
        COMM, GeometrySpec("square", h=1 / 16, subdomain_size=1 / 4, structured=False)
    )


@pytest.fixture(scope="module")
def V(domain):
    return p1_space(domain.mesh)


@pytest.fixture(scope="module", params=MATERIALS, ids=lambda m: m[0] + str(m[1].get("p", "")))
def forms(request, V):
    name, kw = request.param
    return InteriorForms(V, make_material(name, **kw), "sin(3*x)*y")


def smooth(V, a=1.0, b=0.0):
    u = fem.Function(V)
    u.interpolate(lambda x: a * (np.sin(3 * x[0] + 1) * np.cos(2 * x[1]) + x[0] * x[1]) + b * x[0])
    return u


def test_energy_of_linear_state(forms, V):
    """u = 2x - y is exactly in V_h: G = |Omega| g(sqrt(5))."""
    u = fem.Function(V)
    u.interpolate(lambda x: 2 * x[0] - x[1])
    assert forms.energy(u) == pytest.approx(AREA * forms.material.g_np(np.sqrt(5.0)), rel=1e-13)


def test_residual_is_gradient_of_energy(forms, V):
    """Taylor: |G(u + eps w) - G(u) - eps b.w| = O(eps^2) (slope 2 within 0.1), and the
    central difference matches b.w to its O(eps^2) truncation."""
    u, w = smooth(V), smooth(V, a=0.7, b=0.3)
    b = forms.create_vector()
    forms.assemble_residual(u, b)
    bw = b.dot(w.vector)
    G0 = forms.energy(u)
    eps = 1e-2 * 2.0 ** -np.arange(5)
    rem = []
    for e in eps:
        v = u.copy()
        v.x.array[:] += e * w.x.array
        rem.append(abs(forms.energy(v) - G0 - e * bw))
    slope = np.polyfit(np.log(eps), np.log(rem), 1)[0]
    if forms.material.name == "linear":
        # G quadratic: remainder = eps^2/2 w^T K w exactly, slope 2 to round-off
        assert slope == pytest.approx(2.0, abs=1e-6)
    else:
        assert slope == pytest.approx(2.0, abs=0.1)
    e = 1e-4
    vp, vm = u.copy(), u.copy()
    vp.x.array[:] += e * w.x.array
    vm.x.array[:] -= e * w.x.array
    fd = (forms.energy(vp) - forms.energy(vm)) / (2 * e)
    # truncation e^2 |D^3G| ~ 1e-8 * |b.w|, cancellation 1e-16 G / e ~ 1e-12
    assert fd == pytest.approx(bw, rel=1e-6)
    b.destroy()


def test_residual_equals_rho_form(forms, V):
    """The residual of ufl.derivative(G) equals int rho(|grad u|) grad u . grad v dx."""
    u = smooth(V)
    v = ufl.TestFunction(V)
    gu = ufl.grad(u)
    ref_form = compile_form(
        ufl.inner(forms.material.rho(ufl.sqrt(ufl.inner(gu, gu))) * gu, ufl.grad(v)) * ufl.dx
    )
    ref = fem.petsc.assemble_vector(ref_form)
    ref.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    b = forms.create_vector()
    forms.assemble_residual(u, b)
    b.axpy(-1.0, ref)
    assert b.norm() <= 1e-13 * ref.norm()  # two expression trees of the same integrand: round-off
    b.destroy()
    ref.destroy()


def test_jacobians_equal_and_taylor(forms, domain):
    """UFL and hand-written Jacobians agree to round-off; Taylor slopes 1 and 2."""
    r = check_jacobian(domain, forms.material, n_states=2, seed=1)
    assert r["passed"]
    assert r["matrix_rel_diff"] <= 1e-12  # ~100 ulps: same tangent, different expression trees
    assert all(abs(s - 1.0) <= 0.05 for s in r["slope1"])
    if forms.material.name == "linear":
        assert r["taylor_exact"]
    else:
        assert all(abs(s - 2.0) <= 0.1 for s in r["slope2"])


@pytest.mark.parametrize("state", ["zero", "half-flat"])
def test_no_nan_at_zero_gradient(forms, V, state):
    """grad u = 0 on every cell (zero) or on half of them (u = max(x, 0)): energy,
    residual and both Jacobians are finite; at u = 0 the Jacobian is rho(0) A_lap."""
    u = fem.Function(V)
    if state == "half-flat":
        u.interpolate(lambda x: np.maximum(x[0], 0.0))
    assert np.isfinite(forms.energy(u))
    b = forms.create_vector()
    forms.assemble_residual(u, b)
    assert np.all(np.isfinite(b.array))
    K = forms.assemble_stiffness()
    for kind in ("ufl", "handwritten"):
        A = forms.create_matrix()
        forms.assemble_jacobian(u, A, kind)
        assert np.all(np.isfinite(A.getValuesCSR()[2]))
        if state == "zero":
            A.axpy(-forms.material.rho0, K)
            assert A.norm() <= 1e-14 * forms.material.rho0 * K.norm()
        A.destroy()
    if state == "zero":
        assert b.norm() == 0.0 and forms.energy(u) == 0.0
    K.destroy()
    b.destroy()


def test_load_and_stiffness(V):
    forms = InteriorForms(V, make_material("linear"), "1 + x", jacobian="handwritten")
    bf = forms.assemble_load()
    # sum_i int (1 + x) v_i = int (1 + x) dx = |Omega| (centroid x = 0)
    assert bf.sum() == pytest.approx(AREA, rel=1e-13)
    K = forms.assemble_stiffness()
    x = smooth(V, a=0.0, b=1.0).vector  # u = x
    one = x.duplicate()
    one.set(1.0)
    Kx = x.duplicate()
    K.mult(one, Kx)
    assert Kx.norm() <= 1e-13 * K.norm()  # constants are in the kernel
    K.mult(x, Kx)
    assert Kx.dot(x) == pytest.approx(AREA, rel=1e-13)  # int |grad x|^2 = |Omega|
    zero = InteriorForms(V, make_material("linear"), None).assemble_load()
    assert zero.norm() == 0.0
    for obj in (bf, K, one, Kx, zero):
        obj.destroy()


def test_boundary_load(V):
    """Sum of m_t = int_Gamma t0: perimeter for t0 = 1, 0 for t0 = nx, 2|Omega| for x.n."""
    for t0, exact in (("1", 2.0), ("nx", 0.0), ("x*nx + y*ny", 2 * AREA), (2.0, 4.0)):
        m = assemble_boundary_load(V, t0)
        assert m.sum() == pytest.approx(exact, abs=1e-14)
        m.destroy()


def test_bad_arguments(V):
    with pytest.raises(ValueError, match="jacobian must be one of"):
        InteriorForms(V, make_material("linear"), None, jacobian="fd")
    with pytest.raises(ValueError, match="use make_material"):
        InteriorForms(V, "linear", None)
    with pytest.raises(ValueError, match="unknown name 'z'"):
        InteriorForms(V, make_material("linear"), "z")
