"""The elastic problem with a unilateral interface (docs/method.md section 12): a linear
elastic or Hencky body in an unbounded elastic medium, in frictionless ("slip") or sticking
contact on its bottom face, against the manufactured solutions of
coupling/manufactured_elastic.py (exterior: a translation and a Kelvin point force).

Measured (ssn, tol 1e-10, dense Lame S_h, docs/design/elasticity.md): on the square with
n = 8, 16, 32 cells per side the nodal error of u_h falls by 2^1.58 and 2^1.68 (linear,
stick; Hencky, slip: 1.56, 1.66), the gap's by 2^2.2; on the box (n = 4, 8) by 2^1.56. The
nodal orders rise towards 2 with n: the contact term max(0, -x)^3 and the Kelvin field's
gradients are resolved late. The discrete contact set is the exact {x < 0} at every node
farther than h from its edge x = 0.
"""
from __future__ import annotations

import numpy as np
import pytest
from mpi4py import MPI

from coupling.manufactured_elastic import elastic_contact
from coupling.options import SolverOptions
from coupling.problem import SignoriniProblem
from coupling.solvers import solve
from fem_py.forms import InteriorForms
from fem_py.forms.elasticity import hencky, linear_elastic, rigid_body_modes
from fem_py.mesh import GeometrySpec, build_domain

COMM = MPI.COMM_WORLD


def _material(kind: str, dim: int):
    return linear_elastic(2.5, 0.25, dim) if kind == "linear" else hencky(2.0, "1 + 1/(1 + s)", dim)


def _domain(dim: int, n: int):
    square = {"subdomain_size": 0.125 if n >= 8 else 0.25}
    shape, size = ("square", square) if dim == 2 else ("box", {"width": 0.5})
    return build_domain(COMM, GeometrySpec(shape, h=0.5 / n, signorini=["bottom"], **size))


def _problem(dim, n, kind="linear", tangential="slip", **options):
    domain = _domain(dim, n)
    material = _material(kind, dim)
    case = elastic_contact(domain.mesh, material)
    problem = SignoriniProblem(
        domain,
        material,
        **case.data,
        tangential=tangential,
        boundary_operator="dense",
        **options,
    )
    return problem, case


def _errors(dim, n, kind, tangential, method="ssn"):
    problem, case = _problem(dim, n, kind, tangential)
    solution = solve(problem, SolverOptions(method=method, tol=1e-10))
    assert solution.converged
    owned = problem.V.dofmap.index_map.size_local
    x = problem.V.tabulate_dof_coordinates()[:owned, :dim]
    u_h = solution.u.x.array[: owned * dim].reshape(-1, dim)
    b = problem.boundary
    faces = b.nodes[b.signorini]
    normal = solution.phi[problem.gap.bounded]
    away = np.abs(faces[:, 0]) > 0.5 / n  # farther than h from the contact set's edge
    assert np.array_equal(solution.contact[away], faces[away, 0] < 0)
    if tangential == "slip":  # the exact slip is 0: the computed one is of the error's size
        assert (
            np.abs(solution.phi[~problem.gap.bounded]).max()
            <= 2 * np.abs(normal - case.gap(faces)).max() + 1e-3 / n**2
        )
    return np.abs(u_h - case.u(x)).max(), np.abs(normal - case.gap(faces)).max()


@pytest.mark.parametrize("kind, tangential", [("linear", "stick"), ("hencky", "slip")])
def test_plane_strain_contact_converges(kind, tangential):
    errors = np.array([_errors(2, n, kind, tangential) for n in (8, 16, 32)])
    orders = np.log2(errors[:-1] / errors[1:])
    assert orders[:, 0].min() >= 1.5 and orders[-1, 0] > orders[0, 0]  # rising to 2
    assert orders[:, 1].min() >= 1.9


def test_box_contact_converges():
    errors = np.array([_errors(3, n, "linear", "slip") for n in (4, 8)])
    assert np.log2(errors[0, 0] / errors[1, 0]) >= 1.5
    assert np.log2(errors[0, 1] / errors[1, 1]) >= 1.5


