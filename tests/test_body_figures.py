"""The figures of a body in R^3 say what the run computed (issue 66, items 3-5): on a box
away from the origin, signorini.png shows the real coordinates and colours the gap and
the pressure from the nodes with a gap unknown, on scales that end at 0."""
from __future__ import annotations

import numpy as np
import pytest

from conftest import run_cli

#: a box at x in [0.7, 1.3], pressed onto its bottom face (4 cubes per side)
BOX = """[geometry]
shape = "box"
center = [1.0, 0.0, 0.0]
width = 0.6
h = 0.15
signorini = ["bottom"]

[material]
rho = "carstensen"

[data]
f = "1"
t0 = "-1"
u0 = "0.05*(x - 1)"

[output]
xdmf = false
plots = false
"""


@pytest.fixture(scope="module")
def box_fields(tmp_path_factory):
    folder = tmp_path_factory.mktemp("box")
    config = folder / "box.toml"
    config.write_text(BOX)
    proc = run_cli("solve", str(config), "--out", str(folder / "out"), "--quiet")
    assert proc.returncode == 0, proc.stderr
    with np.load(folder / "out" / "fields.npz") as data:
        return {k: data[k] for k in data.files}


def _inputs(fields):
    from coupling.io.body_figure_data import surface_inputs

    return surface_inputs(fields, {"iteration": []}, tol=1e-8)


def test_signorini_figure_shows_the_real_coordinates(box_fields):
    import matplotlib.pyplot as plt

    from coupling.io.body_figures import _figure_signorini

    fig = _figure_signorini(_inputs(box_fields))
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

    from coupling.io.body_figures import _figure_signorini

    f = box_fields
    gap, pressure = f["signorini"], f["pressure"]
    bottom = np.isclose(f["boundary_x"][:, 2], -0.3)
    rim = bottom & ~gap
    assert pressure[rim].max() > 0.1  # the rim's flux, no contact pressure
    fig = _figure_signorini(_inputs(f))
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
