"""The figures of a body in R^3 say what the run computed (issue 66, items 3-5): on a box
away from the origin, signorini.png shows the real coordinates and colours the gap and
the pressure from the nodes with a gap unknown, on scales that end at 0."""
from __future__ import annotations

import numpy as np
import pytest

from conftest import run_cli, solved_fields
from solid_files import box_toml, group_bottom_faces

#: a box at x in [0.7, 1.3], pressed onto its bottom face (4 cubes per side)
BOX = box_toml("[1.0, 0.0, 0.0]", 0.6, 0.15, 'u0 = "0.05*(x - 1)"')


@pytest.fixture(scope="module")
def box_fields(tmp_path_factory):
    return solved_fields(tmp_path_factory.mktemp("box"), "box", BOX)


def _inputs(fields):
    from coupling.io.body_figure_data import surface_inputs

    return surface_inputs(fields, {"iteration": []}, tol=1e-8)


def test_signorini_figure_shows_the_real_coordinates(box_fields):
    import matplotlib.pyplot as plt

    from coupling.io.body_figures import figure_signorini

    fig = figure_signorini(_inputs(box_fields))
    try:
        for ax in fig.axes[:2]:  # the two panels (then their colour bars)
            assert (ax.get_xlabel(), ax.get_ylabel()) == ("x", "y")
            box = ax.dataLim
            # the bottom face is [0.7, 1.3] x [-0.3, 0.3] (it was drawn centred on 0)
            assert (box.x0, box.x1) == pytest.approx((0.7, 1.3), abs=1e-12)
            assert (box.y0, box.y1) == pytest.approx((-0.3, 0.3), abs=1e-12)
    finally:
        plt.close(fig)


def test_signorini_figure_colours_from_the_gap_unknowns(box_fields):
    import matplotlib.pyplot as plt

    from coupling.io.body_figures import figure_signorini

    f = box_fields
    gap, pressure = f["signorini"], f["pressure"]
    bottom = np.isclose(f["boundary_x"][:, 2], -0.3)
    rim = bottom & ~gap
    assert pressure[rim].max() > 0.1  # the rim's flux, no contact pressure
    fig = figure_signorini(_inputs(f))
    try:
        left, right = fig.axes[:2]
        gap_colours, pressure_colours = left.collections[0], right.collections[0]
        # the pressure's scale: its values on the gap unknowns, ending at 0
        assert pressure_colours.get_clim() == pytest.approx((pressure[gap].min(), 0.0))
        assert pressure_colours.get_clim()[0] < -0.01
        assert gap_colours.get_clim()[0] == 0.0  # the gap's scale starts at 0
        # the coloured triangles have a gap unknown at each corner
        drawn = pressure_colours._triangulation.triangles  # a matplotlib Triangulation
        assert gap[f["boundary_triangles"]].all(axis=1).sum() == len(drawn)
        # a value of the wrong sign takes the colour beyond the scale's end
        over = pressure_colours.get_cmap().get_over()
        assert tuple(over) != tuple(pressure_colours.get_cmap()(1.0))
    finally:
        plt.close(fig)


def _drawn_lines(ax) -> np.ndarray:
    """The vertices (k, 2) of every line drawn in ``ax`` by a collection (outlines)."""
    from matplotlib.collections import LineCollection

    lines = [c for c in ax.collections if isinstance(c, LineCollection)]
    lines += [c for c in ax.collections if type(c).__name__ == "PathCollection"]
    return np.concatenate([p.vertices for c in lines for p in c.get_paths()])


