"""Safe parser for the user expressions of the configuration (data f, u0, t0, rho).

Grammar (a subset of Python expression syntax, checked node by node, never passed
to ``eval``)::

    expr   := number | name | expr OP expr | -expr | +expr | (expr) | func(expr, ...)
    OP     := + - * / **        ("^" is accepted as a synonym of "**": the text is
                                 rewritten before parsing, so 2*t^2 means 2*(t**2))
    number := 1, 2.5, 1e-3, ...
    name   := a variable given by the caller (x, y; nx, ny in boundary data; t in rho)
              or the constants pi and e
    func   := sin cos tan exp log sqrt abs sinh cosh tanh (one argument)
              atan2(y, x) max(a, b) min(a, b)          (two arguments)

``log`` is the natural logarithm. Precedence follows Python: ``-x**2 = -(x**2)``,
``**`` is right associative.

One parsed tree is evaluated with one of three backends:

- ``"ufl"``: variables are UFL expressions (``ufl.SpatialCoordinate`` components,
  ``ufl.FacetNormal`` components, ...); the result is a UFL expression.
- ``"numpy"``: variables are arrays (or floats); the result is a float array of the
  broadcast shape of the variables.
- ``"sympy"``: variables are sympy symbols; numbers become exact rationals, so that
  sympy can integrate and differentiate (used by :mod:`fem_py.forms.materials`).

:func:`from_sympy` translates sympy results (g and rho' of a material) back to UFL
or numpy.
"""
from __future__ import annotations

import ast
import builtins
import math
from typing import Any, Callable, Mapping

import numpy as np

__all__ = [
    "FUNCTIONS",
    "CONSTANTS",
    "Expression",
    "parse_expression",
    "numpy_function",
    "from_sympy",
]

BACKENDS = ("ufl", "numpy", "sympy")

#: Allowed function names and their number of arguments.
FUNCTIONS: dict[str, int] = {
    "sin": 1,
    "cos": 1,
    "tan": 1,
    "exp": 1,
    "log": 1,
    "sqrt": 1,
    "abs": 1,
    "sinh": 1,
    "cosh": 1,
    "tanh": 1,
    "atan2": 2,
    "max": 2,
    "min": 2,
}
#: Named constants.
CONSTANTS: dict[str, float] = {"pi": math.pi, "e": math.e}

_MAX_LENGTH = 10_000
_BINOPS = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**"}
_UNARY = {ast.USub: "-", ast.UAdd: "+"}


#: The object of each function of :data:`FUNCTIONS` in each backend's module, by name
#: (ufl, numpy, sympy, math; "" where Python's builtin of the same name serves). From
#: sympy, :func:`from_sympy` maps these back (and the inverse functions).
_NAMES: dict[str, tuple[str, str, str, str]] = {
    **{name: (name,) * 4 for name in ("sin", "cos", "tan", "exp", "sqrt", "sinh", "cosh", "tanh")},
    "log": ("ln", "log", "log", "log"),
    "abs": ("", "abs", "Abs", ""),
    "atan2": ("atan_2", "arctan2", "atan2", "atan2"),
    "max": ("max_value", "maximum", "Max", ""),
    "min": ("min_value", "minimum", "Min", ""),
}
_MODULES = ("ufl", "numpy", "sympy", "math")


def _functions(module: str) -> dict[str, Callable]:
    """The functions of :data:`FUNCTIONS` in ``module`` (one of :data:`_MODULES`; math:
    constant folding, all arguments plain numbers, for the ufl backend)."""
    import importlib

    lib, column = importlib.import_module(module), _MODULES.index(module)
    return {
        name: getattr(lib, names[column]) if names[column] else getattr(builtins, name)
        for name, names in _NAMES.items()
    }


