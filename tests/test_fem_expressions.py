"""fem_py.forms.expressions: values of a table of expressions in all three backends, and the
rejection of everything outside the grammar (no eval: injection attempts must fail)."""
from __future__ import annotations

import math

import numpy as np
import pytest
import sympy
import ufl
from dolfinx import fem, mesh
from mpi4py import MPI

from fem_py.forms import Expression, from_sympy, numpy_function, parse_expression

# (text, reference numpy function of x, y)
TABLE = [
    ("x + 2*y", lambda x, y: x + 2 * y),
    ("x^2 - y**3", lambda x, y: x**2 - y**3),
    ("-x**2", lambda x, y: -(x**2)),
    ("2^3^2 + 0*x", lambda x, y: 512.0 + 0 * x),
    ("2**-1*x", lambda x, y: 0.5 * x),
    ("1e-3*x + 2.5E2*y", lambda x, y: 1e-3 * x + 250.0 * y),
    ("sin(pi*x)*cos(y)", lambda x, y: np.sin(np.pi * x) * np.cos(y)),
    (
        "tan(x) + sinh(y) + cosh(x) + tanh(y)",
        lambda x, y: np.tan(x) + np.sinh(y) + np.cosh(x) + np.tanh(y),
    ),
    ("exp(x) - log(y + 2)", lambda x, y: np.exp(x) - np.log(y + 2)),
    ("sqrt(abs(x)) + abs(y)", lambda x, y: np.sqrt(np.abs(x)) + np.abs(y)),
    ("atan2(y, x)", lambda x, y: np.arctan2(y, x)),
    ("max(x, y) - 2*min(x, y)", lambda x, y: np.maximum(x, y) - 2 * np.minimum(x, y)),
    ("e**x + (x + 1)/(y + 3)", lambda x, y: np.e**x + (x + 1) / (y + 3)),
    ("+x - -y", lambda x, y: x + y),
    (
        "x**5 - (y + 2)**-3 + (x*y)^16 + x**17 - abs(x)**2.5",
        lambda x, y: x**5 - (y + 2) ** -3.0 + (x * y) ** 16 + x**17 - np.abs(x) ** 2.5,
    ),
]

POINTS = np.array([[0.3, -0.7], [-0.45, 0.2], [0.1, 0.9], [-0.8, -0.35]])


@pytest.mark.parametrize("text, ref", TABLE)
def test_numpy_backend(text, ref):
    x, y = POINTS[:, 0], POINTS[:, 1]
    got = parse_expression(text, {"x": x, "y": y}, backend="numpy")
    # same operations in the same order as numpy: agreement to a few ulps
    assert got.shape == x.shape
    assert np.allclose(got, ref(x, y), rtol=1e-14, atol=1e-14)
    assert np.allclose(numpy_function(text, ("x", "y"))(x, y), got, rtol=0, atol=0)


@pytest.mark.parametrize("text, ref", TABLE)
def test_sympy_backend(text, ref):
    xs, ys = sympy.symbols("x y", real=True)
    e = parse_expression(text, {"x": xs, "y": ys}, backend="sympy")
    for px, py in POINTS:
        assert float(e.subs({xs: px, ys: py}).evalf(30)) == pytest.approx(
            ref(px, py), rel=1e-13, abs=1e-13
        )
    # back to numpy through from_sympy
    got = from_sympy(e, {"x": POINTS[:, 0], "y": POINTS[:, 1]}, "numpy")
    assert np.allclose(
        np.broadcast_to(got, (len(POINTS),)),
        ref(POINTS[:, 0], POINTS[:, 1]),
        rtol=1e-13,
        atol=1e-13,
    )