def test_slice_outline_is_the_section_of_gamma(box_fields):
    """slice.png's outline is where the plane cuts Gamma's triangles (it was the edge of
    the pixels inside, drawn up to 0.015 outside the section)."""
    import matplotlib.pyplot as plt

    from coupling.io.body_figure_data import section
    from coupling.io.body_figures import _figure_slice

    inputs = _inputs(box_fields)._replace(section=section(box_fields, "z = 0.1"))
    fig = _figure_slice(inputs)
    try:
        ax = fig.axes[0]
        assert ax.get_title() == "section z = 0.1"
        assert (ax.get_xlabel(), ax.get_ylabel()) == ("$x$", "$y$")
        xy = _drawn_lines(ax)
        assert len(xy) >= 8
        # on the square [0.7, 1.3] x [-0.3, 0.3], the section of the box
        assert xy[:, 0].min() == pytest.approx(0.7, abs=1e-12)
        assert xy[:, 0].max() == pytest.approx(1.3, abs=1e-12)
        assert np.abs(xy[:, 1]).max() == pytest.approx(0.3, abs=1e-12)
        off = np.minimum(np.abs(np.abs(xy[:, 0] - 1.0) - 0.3), np.abs(np.abs(xy[:, 1]) - 0.3))
        assert off.max() <= 1e-12
        # no pixel is left blank between u_h inside and u_e outside
        image = ax.get_images()[0].get_array()
        assert np.ma.count_masked(image) == 0
    finally:
        plt.close(fig)


def _bracket_msh(path):
    """An L-shaped bracket: a foot [0, 0.6] x [0, 0.3] x [0, 0.1] and an upright
    [0, 0.1] x [0, 0.3] x [0, 0.6]; its bottom face z = 0 the group "foot"."""
    import gmsh

    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        occ = gmsh.model.occ
        foot, upright = occ.addBox(0, 0, 0, 0.6, 0.3, 0.1), occ.addBox(0, 0, 0, 0.1, 0.3, 0.6)
        (body, *_), _ = occ.fuse([(3, foot)], [(3, upright)])
        occ.synchronize()
        group_bottom_faces(gmsh, body[1], "foot")
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.05)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.model.mesh.generate(3)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()


def test_the_default_slice_goes_through_the_signorini_part(tmp_path):
    """The section through the middle of the bounding box (z = 0.3) missed the bracket's
    foot, where the contact is; the default plane goes through the Signorini part."""
    from coupling.io.body_figure_data import section

    _bracket_msh(tmp_path / "bracket.msh")
    fields = solved_fields(
        tmp_path,
        "bracket",
        '[geometry]\nmesh = "bracket.msh"\nsignorini = ["foot"]\n[data]\nf = "1"\nt0 = "-1"',
    )
    s = section(fields)
    assert (s["axis"], s["names"]) == ("y", ("x", "z"))
    assert s["value"] == pytest.approx(0.15, abs=0.02)  # the foot's middle
    # u_h's pixels reach along the foot, to x = 0.6, and the outline holds its bottom
    x0, x1, z0, z1 = s["u_extent"]
    n = s["u"].shape[1]
    columns = x0 + (np.arange(n) + 0.5) * (x1 - x0) / n
    inside = np.isfinite(s["u"]).any(axis=0)
    assert columns[inside].max() > 0.55
    bottom = s["outline"][np.abs(s["outline"][:, :, 1]).max(axis=1) < 1e-12]
    assert np.ptp(bottom[:, :, 0]) == pytest.approx(0.6, abs=1e-9)
    assert section(fields, "z = 0.3")["axis"] == "z"  # the user's plane


@pytest.mark.parametrize(
    "geometry, value, message",
    [
        ('shape = "box"', "w = 1", 'output.slice must be "auto" or a coordinate plane'),
        ('shape = "box"', "z = one", 'output.slice must be "auto" or a coordinate plane'),
        ('shape = "square"', "z = 0", "output.slice: the section slice.png is a figure of"),
    ],
)
def test_a_bad_slice_is_refused_in_one_line(tmp_path, geometry, value, message):
    config = tmp_path / "c.toml"
    config.write_text(f"[geometry]\n{geometry}\n")
    proc = run_cli("info", str(config), "--set", f"output.slice={value}")
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], lines