class Expression:
    """A validated expression tree, evaluable with the ufl, numpy or sympy backend.

    Parameters
    ----------
    text
        The expression, e.g. ``"sin(pi*x)*exp(-y^2)"``.
    names
        Variable names the expression may use (besides ``pi`` and ``e``).

    Raises
    ------
    ValueError
        Bad syntax, an unknown name or function, a wrong number of arguments, or any
        construct outside the grammar of the module docstring (attribute access,
        subscripts, keywords, strings, comparisons, lambdas, ...). The message names
        the offending token.
    """

    def __init__(self, text: str, names: tuple[str, ...] | list[str] | Mapping[str, Any]):
        if not isinstance(text, str):
            raise ValueError(
                f"expression must be a string, got {type(text).__name__}; "
                "quote it in the configuration"
            )
        if len(text) > _MAX_LENGTH:
            raise ValueError(
                f"expression is {len(text)} characters long; the limit is {_MAX_LENGTH}"
            )
        self.text = text
        self.names = tuple(names)
        for n in self.names:
            if n in FUNCTIONS or n in CONSTANTS:
                raise ValueError(
                    f"variable name '{n}' clashes with a built-in function or constant; rename it"
                )
        source = text.replace("^", "**").strip()
        if not source:
            raise ValueError("expression is empty; give a formula such as '1' or 'sin(pi*x)'")
        self._source = source
        try:
            tree = ast.parse(source, mode="eval")
        except SyntaxError as err:
            col = (err.offset or 1) - 1
            token = source[col : col + 10] or "<end of text>"
            raise ValueError(
                f"cannot parse expression {text!r}: invalid syntax at '{token}' "
                f"(column {col + 1}); use + - * / ** ^, parentheses, numbers and the allowed "
                "names and functions"
            ) from None
        self._tree = tree.body
        self.used_names: set[str] = set()
        self._check(self._tree)

    # ----------------------------------------------------------------- checks
    def _segment(self, node: ast.AST) -> str:
        seg = ast.get_source_segment(self._source, node)
        return seg if seg is not None else type(node).__name__

    def _check(self, node: ast.AST) -> None:
        if isinstance(node, (ast.BinOp, ast.UnaryOp)):
            binary = isinstance(node, ast.BinOp)
            if type(node.op) not in (_BINOPS if binary else _UNARY):
                raise ValueError(
                    f"operator in '{self._segment(node)}' is not allowed in expression "
                    f"{self.text!r}; use {'+ - * / ** only' if binary else 'unary + or - only'}"
                )
            for operand in (node.left, node.right) if binary else (node.operand,):
                self._check(operand)
        elif isinstance(node, ast.Constant):
            if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
                raise ValueError(
                    f"literal '{self._segment(node)}' is not allowed in expression "
                    f"{self.text!r}; only real numbers are"
                )
        elif isinstance(node, ast.Name):
            if node.id not in self.names and node.id not in CONSTANTS:
                if node.id in FUNCTIONS:
                    raise ValueError(
                        f"function '{node.id}' used without arguments in expression {self.text!r}; "
                        f"write {node.id}(...)"
                    )
                allowed = ", ".join(sorted(self.names) + sorted(CONSTANTS))
                raise ValueError(
                    f"unknown name '{node.id}' in expression {self.text!r}; "
                    f"allowed names: {allowed}"
                )
            self.used_names.add(node.id)
        elif isinstance(node, ast.Call):
            if not isinstance(node.func, ast.Name):
                raise ValueError(
                    f"call '{self._segment(node)}' is not allowed in expression {self.text!r}; "
                    f"allowed functions: {', '.join(FUNCTIONS)}"
                )
            name = node.func.id
            if name not in FUNCTIONS:
                raise ValueError(
                    f"unknown function '{name}' in expression {self.text!r}; "
                    f"allowed functions: {', '.join(FUNCTIONS)}"
                )
            if node.keywords:
                raise ValueError(
                    f"keyword arguments in '{self._segment(node)}' are not allowed in expression "
                    f"{self.text!r}; pass arguments by position"
                )
            if len(node.args) != FUNCTIONS[name] or any(
                isinstance(a, ast.Starred) for a in node.args
            ):
                raise ValueError(
                    f"function '{name}' takes {FUNCTIONS[name]} argument(s), got "
                    f"'{self._segment(node)}' in expression {self.text!r}"
                )
            for a in node.args:
                self._check(a)
        elif isinstance(node, ast.Attribute):
            raise ValueError(
                f"attribute access '{self._segment(node)}' is not allowed in expression "
                f"{self.text!r}"
            )
        else:
            raise ValueError(
                f"'{self._segment(node)}' ({type(node).__name__}) is not allowed in expression "
                f"{self.text!r}; use numbers, names, + - * / ** and the allowed functions"
            )

    # ------------------------------------------------------------- evaluation
    def evaluate(self, variables: Mapping[str, Any], backend: str = "ufl") -> Any:
        """Evaluate the tree with the given variable values.

        Parameters
        ----------
        variables
            Value of every name the expression uses (extra names are ignored).
        backend
            ``"ufl"``, ``"numpy"`` or ``"sympy"`` (see the module docstring).

        Returns
        -------
        A UFL expression, a float ndarray (broadcast to the shape of the numpy
        variables; a float when there are none), or a sympy expression.
        """
        if backend not in BACKENDS:
            raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
        missing = self.used_names - set(variables) - set(CONSTANTS)
        if missing:
            raise ValueError(f"expression {self.text!r} needs values for {sorted(missing)}")
        if backend == "numpy":
            arrays = {
                k: np.asarray(v, dtype=float) for k, v in variables.items() if k in self.used_names
            }
            with np.errstate(all="ignore"):
                value = self._eval(self._tree, arrays, _functions("numpy"), "numpy")
                shape = np.broadcast_shapes(*(a.shape for a in arrays.values())) if arrays else ()
                return (
                    np.array(np.broadcast_to(np.asarray(value, dtype=float), shape), dtype=float)
                    if shape
                    else float(value)
                )
        if backend == "ufl":
            import ufl

            value = self._eval(self._tree, variables, _functions("ufl"), "ufl")
            return ufl.as_ufl(value)
        return self._eval(self._tree, variables, _functions("sympy"), "sympy")

    def _eval(self, node: ast.AST, env: Mapping[str, Any], funcs: dict, backend: str) -> Any:
        if isinstance(node, ast.Constant):
            if backend == "sympy":
                import sympy

                return sympy.Rational(repr(float(node.value)))
            return float(node.value)
        if isinstance(node, ast.Name):
            if node.id in env:
                return env[node.id]
            if backend == "sympy":
                import sympy

                return {"pi": sympy.pi, "e": sympy.E}[node.id]
            return CONSTANTS[node.id]
        if isinstance(node, ast.UnaryOp):
            operand = self._eval(node.operand, env, funcs, backend)
            return -operand if isinstance(node.op, ast.USub) else operand
        if isinstance(node, ast.BinOp):
            a = self._eval(node.left, env, funcs, backend)
            b = self._eval(node.right, env, funcs, backend)
            op = _BINOPS[type(node.op)]
            try:
                if op == "+":
                    return a + b
                if op == "-":
                    return a - b
                if op == "*":
                    return a * b
                if op == "/":
                    return a / b
                return _ufl_power(a, b) if backend == "ufl" else a**b
            except (ZeroDivisionError, OverflowError) as err:
                raise ValueError(
                    f"'{self._segment(node)}' in expression {self.text!r} cannot be evaluated "
                    f"({err}); fix the constant"
                ) from None
        # ast.Call (validated in _check)
        name = node.func.id
        args = [self._eval(a, env, funcs, backend) for a in node.args]
        if backend == "ufl" and all(isinstance(a, float) for a in args):
            funcs = _functions("math")
        try:
            return funcs[name](*args)
        except (ValueError, ZeroDivisionError, OverflowError) as err:
            raise ValueError(
                f"'{self._segment(node)}' in expression {self.text!r} cannot be evaluated "
                f"({err}); fix its argument"
            ) from None

    def __repr__(self) -> str:
        return f"Expression({self.text!r}, names={self.names})"