def test_ufl_backend_matches_numpy():
    """Evaluate every table entry as a UFL expression at cell midpoints (fem.Expression)."""
    msh = mesh.create_rectangle(
        MPI.COMM_SELF, [np.array([-0.9, -0.9]), np.array([0.9, 0.9])], [3, 3]
    )
    X = ufl.SpatialCoordinate(msh)
    ref_point = np.array([[1.0 / 3.0, 1.0 / 3.0]])
    cells = np.arange(msh.topology.index_map(2).size_local, dtype=np.int32)
    gdofs = msh.geometry.dofmap.array.reshape(-1, 3)[cells]
    mid = msh.geometry.x[gdofs][:, :, :2].mean(axis=1)
    for text, ref in TABLE:
        # + Constant(0): a constant entry (2^3^2 + 0*x) still needs a domain for fem.Expression
        expr = parse_expression(text, {"x": X[0], "y": X[1]}, backend="ufl") + fem.Constant(
            msh, 0.0
        )
        vals = fem.Expression(expr, ref_point).eval(cells).ravel()
        assert np.allclose(vals, ref(mid[:, 0], mid[:, 1]), rtol=1e-12, atol=1e-12), text


def test_ufl_integer_powers_are_products():
    """Integer exponents 2..16 (either sign) become products in UFL (FFCx would emit libm's
    pow); other exponents stay powers. Their values: test_ufl_backend_matches_numpy."""
    from ufl.corealg.traversal import unique_pre_traversal

    msh = mesh.create_unit_square(MPI.COMM_SELF, 1, 1)
    X = ufl.SpatialCoordinate(msh)

    def exponents(text: str) -> list[str]:
        e = parse_expression(text, {"x": X[0], "y": X[1]})
        return sorted(
            str(n.ufl_operands[1])
            for n in unique_pre_traversal(e)
            if isinstance(n, ufl.classes.Power)
        )

    assert exponents("x**3 + y**-2 + (x*y)^16 + x**2 + x**6.0") == []
    assert exponents("x**2.5 + y**17 + x**y + x**-17") == ["-17.0", "17.0", "2.5", "x[1]"]
    x = sympy.Symbol("x")
    e = from_sympy(x**5 + x**-4, {"x": X[0]})
    assert not any(isinstance(n, ufl.classes.Power) for n in unique_pre_traversal(e))


def test_constant_expression_and_names():
    e = Expression("2*pi + e", ("x",))
    assert e.used_names == {"pi", "e"}
    assert e.evaluate({}, "numpy") == pytest.approx(2 * math.pi + math.e, rel=1e-15)
    assert Expression("x*y", ("x", "y")).used_names == {"x", "y"}


BAD = [
    ("__import__('os')", "__import__"),
    ("__import__('os').system('ls')", "system"),
    ("os.system('ls')", "os.system"),
    ("x.real", "x.real"),
    ("foo(x)", "foo"),
    ("z + 1", "z"),
    ("x +", "invalid syntax"),
    ("x[0]", "x[0]"),
    ("lambda: 1", "lambda"),
    ("'abc'", "'abc'"),
    ("x if y else 1", "x if y else 1"),
    ("x < y", "x < y"),
    ("sin(x, y)", "sin"),
    ("max(x)", "max"),
    ("sin", "sin"),
    ("True", "True"),
    ("sin(x=1)", "keyword"),
    ("[x, y]", "[x, y]"),
    ("1j*x", "1j"),
    ("x % 2", "x % 2"),
    ("(lambda: 0)()", "lambda"),
    ("", "empty"),
]


@pytest.mark.parametrize("text, token", BAD)
def test_rejects(text, token):
    with pytest.raises(ValueError) as err:
        parse_expression(text, {"x": 1.0, "y": 2.0}, backend="numpy")
    msg = str(err.value)
    assert token in msg
    assert "\n" not in msg


def test_rejects_non_string_and_bad_backend():
    with pytest.raises(ValueError, match="must be a string"):
        Expression(3.0, ("x",))
    with pytest.raises(ValueError, match="backend"):
        parse_expression("x", {"x": 1.0}, backend="c")
    with pytest.raises(ValueError, match="clashes"):
        Expression("sin + 1", ("sin",))


def test_constant_errors_are_value_errors():
    with pytest.raises(ValueError, match="1/0"):
        parse_expression("1/0", {"x": 1.0}, backend="ufl")
    with pytest.raises(ValueError, match="log"):
        parse_expression("log(-1) + x", {"x": 1.0}, backend="ufl")
