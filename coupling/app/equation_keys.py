"""Which configuration keys belong to which equation (``[problem] equation``): the scalar
equation of the paper or elasticity (docs/method.md section 12). Elasticity's data are
vectors (:data:`VECTOR_DATA`), its material is ``model`` with its own keys, its medium is
``[exterior]``; the keys of one equation are refused with the other, each in one line
(:class:`coupling.app.errors.ConfigError`)."""
from __future__ import annotations

import math
from typing import Any

from coupling.app.errors import ConfigError
from coupling.options import (
    DATA_VARIABLES,
    DATA_VARIABLES_3D,
    DEFAULTS,
    ELASTIC_MATERIAL_KEYS,
    SCALAR_MATERIAL_KEYS,
    RunConfig,
)

__all__ = [
    "VECTOR_DATA",
    "vector_value",
    "check_equation_keys",
    "check_elastic_data_and_material",
]


#: The [data] keys that are vectors for elasticity (lists of d expressions; of numbers for a).
VECTOR_DATA = ("f", "u0", "t0", "a")


def vector_value(name: str, value: list, numbers: bool) -> list:
    """A vector of [data] (elasticity): 2 or 3 expressions, or numbers for ``a``."""
    kind = "numbers" if numbers else "expressions (strings)"
    valid = (
        (lambda c: isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c))
        if numbers
        else (lambda c: isinstance(c, str) and c.strip() != "")
    )
    if len(value) not in (2, 3) or not all(valid(c) for c in value):
        raise ConfigError(
            f"{name} must be a vector of 2 or 3 {kind}, one per component, got {value!r}"
        )
    return [float(c) for c in value] if numbers else list(value)


def check_equation_keys(config: dict[str, dict[str, Any]], raw: dict[str, Any]) -> None:
    """The keys of one equation refused with the other (each in one line): the elastic
    material keys, [exterior], problem.tangential and vector data with the scalar equation;
    the scalar material keys, scalar data (f, u0, t0, a given as one value), the exact
    solution, adaptivity, the estimator and the scalar preconditioners with elasticity; an
    elastic model's keys with the other model."""
    given = {section: set(table) for section, table in raw.items() if isinstance(table, dict)}
    material, data = given.get("material", set()), given.get("data", set())
    if config["problem"]["equation"] == "scalar":
        elastic = sorted(material - set(SCALAR_MATERIAL_KEYS))
        wrong = [f"material.{elastic[0]} is a key"] if elastic else []
        wrong += ["[exterior] is a section"] if "exterior" in given else []
        if "tangential" in given.get("problem", set()):
            wrong += ["problem.tangential is a key"]
        vectors = [k for k in VECTOR_DATA if isinstance(config["data"][k], list)]
        wrong += [f"data.{k} is a vector: a value" for k in vectors]
        if wrong:
            raise ConfigError(
                f'{wrong[0]} of elasticity; set problem.equation = "elasticity" or drop it'
            )
        return
    scalar = [k for k in SCALAR_MATERIAL_KEYS if k in material]
    if scalar:
        raise ConfigError(
            f"material.{scalar[0]} belongs to the scalar equation; elasticity takes "
            'material.model = "linear-elastic" (E, nu) or "hencky" (bulk, shear)'
        )
    model = config["material"]["model"]
    other = sorted(material - set(ELASTIC_MATERIAL_KEYS[model]))
    if other:
        keys = ", ".join(ELASTIC_MATERIAL_KEYS[model][1:])
        raise ConfigError(
            f'material.{other[0]} is not a key of model "{model}", which takes {keys}; drop it'
            " or change material.model"
        )
    for key in VECTOR_DATA:
        if key in data and not isinstance(config["data"][key], list):
            example = "[0.0, 0.0]" if key == "a" else '["0", "-1"]'
            raise ConfigError(
                f"data.{key} must be a vector for elasticity, one entry per component (e.g. "
                f"{example}), got {config['data'][key]!r}"
            )
    refused = {
        ("data", "exact"): "the exact solution is compared for the scalar equation only; drop"
        " data.exact",
        ("adapt", "steps"): "adaptivity is for the scalar equation so far; set adapt.steps = 0",
        ("output", "estimator"): "the a posteriori estimator is for the scalar equation so"
        " far; set output.estimator = false",
        ("output", "indicators"): "the a posteriori estimator is for the scalar equation so"
        " far; set output.indicators = false",
    }
    for (section, key), why in refused.items():
        if config[section][key] != DEFAULTS[section][key]:
            raise ConfigError(f"{section}.{key}: {why}")
    if config["solver"]["preconditioner"] in ("substructuring", "exact"):
        raise ConfigError(
            f'solver.preconditioner = "{config["solver"]["preconditioner"]}" is a preconditioner'
            ' of the scalar equation; for elasticity use "auto" or "amg"'
        )


def check_elastic_data_and_material(config: RunConfig, dim: int, values: dict) -> None:
    """:func:`check_data_and_material` for elasticity: d components of every vector of
    [data] (given vectors; the defaults are zero vectors), each expression parsed, and the
    elastic material and the exterior medium built."""
    from fem_py.forms import parse_expression
    from fem_py.forms.elasticity import hencky, linear_elastic

    table = DATA_VARIABLES_3D if dim == 3 else DATA_VARIABLES
    for key in VECTOR_DATA:
        value = getattr(config.data, key)
        if isinstance(value, tuple) and len(value) != dim:
            raise ConfigError(
                f"data.{key} has {len(value)} components; a {dim}D displacement has {dim}"
            )
        if key == "a" or isinstance(value, str):
            continue
        for k, text in enumerate(value):
            try:
                parse_expression(text, {name: values[name] for name in table[key]})
            except ValueError as err:
                raise ConfigError(f"data.{key}[{k}]: {err}") from None
    m = config.material
    try:  # the messages start with the key: "bulk = 0: ...", "shear = '...': ..."
        if m.model == "hencky":
            hencky(m.bulk, m.shear, dim)
        else:
            linear_elastic(m.E, m.nu, dim)
    except ValueError as err:
        raise ConfigError(f"material.{err}") from None
