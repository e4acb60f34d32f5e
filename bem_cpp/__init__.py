"""Galerkin BEM for the Laplace and Lame operators on a closed polygon (2D) or a closed triangulated
surface (3D: pass ``triangles=``, docs/method.md section 11, docs/design/bem3d.md).

Operators follow the factor-2 convention of docs/method.md section 2 with
G(x, y) = -(1/2 pi) log|x - y|::

    V psi(x) = 2 int G(x, y) psi(y) ds_y,     K v(x) = 2 int d/dn_y G(x, y) v(y) ds_y,
    W v      = -d/dn (K v)   (Galerkin form via Maue's identity, docs/method.md section 9).

Geometry: ``nodes`` is an (n, 2) float64 array of the boundary nodes of Omega in
counter-clockwise order, the first node not repeated at the end; panel j runs from
node j to node j+1 (mod n) and n_j = (t_y, -t_x) is its outward normal (pointing into
the exterior Omega_e). Trace space: continuous piecewise linear hats v_j of the nodes
(P1). Flux space ``"p1"`` (the same hats) or ``"p0"`` (indicator of panel j). Both have
n degrees of freedom.

All functions validate their input and raise ``ValueError`` with a one-line message:
fewer than 3 nodes, wrong shape, non-finite values, repeated consecutive nodes (also
last == first), clockwise orientation, self-intersection, and, where V_h is factorised,
a logarithmic capacity of Gamma >= 1 (V_h not positive definite).

Integration (bem_cpp/include/bem/log_integrals.hpp): coincident and adjacent panel
pairs in closed form (Duffy split of the adjacent square, after which every integral is
an analytic point-segment moment), nearby pairs with an analytic inner integral and a
Gauss outer rule on pieces at least their own length away, distant pairs with tensor
Gauss rules whose size follows from distance/length. Matrix entries agree with 30-digit
mpmath references to better than 1e-12 relative (docs/design/quadrature.md).

Linear elasticity: every operator, ``steklov_poincare``, ``exterior_flux`` and
``exterior_potential`` take ``kernel=("lame", E, nu)`` (Young's modulus, Poisson ratio; plane
strain in 2D) for the Lame operators of the exterior elastic medium, whose fundamental
solution is Kelvin's (``kelvin_field``; docs/method.md section 12). Every node then carries d
components, dof ``d * node + component`` (node-major, as DOLFINx numbers a vector space); the
double layer and the hypersingular operator are integrated by parts (Gunter derivatives), so
that only weakly singular kernels are integrated, by the Laplace operators' rules.
``exterior_stress`` gives the stress of the medium at exterior points.

Modules: ``checks`` (input validation), ``defaults`` (every default), ``operators``
(dense Galerkin matrices), ``compressed`` (H-matrix operators and S_h), ``dense`` (a
matrix held in single precision, applied in double), ``potentials``
(the representation formula), ``kelvin`` (the point-force field of elasticity),
``surfaces`` (test surfaces in 3D), ``sparse`` (a
supernodal sparse Cholesky factor, for the coarse problem of the FEM preconditioner);
this module only re-exports their public names.
"""
from __future__ import annotations

from bem_cpp._bem import version
from bem_cpp.collectives import mpi_collectives
from bem_cpp.compressed import (
    BoundaryOperators,
    SteklovPoincareOperator,
    boundary_operators,
    steklov_poincare,
)
from bem_cpp.defaults import (
    HMATRIX_ETA,
    HMATRIX_LEAF_SIZE,
    HMATRIX_MAX_ITERATIONS,
    HMATRIX_POTENTIAL_CROSSOVER_DOFS,
    HMATRIX_POTENTIAL_CROSSOVER_POINTS,
    HMATRIX_PRECONDITIONER_TOL,
    HMATRIX_PRODUCT_THREADS,
    HMATRIX_SOLVER_TOL_FACTOR,
)
from bem_cpp.operators import double_layer, exterior_flux, hypersingular, mass, single_layer
from bem_cpp.kelvin import kelvin_field
from bem_cpp.potentials import exterior_potential, exterior_stress

__all__ = [
    "boundary_operators",
    "BoundaryOperators",
    "double_layer",
    "exterior_flux",
    "exterior_potential",
    "exterior_stress",
    "kelvin_field",
    "hypersingular",
    "mass",
    "single_layer",
    "steklov_poincare",
    "SteklovPoincareOperator",
    "version",
    "mpi_collectives",
    "HMATRIX_ETA",
    "HMATRIX_LEAF_SIZE",
    "HMATRIX_MAX_ITERATIONS",
    "HMATRIX_POTENTIAL_CROSSOVER_DOFS",
    "HMATRIX_POTENTIAL_CROSSOVER_POINTS",
    "HMATRIX_PRECONDITIONER_TOL",
    "HMATRIX_PRODUCT_THREADS",
    "HMATRIX_SOLVER_TOL_FACTOR",
]
