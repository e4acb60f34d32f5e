"""fem_py.forms.materials: g' = t rho, rho' against finite differences, closed forms, the
structural check of docs/method.md section 1 and the error messages."""
from __future__ import annotations

import numpy as np
import pytest

from conftest import TEST_MATERIALS
from fem_py.forms import make_material

MATERIALS = [*TEST_MATERIALS, ("2 + 1/(1+t)", {})]
T = np.linspace(0.05, 5.0, 60)


@pytest.fixture(scope="module", params=MATERIALS, ids=lambda m: m[0] + str(m[1].get("p", "")))
def material(request):
    name, kw = request.param
    return make_material(name, **kw)


def test_energy_derivative_is_t_rho(material):
    """g'(t) = t rho(t) (2.1). Central differences with step 1e-5: truncation
    |g'''| k^2/6 <= 1e-9 for these smooth g, cancellation 1e-16 |g|/k <= 1e-10."""
    k = 1e-5
    fd = (material.g_np(T + k) - material.g_np(T - k)) / (2 * k)
    assert np.allclose(fd, T * material.rho_np(T), rtol=1e-7, atol=1e-9)
    assert material.g_np(0.0) == pytest.approx(0.0, abs=1e-15)


def test_drho_is_derivative(material):
    k = 1e-5
    fd = (material.rho_np(T + k) - material.rho_np(T - k)) / (2 * k)
    assert np.allclose(fd, material.drho_np(T), rtol=1e-7, atol=1e-9)


def test_structure_constants(material):
    assert 0 < material.alpha <= material.beta
    assert material.rho0 == pytest.approx(float(material.rho_np(0.0)), rel=1e-15)


def test_closed_forms():
    t = np.linspace(0.0, 10.0, 41)
    m = make_material("carstensen")
    assert np.allclose(m.rho_np(t), 2 + 1 / (1 + t), rtol=1e-15)
    assert np.allclose(m.g_np(t), t**2 + t - np.log1p(t), rtol=1e-14, atol=1e-15)
    # d/dt (t rho) = 2 + 1/(1+t)^2 in (2, 3]: alpha ~ 2, beta = 3 up to the grid spacing
    assert 2.0 <= m.alpha <= 2.0 + 1e-5 and 3.0 - 1e-2 <= m.beta <= 3.0
    p, eps = 1.5, 0.1
    m = make_material("power", p=p, eps=eps)
    assert np.allclose(m.rho_np(t), (eps**2 + t**2) ** ((p - 2) / 2), rtol=1e-14)
    assert np.allclose(
        m.g_np(t), ((eps**2 + t**2) ** (p / 2) - eps**p) / p, rtol=1e-13, atol=1e-15
    )
    m = make_material("linear")
    assert np.allclose(m.g_np(t), t**2 / 2, rtol=1e-15) and m.alpha == m.beta == 1.0


def test_user_expression_matches_builtin():
    """sympy's int_0^t s rho(s) ds for the carstensen rho equals the built-in closed form."""
    t = np.linspace(0.0, 20.0, 81)
    a, b = make_material("2 + 1/(1 + t)"), make_material("carstensen")
    assert np.allclose(a.g_np(t), b.g_np(t), rtol=1e-13, atol=1e-15)
    assert np.allclose(a.drho_np(t), b.drho_np(t), rtol=1e-14)


def test_p_eps_ignored_for_other_materials():
    assert make_material("linear", p=2.0, eps=1.0).g_np(2.0) == pytest.approx(2.0, rel=1e-15)


@pytest.mark.parametrize(
    "args, kw, match",
    [
        (("power",), {}, "needs both p > 1 and eps > 0"),
        (("power",), {"p": 1.0, "eps": 0.1}, "p > 1"),
        (("power",), {"p": 1.5, "eps": 0.0}, "eps > 0"),
        (("1 - t",), {}, "<= 0"),
        (("1/(1 + t)^2",), {}, "not strictly increasing"),
        (("1/t",), {}, "not finite"),
        (("sqrt(t)",), {}, "<= 0"),
        (("2 + 1/(1 + exp(t))",), {}, "closed form"),
        (("2 + q",), {}, "unknown name 'q'"),
        (("2 +",), {}, "invalid syntax"),
        (("",), {}, "non-empty"),
    ],
)
def test_errors(args, kw, match):
    with pytest.raises(ValueError, match=match) as err:
        make_material(*args, **kw)
    assert "\n" not in str(err.value)


BUILTINS = [("linear", {}), ("carstensen", {}), ("power", {"p": 1.5, "eps": 0.1})]
BUILTINS += [("power", {"p": 3.0, "eps": 0.5})]


@pytest.mark.parametrize("name, kw", BUILTINS, ids=lambda v: str(v))
def test_builtin_closed_forms_are_sympys_derivation(name, kw):
    """The built-ins' hand-derived closed forms (written out so that a run never imports
    sympy) equal what sympy derives from rho: g = int_0^t s rho(s) ds and rho' exactly
    (symbolic difference simplified to 0), G2(s) = g(sqrt(s)) at s in [0, 100] to
    round-off."""
    import sympy

    from fem_py.forms.materials import _evaluate

    m = make_material(name, **kw)
    t, x = sympy.Symbol("t", positive=True), sympy.Symbol("x", positive=True)
    rho = m.rho_sym
    assert sympy.simplify(m.g_sym - sympy.integrate(x * rho.subs(t, x), (x, 0, t))) == 0
    assert sympy.simplify(m.drho_sym - sympy.diff(rho, t)) == 0
    s = np.linspace(0.0, 100.0, 201)
    g2 = _evaluate(m._g2_term, {"s": s}, "numpy")
    assert np.allclose(g2, m.g_np(np.sqrt(s)), rtol=1e-14, atol=1e-15)


def test_a_run_with_a_builtin_material_does_not_import_sympy():
    """sympy costs about half a second of every start-up: the modules of a solve and a
    built-in material do without it (a user's rho imports it, to derive g and rho')."""
    import subprocess
    import sys

    code = (
        "import sys\n"
        "import coupling.app.cli, coupling.app.from_config, coupling.app.run\n"
        "import coupling.io.outputs, coupling.solvers\n"
        "from fem_py.forms import make_material\n"
        "for name in ('linear', 'carstensen'):\n"
        "    make_material(name).tangent\n"
        "make_material('power', p=1.5, eps=0.1)\n"
        "assert 'sympy' not in sys.modules, 'sympy imported'\n"
        "make_material('2 + 1/(1 + t)')\n"
        "assert 'sympy' in sys.modules\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
