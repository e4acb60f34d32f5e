"""Data in x, y, z and nx, ny, nz on a body in R^3 (docs/method.md section 11): the interior
and boundary loads against integrals known in closed form, the boundary values at the
nodes, the configuration's check of the expressions, and ``fembem check-jacobian`` on
the box (Taylor slope 2)."""
from __future__ import annotations


import numpy as np
import pytest
from mpi4py import MPI

from conftest import json_report
from coupling.app.config import ConfigError, check_data_and_material, parse_config
from fem_py.boundary import boundary_map
from fem_py.dofs import p1_space
from fem_py.forms import InteriorForms, make_material
from fem_py.mesh import GeometrySpec, build_domain

COMM = MPI.COMM_WORLD
CENTER, WIDTH = (0.1, -0.2, 0.3), 0.5


@pytest.fixture(scope="module")
def box():
    domain = build_domain(COMM, GeometrySpec("box", center=CENTER, width=WIDTH, h=0.125))
    V = p1_space(domain.mesh)
    return domain, V, boundary_map(V, domain)


def test_loads_in_x_y_z_and_the_normal(box):
    domain, V, boundary = box
    volume = WIDTH**3
    # int_Omega (x + y + z) dx = |Omega| (cx + cy + cz): P1 test functions sum to 1, and
    # the degree-6 rule integrates the linear integrand exactly (round-off)
    forms = InteriorForms(V, make_material("linear"), "x + y + z")
    b = forms.assemble_load()
    assert b.sum() == pytest.approx(volume * sum(CENTER), rel=1e-12)
    b.destroy()
    # divergence theorem: int_Gamma (x nx + y ny + z nz) ds = 3 |Omega|, int_Gamma nz ds = 0
    m = forms.boundary_load("x*nx + y*ny + z*nz", boundary)
    assert m.sum() == pytest.approx(3 * volume, rel=1e-12)
    assert abs(forms.boundary_load("nz", boundary).sum()) < 1e-14
    # u0 at the nodes: z + nz with the node normals of the surface map
    u0 = boundary.interpolate_boundary("z + 2*nz")
    assert np.array_equal(u0, boundary.nodes[:, 2] + 2 * boundary.node_normals[:, 2])


def test_planar_data_refuse_z_and_3d_data_take_it():
    check_data_and_material(parse_config({"geometry": {"shape": "box"}, "data": {"t0": "nz*z"}}))
    with pytest.raises(ConfigError, match="data.f: unknown name 'z'"):
        check_data_and_material(parse_config({"data": {"f": "z"}}))
    with pytest.raises(ConfigError, match="data.u0: unknown name 'w'"):
        check_data_and_material(parse_config({"geometry": {"shape": "ball"}, "data": {"u0": "w"}}))


@pytest.mark.parametrize("rho", ["carstensen", "power"])
def test_check_jacobian_on_the_box(tmp_path, rho):
    config = tmp_path / "box.toml"
    config.write_text(
        f'[geometry]\nshape = "box"\nwidth = 0.5\nh = 0.125\n[material]\nrho = "{rho}"\n'
        + ("p = 3.0\n" if rho == "power" else "")
    )
    report = json_report("check-jacobian", config)
    assert report["passed"] and report["n_dofs"] == 125
    assert report["matrix_rel_diff"] <= report["tolerances"]["matrix"]
    assert all(abs(s - 2.0) <= report["tolerances"]["slope"] for s in report["slope2"])
