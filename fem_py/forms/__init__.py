"""The interior problem's forms: the user's expressions parsed safely (``expressions``),
the nonlinear materials rho (``materials``), the interior energy, its residual and
Jacobians and the data loads (``interior``), a P1 matrix without PETSc's insertion
(``p1_matrix``), and the check of the two Jacobians
(``jacobian_check``)."""
from fem_py.dofs.p1 import p1_space
from fem_py.forms.expressions import Expression, from_sympy, numpy_function, parse_expression
from fem_py.forms.interior import (
    JACOBIANS,
    InteriorForms,
    as_ufl_data,
    assemble_boundary_load,
    assemble_linear_form,
    compile_form,
    spatial_variables,
)
from fem_py.forms.jacobian_check import check_jacobian
from fem_py.forms.materials import BUILTIN_MATERIALS, Material, make_material
from fem_py.forms.p1_matrix import P1Matrix

__all__ = [
    "BUILTIN_MATERIALS",
    "Expression",
    "InteriorForms",
    "JACOBIANS",
    "Material",
    "P1Matrix",
    "as_ufl_data",
    "assemble_boundary_load",
    "assemble_linear_form",
    "check_jacobian",
    "compile_form",
    "from_sympy",
    "make_material",
    "numpy_function",
    "p1_space",
    "parse_expression",
    "spatial_variables",
]
