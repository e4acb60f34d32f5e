"""Run configuration: the TOML schema of :mod:`coupling.options` validated into the
typed :class:`coupling.options.RunConfig`, made once here.

A configuration has six sections; every key has a default, so an empty file is a
valid (linear, contact-free) problem. Unknown sections or keys, wrong types and
out-of-range values raise :class:`ConfigError`, a ``ValueError`` whose one-line
message names the key and says what to do.
"""
from __future__ import annotations

import copy
import difflib
import math
import re
import tomllib
from pathlib import Path
from typing import Any

from coupling.options import (
    CHOICES,
    DATA_VARIABLES,
    DATA_VARIABLES_3D,
    DEFAULTS,
    AdaptOptions,
    DataOptions,
    ExteriorOptions,
    MaterialOptions,
    ProblemOptions,
    OutputOptions,
    RunConfig,
    parse_slice,
    solver_options,
)
from coupling.app.errors import ConfigError
from coupling.app.equation_keys import (
    VECTOR_DATA,
    check_elastic_data_and_material,
    check_equation_keys,
    vector_value,
)
from fem_py.spec import PLANAR_ONLY, SOLID_SHAPES, GeometrySpec

__all__ = [
    "ConfigError",
    "load_config",
    "parse_config",
    "apply_override",
    "check_data_and_material",
    "geometry_error",
]


_POSITIVE = {
    ("geometry", "h"),
    ("geometry", "subdomain_size"),
    ("geometry", "width"),
    ("geometry", "radius"),
    ("solver", "tol"),
    ("solver", "max_iterations"),
    ("solver", "projection_max_iterations"),
    ("solver", "signorini_weight"),
    ("material", "eps"),
    ("material", "E"),
    ("material", "bulk"),
    ("material", "shear"),
    ("exterior", "E"),
    ("adapt", "max_dofs"),
}


def _type_name(value: Any) -> str:
    return {
        bool: "a boolean",
        int: "an integer",
        float: "a number",
        str: "a string",
        list: "a list",
    }[type(value)]


def _check_value(section: str, key: str, value: Any) -> Any:
    """Return ``value`` converted to the schema type of ``section.key`` or raise."""
    default = DEFAULTS[section][key]
    name = f"{section}.{key}"
    if (section, key) == ("solver", "step"):
        if value == "auto":
            return value
        if (
            isinstance(value, (int, float))
            and not isinstance(value, bool)
            and value > 0
            and math.isfinite(value)
        ):
            return float(value)
        raise ConfigError(f'{name} must be "auto" or a positive number, got {value!r}')
    if (section, key) == ("geometry", "signorini"):
        return _check_signorini(value)
    if section == "data" and key in VECTOR_DATA and isinstance(value, list):
        return vector_value(name, value, key == "a")
    if (section, key) == ("material", "shear") and isinstance(value, str):
        if not value.strip():
            raise ConfigError(f"{name} must be a positive number or an expression in s")
        return value
    if isinstance(default, bool):
        if not isinstance(value, bool):
            raise ConfigError(f"{name} must be true or false, got {value!r}")
    elif isinstance(default, float):
        if (
            isinstance(value, bool)
            or not isinstance(value, (int, float))
            or not math.isfinite(value)
        ):
            raise ConfigError(f"{name} must be a finite number, got {value!r}")
        value = float(value)
    elif isinstance(default, int):
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(f"{name} must be an integer, got {value!r}")
    elif not isinstance(value, type(default)):
        raise ConfigError(f"{name} must be {_type_name(default)}, got {value!r}")
    if (section, key) in CHOICES and value not in CHOICES[section, key]:
        options = ", ".join(f'"{c}"' for c in CHOICES[section, key])
        raise ConfigError(f"{name} must be one of {options}, got {value!r}")
    if (section, key) in _POSITIVE and not value > 0:
        raise ConfigError(f"{name} must be positive, got {value!r}")
    if (section, key) == ("geometry", "center"):
        value = _point(name, value, sizes=(2, 3))
    if (section, key) == ("geometry", "semi_axes"):
        value = _semi_axes(name, value)
    if (section, key) == ("geometry", "vertices"):
        value = [_point(f"{name}[{i}]", v) for i, v in enumerate(value)]
    if key == "nu" and not -1.0 < value < 0.5:
        raise ConfigError(f"{name} (Poisson's ratio) must lie in (-1, 1/2), got {value!r}")
    if (section, key) == ("solver", "projection_tol") and not 0 <= value < 1:
        raise ConfigError(f"{name} (rho_in of (3.6)) must lie in [0, 1), got {value!r}")
    if (section, key) == ("adapt", "theta") and not 0 < value <= 1:
        raise ConfigError(f"{name} (Doerfler's parameter) must lie in (0, 1], got {value!r}")
    if (section, key) == ("output", "slice"):
        try:
            parse_slice(value)
        except ValueError as err:
            raise ConfigError(f"{name} {err}") from None
    if (section, key) == ("adapt", "steps") and value < 0:
        raise ConfigError(f"{name} must be >= 0 (0: no adaptive refinement), got {value!r}")
    return value


