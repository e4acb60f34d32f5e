"""The figures of an elastic run say what the run computed (issue 65, figures): the von
Mises stress of deformed.png against closed forms, the magnification, the tetrahedron
under each surface triangle, signorini.png's pressure (compression positive) on a scale
set by the nodes with a gap unknown, and u_e by Kelvin's representation formula tending
to the trace on Gamma."""
from __future__ import annotations

import numpy as np
import pytest

from conftest import solved_fields
from test_cli_elastic import BOX, SQUARE


@pytest.fixture(scope="module")
def square(tmp_path_factory):
    return solved_fields(tmp_path_factory.mktemp("square"), "square", SQUARE)


@pytest.fixture(scope="module")
def box(tmp_path_factory):
    return solved_fields(tmp_path_factory.mktemp("box"), "box", BOX)


HISTORY = {"iteration": np.zeros(0)}


def test_von_mises_against_closed_forms():
    from coupling.io.stress import von_mises
    from fem_py.forms.elasticity import hencky, linear_elastic

    E, nu, e = 2.0, 0.25, 1e-3
    # 3D uniaxial stress: eps = e diag(1, -nu, -nu) gives sigma = E e e_1 e_1^T
    grad = np.diag([e, -nu * e, -nu * e])[None]
    assert von_mises(grad, linear_elastic(E, nu, 3)) == pytest.approx([E * e], rel=1e-12)
    # plane strain, eps = e e_1 e_1^T: sigma_xx = (lambda + 2 mu) e, sigma_yy = sigma_zz =
    # lambda e, so the von Mises stress is 2 mu e
    mu = E / (2 * (1 + nu))
    grad = np.array([[[e, 0.0], [0.0, 0.0]]])
    assert von_mises(grad, linear_elastic(E, nu, 2)) == pytest.approx([2 * mu * e], rel=1e-12)
    # pure shear eps_xy = g: tau = 2 mu(s) g, s = |dev eps| = sqrt(2) g, von Mises sqrt(3) tau
    g = 0.3
    grad = np.array([[[0.0, 2 * g], [0.0, 0.0]]])
    s = np.sqrt(2) * g
    tau = 2 * (1 + 1 / (1 + s)) * g
    law = hencky(2.0, "1 + 1/(1 + s)", 2)
    assert von_mises(grad, law) == pytest.approx([np.sqrt(3) * tau], rel=1e-12)


def test_magnification_draws_the_largest_displacement_at_a_tenth_of_the_body():
    from coupling.io.elastic_figure_data import magnification

    x = np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 1.0]])
    for largest, factor in ((1e-3, 200.0), (4e-3, 50.0), (0.1, 2.0), (0.2, 1.0)):
        u = np.array([[largest, 0.0], [0.0, 0.0], [0.0, 0.0]])
        assert magnification(x, u) == pytest.approx(factor)
    assert magnification(x, np.zeros((3, 2))) == 1.0


def test_each_surface_triangle_lies_on_its_tetrahedron(box):
    from coupling.io.elastic_figure_data import surface_cells

    nodes, triangles = box["boundary_x"], box["boundary_triangles"]
    under = surface_cells(box["x"], box["cells"], nodes, triangles)
    tets = box["x"][box["cells"][under]]  # (t, 4, 3)
    corners = nodes[triangles]  # (t, 3, 3)
    # every corner of the triangle is a vertex of its tetrahedron
    gaps = np.linalg.norm(corners[:, :, None, :] - tets[:, None, :, :], axis=-1).min(axis=2)
    assert gaps.max() < 1e-12


def test_the_plane_signorini_figure_draws_the_pressure_compression_positive(square):
    import matplotlib.pyplot as plt

    from coupling.io.elastic_figure_data import elastic_inputs
    from coupling.io.elastic_figures import _figure_signorini_plane
    from fem_py.forms.elasticity import hencky

    inputs = elastic_inputs(square, hencky(2.0, "1 + 1/(1 + s)", 2), HISTORY, tol=1e-8)
    fig = _figure_signorini_plane(inputs)
    try:
        pressure_ax, opening_ax = fig.axes[0], fig.axes[1]
        p = -square["pressure"][square["signorini"]]
        assert p.max() > 0  # compression, drawn positive
        low, high = pressure_ax.get_ylim()
        # the scale: the gap unknowns' pressures and 0, a 5 % margin; not the arc's ends
        assert high == pytest.approx(p.max() + 0.05 * (p.max() - min(p.min(), 0.0)))
        ends = ~square["signorini"] & (np.abs(square["boundary_x"][:, 1] + 0.25) < 1e-12)
        assert np.abs(square["pressure"][ends]).max() > high  # off the scale
        assert opening_ax.get_ylim()[0] <= 0.0 <= opening_ax.get_ylim()[1]
        shaded = [p for p in pressure_ax.patches if p.get_facecolor()[0] > 0.5]
        assert len(shaded) >= 1  # the contact set
    finally:
        plt.close(fig)


def test_the_body_signorini_figure_scales_the_pressure_from_zero(box):
    import matplotlib.pyplot as plt

    from coupling.io.elastic_figure_data import elastic_inputs
    from coupling.io.elastic_figures import _figure_signorini_body
    from fem_py.forms.elasticity import linear_elastic

    inputs = elastic_inputs(box, linear_elastic(2.5, 0.25, 3), HISTORY, tol=1e-8)
    fig = _figure_signorini_body(inputs)
    try:
        pressure = fig.axes[1].collections[0]
        p = -box["pressure"][box["signorini"]]
        assert pressure.get_clim() == pytest.approx((0.0, p.max()))
        assert "contact pressure" in fig.axes[1].get_title()
    finally:
        plt.close(fig)


