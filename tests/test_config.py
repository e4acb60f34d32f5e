"""The TOML configuration: defaults, overrides and one-line errors naming the key."""
import pytest

from coupling.app.config import ConfigError, load_config, parse_config
from coupling.options import DEFAULTS, RunConfig


def test_empty_configuration_is_all_defaults():
    assert parse_config({}) == RunConfig()
    assert parse_config({}).as_dict() == DEFAULTS


def test_values_are_converted_and_overrides_applied(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text(
        '[geometry]\nh = 0.05\nsignorini = ["bottom", [[0, 0], [0.25, 0.0]]]\n'
        "[solver]\nstep = 0.5\nmax_iterations = 10\n"
    )
    config = load_config(
        path, ["material.rho=carstensen", "solver.tol=1e-6", "geometry.structured=false"]
    )
    assert config.geometry.h == 0.05
    assert config.geometry.signorini == ("bottom", ((0.0, 0.0), (0.25, 0.0)))
    assert config.material.rho == "carstensen"
    assert config.solver.tol == 1e-6 and config.solver.step == 0.5
    assert config.geometry.structured is False


@pytest.mark.parametrize(
    "raw, message",
    [
        ({"mesh": {}}, r"unknown section \[mesh\]"),
        ({"geometry": {"hh": 1}}, "unknown key geometry.hh"),
        # did you mean ...? (issue 66, item 12): the closest key, a key of another section
        ({"solver": {"tols": 1e-6}}, r"unknown key solver.tols; did you mean solver.tol\? "),
        ({"solver": {"Method": "pgpm"}}, r"did you mean solver.method\? the keys of"),
        ({"geometry": {"tol": 1e-6}}, r"did you mean solver.tol \(a key of \[solver\]\)\?"),
        ({"solvr": {}}, r"unknown section \[solvr\]; did you mean \[solver\]\? the sections"),
        ({"geometry": {"h": "small"}}, "geometry.h must be a finite number"),
        ({"geometry": {"h": -0.1}}, "geometry.h must be positive"),
        ({"geometry": {"shape": "circle"}}, "geometry.shape must be one of"),
        ({"geometry": {"shape": "polygon"}}, "geometry.vertices must list at least 3"),
        ({"geometry": {"center": [0, "a"]}}, r"geometry.center must be a point"),
        ({"geometry": {"signorini": [[1, 2, 3]]}}, r"geometry.signorini\[0\] must be"),
        ({"geometry": {"signorini": 3}}, "geometry.signorini must be"),
        ({"geometry": {"semi_axes": 0.3}}, "geometry.semi_axes must be a list"),
        ({"geometry": {"semi_axes": [0.3]}}, r"geometry.semi_axes must be \[a, b\], two positive"),
        ({"geometry": {"semi_axes": [0.3, -0.2]}}, r"geometry.semi_axes must be \[a, b\]"),
        ({"geometry": {"semi_axes": [0.3, True]}}, r"geometry.semi_axes must be \[a, b\]"),
        (
            {"geometry": {"mesh": "m.msh", "semi_axes": [0.3, 0.2]}},
            "geometry.semi_axes: the mesh file geometry.mesh sets the geometry",
        ),
        ({"solver": {"step": "big"}}, 'solver.step must be "auto" or a positive number'),
        ({"solver": {"max_iterations": 1.5}}, "solver.max_iterations must be an integer"),
        ({"solver": {"coarse_space": "exact"}}, "solver.coarse_space must be one of"),
        ({"solver": {"projection_tol": 1.0}}, r"solver.projection_tol .* must lie in \[0, 1\)"),
        ({"output": {"plots": "yes"}}, "output.plots must be true or false"),
        ({"data": {"f": 1}}, "data.f must be a string"),
    ],
)
def test_errors_name_the_key(raw, message):
    with pytest.raises(ConfigError, match=message):
        parse_config(raw)


def test_ellipse_keys():
    config = parse_config({"geometry": {"shape": "ellipse", "semi_axes": [1, 0.25]}})
    assert config.geometry.shape == "ellipse" and config.geometry.semi_axes == (1.0, 0.25)
    assert config.as_dict()["geometry"]["semi_axes"] == [1.0, 0.25]


def test_missing_file_and_bad_toml(tmp_path):
    with pytest.raises(ConfigError, match="not found"):
        load_config(tmp_path / "nope.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[geometry\nh = 1")
    with pytest.raises(ConfigError, match="invalid TOML"):
        load_config(bad)
    with pytest.raises(ConfigError, match="--set expects section.key=value"):
        load_config(None, ["h=1"])