def _point(name: str, value: Any, sizes: tuple[int, ...] = (2,)) -> list[float]:
    """A point of finite numbers with one of ``sizes`` coordinates ([x, y] or [x, y, z])."""
    if (
        not isinstance(value, list)
        or len(value) not in sizes
        or not all(
            isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c)
            for c in value
        )
    ):
        raise ConfigError(f"{name} must be {_POINTS[sizes]}, got {value!r}")
    return [float(c) for c in value]


_POINTS = {
    (2,): "a point [x, y] of two numbers",
    (3,): "a point [x, y, z] of three numbers",
    (2, 3): "a point [x, y] of two numbers (or [x, y, z] for a 3D shape)",
}


def _semi_axes(name: str, value: list) -> list[float]:
    """The ellipse's semi-axes [a, b]: two positive finite numbers."""
    if len(value) != 2 or not all(
        isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c) and c > 0
        for c in value
    ):
        raise ConfigError(
            f"{name} must be [a, b], two positive numbers (the semi-axes along x and y), "
            f"got {value!r}"
        )
    return [float(value[0]), float(value[1])]


def _check_signorini(value: Any) -> str | list:
    """``"all"``, or a list whose items are side names or arcs [[x0, y0], [x1, y1]]; an
    integer names a physical group of a mesh file without a name by its number (gmsh's
    ``Physical Curve(5)``) and is taken as the text "5"."""
    name = "geometry.signorini"
    if value == "all":
        return value
    if not isinstance(value, list):
        raise ConfigError(
            f'{name} must be "all" or a list of arcs [[x0, y0], [x1, y1]] '
            f"or side names, got {value!r}"
        )
    arcs: list = []
    for i, arc in enumerate(value):
        if isinstance(arc, str):
            arcs.append(arc)
        elif isinstance(arc, int) and not isinstance(arc, bool):
            arcs.append(str(arc))
        elif isinstance(arc, list) and len(arc) == 2:
            arcs.append(
                (tuple(_point(f"{name}[{i}][0]", arc[0])), tuple(_point(f"{name}[{i}][1]", arc[1])))
            )
        else:
            raise ConfigError(
                f"{name}[{i}] must be a side name, a physical group number or an arc "
                f"[[x0, y0], [x1, y1]], got {arc!r}"
            )
    return arcs


def parse_config(raw: dict[str, Any], folder: str | Path | None = None) -> RunConfig:
    """Validate a raw configuration mapping and fill in the defaults.

    Parameters
    ----------
    raw
        Mapping section -> {key: value}, as read from TOML.
    folder
        The configuration file's folder: a relative ``geometry.mesh`` is relative to it.

    Returns
    -------
    RunConfig
    """
    config = _checked(raw)
    mesh = config["geometry"]["mesh"]
    if mesh and folder is not None and not Path(mesh).is_absolute():
        config["geometry"]["mesh"] = str(Path(folder) / mesh)
    # after the folder is applied: a mesh file is opened for its dimension
    _check_dimension_keys(config["geometry"], raw.get("geometry", {}))
    try:
        return _typed(config)
    except ValueError as err:  # a combination RunConfig (or GeometrySpec) refuses
        raise ConfigError(str(geometry_error(err))) from None