def test_box_m_s_from_the_hmatrix_lame_w_h(monkeypatch):
    """With S_h as H-matrices (3D) M_s = E^T W_h E is read from S_h's H-matrices of the Lame
    W_h (Z + 2 mu W_L kron I_3; no dense integration): the integrated block to S_h's tol (1e-4
    here, so the blocks and M_s are held in single precision; the 386 vertices' blocks are all
    dense, so the difference is float's rounding, about 6e-8), and ssn takes the same
    iterations to the same answer as with the integrated one (the former path, the read
    refused)."""
    from bem_cpp.compressed import SteklovPoincareOperator
    from bem_cpp.dense import SingleMatrix
    from coupling.preconditioners import signorini_hypersingular

    runs = []
    for read in (True, False):
        if not read:
            monkeypatch.setattr(SteklovPoincareOperator, "holds_hypersingular", False)
        domain = _domain(3, 8)
        material = _material("linear", 3)
        case = elastic_contact(domain.mesh, material)
        problem = SignoriniProblem(domain, material, **case.data, boundary_operator="hmatrix")
        assert problem.S.holds_hypersingular == read
        M_s = signorini_hypersingular(
            COMM, problem.boundary, problem.S, gap=problem.gap, kernel=problem.kernel
        )
        runs.append((M_s, solve(problem, SolverOptions(method="ssn", tol=1e-10))))
    (held, one), (integrated, two) = runs
    assert isinstance(held, SingleMatrix)  # tol 1e-4: the blocks and M_s in single precision
    held = held.to_dense()
    assert held.shape == integrated.shape == (3 * problem.boundary.signorini.size,) * 2
    assert np.linalg.norm(held - integrated) <= 1e-4 * np.linalg.norm(integrated)
    assert one.converged and two.converged
    assert one.iterations == two.iterations
    assert np.array_equal(one.contact, two.contact)
    scale = np.abs(two.u.x.array).max()
    assert np.abs(one.u.x.array - two.u.x.array).max() <= 1e-6 * scale


@pytest.mark.parametrize("method", ["pgpm", "apgpm"])
def test_gradient_methods_reach_the_newton_answer(method):
    problem, _ = _problem(2, 8, "hencky", "slip")
    ssn = solve(problem, SolverOptions(method="ssn", tol=1e-10))
    other = solve(problem, SolverOptions(method=method, tol=1e-10))
    assert other.converged
    scale = np.abs(ssn.u.x.array).max()
    assert np.abs(other.u.x.array - ssn.u.x.array).max() <= 1e-7 * scale
    assert np.array_equal(other.contact, ssn.contact)


def test_a_rigid_motion_of_the_data_moves_the_answer_rigidly():
    """u0 -> u0 + r for a rigid motion r changes J_h by a constant after u -> u + r
    (eps(r) = 0): u_h moves by r, the gaps stay."""
    problem, case = _problem(2, 8, "linear", "slip")

    def shifted(k):  # u0_k + r_k, r = (0.3 - 0.2 y, -0.1 + 0.2 x)
        rigid = (lambda x, y: 0.3 - 0.2 * y) if k == 0 else (lambda x, y: -0.1 + 0.2 * x)
        return lambda *xn: case.u0[k](*xn) + rigid(*xn[:2])

    shifted_u0 = [shifted(k) for k in range(2)]
    moved = SignoriniProblem(
        problem.domain,
        problem.material,
        f=case.f,
        u0=shifted_u0,
        t0=case.t0,
        a=case.a,
        exterior=case.exterior,
        boundary_operator="dense",
    )
    one = solve(problem, SolverOptions(tol=1e-11))
    two = solve(moved, SolverOptions(tol=1e-11))
    owned = problem.V.dofmap.index_map.size_local
    x = problem.V.tabulate_dof_coordinates()[:owned, :2]
    r = np.stack([0.3 - 0.2 * x[:, 1], -0.1 + 0.2 * x[:, 0]], axis=1).ravel()
    shift = two.u.x.array[: 2 * owned] - one.u.x.array[: 2 * owned]
    assert np.abs(shift - r).max() <= 1e-7
    assert np.abs(two.phi - one.phi).max() <= 1e-7


