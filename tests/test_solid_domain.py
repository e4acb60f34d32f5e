"""The 3D geometry of a run (docs/method.md section 11): GeometrySpec's box, ball and
tetrahedral files, their dimension, build_domain's SolidDomain with the Signorini tags,
the closed-form sizes of the box, and the planar keys refused in one line."""
from __future__ import annotations


import pytest
from mpi4py import MPI

from conftest import json_report
from coupling.app.config import ConfigError, parse_config
from fem_py.boundary import SurfaceMap, boundary_map
from fem_py.dofs import p1_space
from fem_py.mesh import GeometrySpec, SolidDomain, build_domain, domain_size, spec_dimension
from fem_py.mesh.solid import box_size
from solid_files import solid_msh

COMM = MPI.COMM_WORLD


@pytest.mark.parametrize(
    "signorini", [(), ("bottom",), ("bottom", "left"), ("bottom", "left", "front"), "all"]
)
def test_box_domain_and_its_closed_form_sizes(signorini):
    spec = GeometrySpec("box", center=(0.1, 0.0, -0.2), width=0.6, h=0.15, signorini=signorini)
    assert spec.dim == 3
    domain = build_domain(COMM, spec)
    assert isinstance(domain, SolidDomain) and domain.dim == 3 and domain.shape == "box"
    boundary = boundary_map(p1_space(domain.mesh), domain)
    assert isinstance(boundary, SurfaceMap)
    size = domain_size(spec)
    n = 4  # cubes per side
    assert size == box_size(n, 0.6, signorini)
    assert size.dofs == (n + 1) ** 3 == domain.mesh.topology.index_map(0).size_global
    assert (size.boundary_dofs, size.signorini_dofs) == (boundary.n_gamma, boundary.n_signorini)
    # the six-tetrahedra split: edges of length w/n (cube edges) to sqrt(3) w/n (diagonal)
    assert domain.h_min == pytest.approx(size.h_min, rel=1e-12)
    assert domain.h_max == pytest.approx(size.h_max, rel=1e-12)
    assert domain.signorini_is_whole_boundary == (signorini == "all")


def test_ball_and_mesh_file_domains(tmp_path):
    ball = build_domain(COMM, GeometrySpec("ball", center=(0, 0, 0.1), radius=0.3, h=0.15))
    assert (ball.shape, ball.signorini, ball.names) == ("ball", (), {"bottom": 1, "top": 2})
    top = build_domain(COMM, GeometrySpec("ball", radius=0.3, h=0.15, signorini=["top"]))
    assert top.signorini == (2,)
    path = solid_msh(tmp_path / "cube.msh", h=0.4) if COMM.rank == 0 else tmp_path / "cube.msh"
    COMM.barrier()
    spec = GeometrySpec(mesh=str(path), signorini=["bottom"])
    assert spec.dim == 0 and spec_dimension(spec) == 3 == spec_dimension(spec, COMM)
    domain = build_domain(COMM, spec)
    # every surface group is tagged (issue 66, item 9), the Signorini ones first
    assert (domain.shape, domain.names, domain.signorini) == ("mesh", {"bottom": 1, "7": 2}, (1,))
    boundary = boundary_map(p1_space(domain.mesh), domain)
    assert boundary.area == pytest.approx(6.0, rel=1e-13)  # the unit cube, round-off
    with pytest.raises(ValueError, match="signorini: .*'omega' .*volume"):
        build_domain(COMM, GeometrySpec(mesh=str(path), signorini=["omega"]))


@pytest.mark.parametrize(
    "fields, message",
    [
        ({"vertices": ((0, 0), (1, 0), (0, 1))}, "vertices: a polygon is planar"),
        ({"signorini": (((0, 0), (1, 0)),)}, "signorini: shape 'box' takes face names"),
        ({"signorini": ["nope"]}, "signorini: unknown face or group 'nope'"),
        ({"center": (0, 1)}, r"center must be a point \[x, y, z\]"),
        ({"width": -1.0}, "width must be a positive number"),
        ({"dim": 2}, "dim: shape 'box' is 3D, not 2D"),
    ],
)
def test_bad_box_is_one_line(fields, message):
    with pytest.raises(ValueError, match=message) as err:
        build_domain(COMM, GeometrySpec("box", **fields))
    assert "\n" not in str(err.value)


def test_config_takes_3d_shapes_and_refuses_planar_keys():
    config = parse_config(
        {"geometry": {"shape": "box", "center": [0, 0, 0.5], "signorini": ["bottom"]}}
    )
    assert (config.geometry.dim, config.geometry.center) == (3, (0.0, 0.0, 0.5))
    assert parse_config({"geometry": {"shape": "ball"}}).geometry.center == (0.0, 0.0, 0.0)
    assert parse_config({}).geometry.dim == 2
    for geometry, message in [
        ({"shape": "box", "subdomain_size": 0.1}, "geometry.subdomain_size: a 3D body has no"),
        ({"shape": "ball", "allow_large": True}, "geometry.allow_large: in 3D V is elliptic"),
        ({"shape": "box", "center": [0, 0]}, r"geometry.center must be a point \[x, y, z\]"),
        ({"center": [0, 0, 0]}, r"geometry.center must be a point \[x, y\] .* 'square'"),
        ({"shape": "box", "signorini": [[[0, 0], [1, 0]]]}, "geometry.signorini: .*face names"),
    ]:
        with pytest.raises(ConfigError, match=message):
            parse_config({"geometry": geometry})


def test_cli_info_of_a_box(tmp_path):
    config = tmp_path / "box.toml"
    config.write_text('[geometry]\nshape = "box"\nwidth = 0.5\nh = 0.125\nsignorini = ["top"]\n')
    report = json_report("info", config)
    assert (report["dofs"], report["boundary_dofs"], report["signorini_dofs"]) == (125, 98, 9)