def test_kelvins_representation_formula_tends_to_the_trace(square):
    """u_e just outside the middle of the right side: the trace ue on Gamma, to the
    discrete data's accuracy."""
    from coupling.io.evaluation import exterior_from_fields

    nodes = square["boundary_x"]
    i = int(np.flatnonzero(np.isclose(nodes[:, 0], 0.25) & np.isclose(nodes[:, 1], 0.0))[0])
    points = nodes[i] + np.array([[1e-4, 0.0]])
    ue = exterior_from_fields(square, points, kernel=("lame", 1.5, 0.3))
    assert ue.shape == (1, 2)
    assert np.linalg.norm(ue[0] - square["ue"][i]) <= 1e-2 * np.linalg.norm(square["ue"][i])


def test_plane_elastic_figures_are_drawn_without_mpi(square, tmp_path):
    """The figure process of a plane elastic run unpickles its inputs and draws them
    without importing MPI (under mpirun a process importing it would try to join the job),
    the exterior samples included."""
    import pickle
    import subprocess
    import sys

    from coupling.io.elastic_figure_data import elastic_inputs, exterior_section
    from fem_py.forms.elasticity import hencky

    inputs = elastic_inputs(square, hencky(2.0, "1 + 1/(1 + s)", 2), HISTORY, tol=1e-8)
    inputs = inputs._replace(exterior=exterior_section(square, ("lame", 1.5, 0.3)))
    pickled = tmp_path / "inputs.pkl"
    pickled.write_bytes(pickle.dumps(inputs))
    code = (
        "import pickle, sys; from coupling.io import figures; "
        f"pngs = figures.render(pickle.loads(open({str(pickled)!r}, 'rb').read())); "
        "assert set(pngs) == {'deformed.png', 'signorini.png', 'exterior.png'}, set(pngs); "
        "sys.exit(3 if 'mpi4py' in sys.modules else 0)"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr


def test_cell_gradients_of_an_affine_field_are_exact():
    from coupling.io.stress import cell_gradients

    rng = np.random.default_rng(1)
    for d in (2, 3):
        x = rng.random((40, d))
        cells = np.array([rng.choice(40, d + 1, replace=False) for _ in range(25)])
        A, b = rng.random((d, d)), rng.random(d)
        assert np.abs(cell_gradients(x, cells, x @ A.T + b) - A).max() < 1e-9


def test_write_outputs_draws_the_elastic_figures_in_this_process(tmp_path):
    """Without a figure process the figures are drawn in the run's process; and the
    problem's exterior evaluation uses Kelvin's kernel, as the figures' samples do."""
    from mpi4py import MPI

    from coupling.io.evaluation import exterior_from_fields
    from coupling.io.outputs import load_fields, write_outputs
    from coupling.options import SolverOptions
    from coupling.problem import SignoriniProblem
    from coupling.solvers import solve
    from fem_py.forms.elasticity import linear_elastic
    from fem_py.mesh import GeometrySpec, build_domain

    spec = GeometrySpec("square", h=1 / 16, subdomain_size=0.125, signorini=["bottom"])
    domain = build_domain(MPI.COMM_WORLD, spec)
    problem = SignoriniProblem(
        domain,
        linear_elastic(2.5, 0.25, 2),
        f=["1", "0"],
        u0=["0", "0.05*x"],
        exterior=(1.5, 0.3),
        boundary_operator="dense",
    )
    result = solve(problem, SolverOptions())
    names = write_outputs(
        MPI.COMM_WORLD, tmp_path, problem, result, tol=1e-8, xdmf=False, plots=True, timings={}
    )
    assert {"deformed.png", "signorini.png", "exterior.png", "history.png"} <= set(names)
    fields = load_fields(tmp_path)
    points = np.array([[0.6, 0.1], [-0.4, -0.7]])
    direct = exterior_from_fields(fields, points, kernel=problem.kernel)
    assert problem.exterior(result, points) == pytest.approx(direct, rel=1e-12, abs=1e-15)


def test_the_medium_s_stress_is_that_of_its_displacement(square):
    """exterior.png's stress: the von Mises stress of sigma(u_e) by the representation
    formula equals that of the plane-strain stress of u_e's central differences."""
    from coupling.io.elastic_figure_data import exterior_von_mises
    from coupling.io.stress import equivalent_stress
    from coupling.io.evaluation import exterior_from_fields
    from fem_py.forms.elasticity import lame_parameters

    kernel = ("lame", 1.5, 0.3)
    lam, mu = lame_parameters(1.5, 0.3)
    points = np.array([[0.45, 0.1], [-0.1, -0.42], [0.3, 0.3]])
    eps = 1e-5
    grad = np.stack(
        [
            (
                exterior_from_fields(square, points + eps * e, kernel=kernel)
                - exterior_from_fields(square, points - eps * e, kernel=kernel)
            )
            / (2 * eps)
            for e in np.eye(2)
        ],
        axis=2,
    )  # [m, i, j] = du_i/dx_j
    strain = 0.5 * (grad + grad.transpose(0, 2, 1))
    trace = np.trace(strain, axis1=1, axis2=2)
    sigma = np.zeros((len(points), 3, 3))
    sigma[:, :2, :2] = lam * trace[:, None, None] * np.eye(2) + 2 * mu * strain
    sigma[:, 2, 2] = lam * trace
    expected = equivalent_stress(sigma)
    assert exterior_von_mises(square, points, kernel) == pytest.approx(expected, rel=1e-5)