def parse_expression(text: str, variables: Mapping[str, Any], *, backend: str = "ufl") -> Any:
    """Parse ``text`` (names restricted to ``variables``) and evaluate it with ``backend``.

    Example: ``parse_expression("sin(pi*x)*y", {"x": X[0], "y": X[1]})`` with
    ``X = ufl.SpatialCoordinate(mesh)`` gives a UFL expression;
    ``parse_expression("x^2", {"x": np.linspace(0, 1, 5)}, backend="numpy")`` an array.
    """
    return Expression(text, tuple(variables)).evaluate(variables, backend)


def numpy_function(text: str, names: tuple[str, ...]) -> Callable[..., np.ndarray]:
    """Parse once and return ``f(*arrays)`` evaluating ``text`` with numpy.

    The arguments are the arrays of ``names`` in that order; the result is a float array
    of their broadcast shape.
    """
    expr = Expression(text, names)

    def f(*arrays: Any) -> np.ndarray:
        if len(arrays) != len(names):
            raise ValueError(
                f"expression {text!r} expects {len(names)} arrays ({', '.join(names)}), "
                f"got {len(arrays)}"
            )
        return expr.evaluate(dict(zip(names, arrays)), "numpy")

    return f


# ------------------------------------------------------------- sympy -> backend
def _sympy_table(backend: str) -> dict:
    """sympy's function classes -> those of ``backend`` ("ufl" or "numpy"): the
    functions of :data:`_NAMES` (sqrt is a power in sympy) and the inverse functions."""
    import sympy

    functions = _functions(backend)
    table = {getattr(sympy, n[2]): functions[name] for name, n in _NAMES.items() if name != "sqrt"}
    if backend == "ufl":
        import ufl

        def asinh(a):
            return ufl.ln(a + ufl.sqrt(a * a + 1.0))

        def acosh(a):
            return ufl.ln(a + ufl.sqrt(a * a - 1.0))

        def atanh(a):
            return 0.5 * ufl.ln((1.0 + a) / (1.0 - a))

        inverse = (ufl.asin, ufl.acos, ufl.atan, asinh, acosh, atanh, ufl.erf)
    else:
        from scipy import special

        inverse = (np.arcsin, np.arccos, np.arctan, np.arcsinh, np.arccosh, np.arctanh)
        inverse += (special.erf,)
    names = (sympy.asin, sympy.acos, sympy.atan, sympy.asinh, sympy.acosh, sympy.atanh)
    return {**table, **dict(zip(names + (sympy.erf,), inverse))}