@pytest.mark.parametrize("dim", [2, 3])
def test_handwritten_jacobian_is_the_derived_one(dim):
    domain = _domain(dim, 4)
    from fem_py.dofs import p1_space

    V = p1_space(domain.mesh, dim)
    forms = InteriorForms(V, _material("hencky", dim), jacobian="ufl")
    u = forms.create_vector()
    u.array[:] = np.random.default_rng(1).standard_normal(u.array.size)
    A, B = forms.create_matrix(), forms.create_matrix()
    forms.assemble_jacobian(u, A, "ufl")
    forms.assemble_jacobian(u, B, "handwritten")
    A.axpy(-1.0, B)
    assert A.norm() <= 1e-12 * B.norm()


@pytest.mark.parametrize("dim", [2, 3])
def test_rigid_body_modes_span_the_stiffness_kernel(dim):
    from fem_py.dofs import p1_space

    V = p1_space(_domain(dim, 4).mesh, dim)
    forms = InteriorForms(V, _material("linear", dim))
    K = forms.assemble_stiffness()
    modes = rigid_body_modes(V)
    assert len(modes) == (3 if dim == 2 else 6)
    y = K.createVecLeft()
    for mode in modes:
        K.mult(mode, y)
        assert y.norm() <= 1e-12 * K.norm()
    gram = np.array([[a.dot(b) for b in modes] for a in modes])
    assert np.abs(gram - np.eye(len(modes))).max() <= 1e-12


@pytest.mark.parametrize(
    "changes, message",
    [
        (dict(exterior=None), "exterior medium"),
        (dict(exterior=(0.0, 0.3)), "Young's modulus"),
        (dict(exterior=(1.0, 0.5)), "Poisson's ratio"),
        (dict(tangential="glue"), "tangential"),
        (dict(a=(1.0, 2.0, 3.0)), "translation at infinity"),
        (dict(u0=["0", "0", "0"]), "2 components"),
        (dict(u0="x"), "a scalar"),
        (dict(f=["0", "0", "1"]), "f has 3 components"),
        (dict(t0="1"), "t0 has 1 component"),
    ],
)
def test_bad_elastic_input_is_refused_in_one_line(changes, message):
    domain = _domain(2, 4)
    data = dict(exterior=(1.5, 0.3), f=["0", "-1"], u0=["0", "0"], t0=["0", "0"])
    data.update(changes)
    with pytest.raises(ValueError, match=message) as error:
        SignoriniProblem(domain, _material("linear", 2), boundary_operator="dense", **data)
    assert "\n" not in str(error.value)


@pytest.mark.parametrize(
    "build, message",
    [
        (lambda: linear_elastic(-1.0, 0.3, 2), "Young's modulus"),
        (lambda: hencky(0.0, 1.0, 2), "bulk modulus"),
        (lambda: hencky(1.0, -1.0, 2), "shear modulus"),
        (lambda: hencky(1.0, "1/(1 + s)^3", 2), "not strictly increasing"),
        (lambda: hencky(1.0, "1 + t", 2), "written in s"),
    ],
)
def test_bad_materials_are_refused_in_one_line(build, message):
    with pytest.raises(ValueError, match=message) as error:
        build()
    assert "\n" not in str(error.value)


def test_scalar_equation_refuses_an_exterior_medium():
    from fem_py.forms import make_material

    with pytest.raises(ValueError, match="for elasticity"):
        SignoriniProblem(_domain(2, 4), make_material("linear"), exterior=(1.0, 0.3))


def test_slip_on_a_whole_circle_is_refused_as_not_unique():
    """The rotation of a disk changes u and the tangential gaps and not J_h: refused in one
    line; "stick" on the same circle is unique."""
    domain = build_domain(COMM, GeometrySpec("disk", radius=0.25, h=0.0625, signorini="all"))
    data = dict(exterior=(1.5, 0.3), boundary_operator="dense")
    with pytest.raises(ValueError, match="not unique") as error:
        SignoriniProblem(domain, _material("linear", 2), tangential="slip", **data)
    assert "\n" not in str(error.value)
    SignoriniProblem(domain, _material("linear", 2), tangential="stick", **data)