def _typed(config: dict[str, dict[str, Any]]) -> RunConfig:
    """The :class:`RunConfig` of validated sections (TOML arrays become tuples)."""
    g = config["geometry"]
    signorini = g["signorini"]
    geometry = {
        **g,
        "center": tuple(g["center"]),
        "vertices": tuple(tuple(v) for v in g["vertices"]),
        "semi_axes": tuple(g["semi_axes"]),
        "signorini": signorini if signorini == "all" else tuple(signorini),
    }
    data = {k: tuple(v) if isinstance(v, list) else v for k, v in config["data"].items()}
    return RunConfig(
        problem=ProblemOptions(**config["problem"]),
        geometry=GeometrySpec(**geometry),
        material=MaterialOptions(**config["material"]),
        exterior=ExteriorOptions(**config["exterior"]),
        data=DataOptions(**data),
        solver=solver_options(config["solver"]),
        adapt=AdaptOptions(**config["adapt"]),
        output=OutputOptions(**config["output"]),
    )


def _checked(raw: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Every section and key of :data:`DEFAULTS`, the given ones checked."""
    config = copy.deepcopy(DEFAULTS)
    for section, table in raw.items():
        if section not in DEFAULTS:
            known = ", ".join(f"[{s}]" for s in DEFAULTS)
            guess = _closest(section, list(DEFAULTS))
            hint = f"did you mean [{guess}]? " if guess else ""
            raise ConfigError(f"unknown section [{section}]; {hint}the sections are {known}")
        if not isinstance(table, dict):
            raise ConfigError(f"[{section}] must be a table of keys")
        for key, value in table.items():
            if key not in DEFAULTS[section]:
                known = ", ".join(DEFAULTS[section])
                raise ConfigError(
                    f"unknown key {section}.{key}; {_key_hint(section, key)}the keys of "
                    f"[{section}] are {known}"
                )
            config[section][key] = _check_value(section, key, value)
    solver = config["solver"]
    if solver["preconditioner"] == "exact" and solver["boundary_operator"] == "hmatrix":
        raise ConfigError(
            'solver.preconditioner = "exact" factors the dense S_h; set solver.boundary_operator '
            '= "dense" (or "auto" for small boundaries) or use another preconditioner'
        )
    check_equation_keys(config, raw)
    if config["adapt"]["steps"] > 0 and raw.get("solver", {}).get("nested") is not True:
        solver["nested"] = False  # the default (true) applies to plain solves only
    geometry = config["geometry"]
    _check_mesh_keys(geometry, raw.get("geometry", {}))
    if geometry["shape"] == "polygon" and len(geometry["vertices"]) < 3:
        raise ConfigError(
            "geometry.vertices must list at least 3 points [x, y] in "
            'counter-clockwise order when geometry.shape = "polygon"'
        )
    return config


def _closest(word: str, choices: list[str]) -> str | None:
    """The choice closest to a misspelt ``word`` (difflib's ratio at least 0.6), or None."""
    found = difflib.get_close_matches(word, choices, n=1)
    if not found:  # a case slip or a word in the wrong case ("TOL", "Solver")
        found = [c for c in choices if c.lower() == word.lower()]
    return found[0] if found else None


def _key_hint(section: str, key: str) -> str:
    """ "did you mean ...? " for an unknown ``section.key``: the key of that section it is
    closest to, or the same key in the section it belongs to; "" when none is close."""
    guess = _closest(key, list(DEFAULTS[section]))
    if guess:
        return f"did you mean {section}.{guess}? "
    elsewhere = [s for s, table in DEFAULTS.items() if key in table]
    if elsewhere:
        return f"did you mean {elsewhere[0]}.{key} (a key of [{elsewhere[0]}])? "
    return ""


#: The [geometry] keys of a generated shape, which a mesh file sets itself.
GENERATED_KEYS = (
    "shape",
    "center",
    "width",
    "radius",
    "semi_axes",
    "vertices",
    "h",
    "structured",
)


def _check_mesh_keys(geometry: dict[str, Any], given: dict[str, Any]) -> None:
    """``mesh`` excludes the keys of a generated shape; ``subdomains = "physical"`` needs
    ``mesh``; a mesh file takes names of physical groups as ``signorini`` (curve groups
    of a 2D mesh, surface groups of a 3D one)."""
    if not geometry["mesh"]:
        if geometry["subdomains"] != "auto":
            raise ConfigError(
                'geometry.subdomains = "physical" needs geometry.mesh (the physical surface '
                "groups of a mesh file); drop it for a generated shape"
            )
        return
    for key in GENERATED_KEYS:
        if key in given:
            raise ConfigError(
                f"geometry.{key}: the mesh file geometry.mesh sets the geometry; drop "
                f"geometry.{key} (or geometry.mesh)"
            )
    signorini = geometry["signorini"]
    if signorini != "all" and any(not isinstance(s, str) for s in signorini):
        raise ConfigError(
            "geometry.signorini: with geometry.mesh give names of physical groups (curve "
            'groups of a 2D mesh, surface groups of a 3D one: ["contact", ...]) or "all", not '
            "coordinate arcs"
        )


def _check_dimension_keys(geometry: dict[str, Any], given: dict[str, Any]) -> None:
    """A 3D body (``shape = "box"`` or ``"ball"``, or a mesh file of tetrahedra, whose
    dimension is read only when a planar key is given) refuses the keys that mean nothing
    in R^3 (``fem_py.spec.PLANAR_ONLY``) and takes a center [x, y, z]; a planar shape a
    center [x, y]."""
    from fem_py.mesh import spec_dimension

    planar = [key for key in PLANAR_ONLY if key in given]
    if geometry["mesh"]:
        if not planar:
            return
        try:
            dim = spec_dimension(GeometrySpec(mesh=geometry["mesh"]))
        except ValueError as err:
            raise ConfigError(str(geometry_error(err))) from None
    else:
        dim = 3 if geometry["shape"] in SOLID_SHAPES else 2
    if dim == 3 and planar:
        key = planar[0]
        raise ConfigError(f"geometry.{key}: {PLANAR_ONLY[key]}; drop geometry.{key} for a 3D body")
    if "center" in given and len(geometry["center"]) != dim:
        raise ConfigError(
            f"geometry.center must be {_POINTS[(dim,)]} for shape {geometry['shape']!r}, "
            f"got {given['center']!r}"
        )


def apply_override(raw: dict[str, Any], assignment: str) -> None:
    """Apply one ``section.key=value`` override (value in TOML syntax) to ``raw``.

    A value that is not valid TOML is taken as a string, so ``--set material.rho=carstensen``
    works without quotes; so is any value of a string key (expressions, names), so that
    ``--set data.f=2`` means the expression "2".
    """
    lhs, sep, rhs = assignment.partition("=")
    section, dot, key = lhs.strip().partition(".")
    if not sep or not dot or not section or not key:
        raise ConfigError(f"--set expects section.key=value, got {assignment!r}")
    try:
        value = tomllib.loads(f"v = {rhs.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = rhs.strip()
    if (
        isinstance(DEFAULTS.get(section, {}).get(key), str)
        and not isinstance(value, str)
        and (section, key) != ("solver", "step")
        and not (section == "data" and key in VECTOR_DATA and isinstance(value, list))
    ):  # step: "auto" or a number; a vector of data: a list
        value = rhs.strip()
    raw.setdefault(section, {})
    if not isinstance(raw[section], dict):
        raise ConfigError(f"[{section}] must be a table of keys")
    raw[section][key] = value


def load_config(path: str | Path | None, overrides: list[str] = ()) -> RunConfig:
    """Read a TOML file (or nothing), apply ``section.key=value`` overrides, validate."""
    raw: dict[str, Any] = {}
    if path is not None:
        path = Path(path)
        if not path.is_file():
            raise ConfigError(
                f"configuration file {str(path)!r} not found; give the path "
                "of an existing TOML file"
            )
        try:
            raw = tomllib.loads(path.read_text())
        except tomllib.TOMLDecodeError as err:
            raise ConfigError(f"{path}: invalid TOML ({err}); fix the syntax") from None
    for assignment in overrides:
        apply_override(raw, assignment)
    return parse_config(raw, None if path is None else Path(path).parent)


def check_data_and_material(config: RunConfig) -> None:
    """Parse the [data] expressions and build the material of a validated configuration.

    Cheap (no mesh, no MPI; a mesh file is opened for its dimension): run it before the
    mesh is built so that a misspelt function or a material violating the structure
    condition of docs/method.md section 1 fails at once. The expressions are evaluated
    symbolically with UFL on an abstract triangle (tetrahedron in 3D) domain, the code
    path of ``fem_py.forms``, so constant sub-expressions that cannot be evaluated
    (``1/0``, ``log(-1)``) are caught too. A body in R^3 refuses what is planar: the
    substructuring preconditioner.

    Raises
    ------
    ConfigError
        The fem_py message, prefixed with the key (``data.f: unknown function ...``).
    """
    import ufl

    from fem_py.forms import make_material, parse_expression

    from fem_py.forms import spatial_variables
    from fem_py.mesh import spec_dimension

    try:  # a mesh file tells its dimension (read here, on every rank)
        dim = spec_dimension(config.geometry)
    except ValueError as err:
        raise ConfigError(str(geometry_error(err))) from None
    if dim == 3:
        _check_solid_options(config)
    elif config.output.slice != "auto":
        raise ConfigError(
            "output.slice: the section slice.png is a figure of a body in R^3; drop "
            "output.slice for a planar domain"
        )
    cell = ufl.tetrahedron if dim == 3 else ufl.triangle
    domain = ufl.Mesh(ufl.VectorElement("Lagrange", cell, 1))
    values = spatial_variables(domain, boundary=True)
    if config.problem.equation == "elasticity":
        check_elastic_data_and_material(config, dim, values)
        return
    for key, names in (DATA_VARIABLES_3D if dim == 3 else DATA_VARIABLES).items():
        text = getattr(config.data, key)
        if key == "exact" and not text:
            continue  # no exact solution known
        try:
            parse_expression(text, {name: values[name] for name in names})
        except ValueError as err:
            raise ConfigError(f"data.{key}: {err}") from None
    material = config.material
    try:
        make_material(material.rho, p=material.p, eps=material.eps)
    except ValueError as err:
        # the power law's own parameters are named in its messages ("needs p > 1")
        key = next(
            (k for k in ("p", "eps") if material.rho == "power" and f"needs {k} " in str(err)),
            "rho",
        )
        raise ConfigError(f"material.{key}: {err}") from None


def _check_solid_options(config: RunConfig) -> None:
    """The options a body in R^3 cannot take yet, each refused in one line."""
    if config.solver.preconditioner == "substructuring":
        raise ConfigError(
            'solver.preconditioner = "substructuring" is the planar preconditioner (docs/method.md '
            'section 6); for a 3D body use "auto" or "amg" (section 11)'
        )


def geometry_error(err: ValueError) -> ValueError:
    """Name the [geometry] key of an error raised by ``fem_py.mesh.build_domain``.

    Its messages start with the name of the argument at fault, which is the key of the
    same name (``signorini arc 0: point ... is not on the boundary``); a too large
    domain is fixed by shrinking it or by ``allow_large``. Other errors are returned
    unchanged.
    """
    message = str(err)
    word = re.match(r"[A-Za-z_()]+", message)
    word = word.group(0) if word else ""
    key = "allow_large" if word == "diam(Omega)" else word
    if key not in DEFAULTS["geometry"]:
        return err
    if message.startswith(f"{key}: "):  # "mesh: ..." names its key once, not twice
        message = message[len(key) + 2 :]
    return ConfigError(f"geometry.{key}: {message}")