def from_sympy(expr: Any, variables: Mapping[str, Any], backend: str = "ufl") -> Any:
    """Translate a sympy expression into UFL or numpy.

    Parameters
    ----------
    expr
        sympy expression built from Add, Mul, Pow, numbers, pi, E, the symbols named in
        ``variables`` and elementary functions (exp, log, trigonometric and hyperbolic
        functions and their inverses, erf, Abs, atan2, Max, Min).
    variables
        Symbol name -> UFL expression or array.
    backend
        ``"ufl"`` or ``"numpy"``.

    Raises
    ------
    ValueError
        The expression contains anything else (Piecewise, unevaluated Integral, special
        functions ...), naming it.
    """
    import sympy

    if backend not in ("ufl", "numpy"):
        raise ValueError(f"backend must be 'ufl' or 'numpy', got {backend!r}")
    table = _sympy_table(backend)

    def walk(e):
        if e.is_Symbol:
            if e.name not in variables:
                raise ValueError(f"symbol '{e.name}' has no value; give it in variables")
            return variables[e.name]
        if e.is_Number or isinstance(e, sympy.NumberSymbol):
            try:
                v = complex(e)
            except (TypeError, ValueError):
                v = complex(float("nan"))
            if not np.isfinite(v.real) or v.imag != 0.0:
                raise ValueError(f"the constant {e} is not a finite real number")
            return float(v.real)
        if e.is_Add:
            terms = [walk(a) for a in e.args]
            out = terms[0]
            for a in terms[1:]:
                out = out + a
            return out
        if e.is_Mul:
            factors = [walk(a) for a in e.args]
            out = factors[0]
            for a in factors[1:]:
                out = out * a
            return out
        if e.is_Pow:
            base, ex = e.args
            b = walk(base)
            if ex == sympy.Rational(1, 2):
                return np.sqrt(b) if backend == "numpy" else _ufl_sqrt(b)
            if ex == -1:
                return 1.0 / b
            if backend == "numpy":
                return b ** int(ex) if ex.is_Integer else b ** walk(ex)
            return _ufl_power(b, walk(ex))
        func = e.func
        if func in table:
            args = [walk(a) for a in e.args]
            f = table[func]
            if func in (sympy.Max, sympy.Min) and len(args) > 2:
                out = f(args[0], args[1])
                for a in args[2:]:
                    out = f(out, a)
                return out
            return f(*args)
        raise ValueError(
            f"'{func.__name__}' in {e} has no {backend} translation; "
            "choose an expression with an elementary closed form"
        )

    return walk(sympy.sympify(expr))


#: The largest integer exponent written out as products in UFL (:func:`_ufl_power`).
_PRODUCT_POWER_LIMIT = 16


def _ufl_power(a: Any, b: Any) -> Any:
    """a**b for UFL, with an integer exponent n, 2 <= |n| <= :data:`_PRODUCT_POWER_LIMIT`,
    written as products of a (repeated squaring: a**5 = (a*a)**2 * a; a**-n = 1/a**n).

    FFCx emits every power as C's ``pow``, and at the JIT's -O2 the compiler replaces only
    ``pow(a, 2.0)`` by a product; the other exponents call libm, whose ``pow`` costs many
    products. The products round up to 7 times (n = -15) where ``pow`` rounds once, a few
    units in the last place; the data are known to no better. Any other exponent, or a
    number base, is left to ``**``."""
    n = b if isinstance(b, int) else int(b) if isinstance(b, float) and b.is_integer() else 0
    if isinstance(a, (int, float)) or not 2 <= abs(n) <= _PRODUCT_POWER_LIMIT:
        return a**b
    result, factor, k = None, a, abs(n)
    while k:
        if k & 1:
            result = factor if result is None else result * factor
        k >>= 1
        if k:
            factor = factor * factor
    return 1.0 / result if n < 0 else result


def _ufl_sqrt(b: Any) -> Any:
    import ufl

    return math.sqrt(b) if isinstance(b, float) else ufl.sqrt(b)
