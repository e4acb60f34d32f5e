"""Reproducibility study of the claims of docs/method.md section 7 (``make study``).

Six parts, each a module with the same interface (:class:`study.base.Part`:
``run`` returns tables, lists of dicts, one dict a row; ``summarize``, ``plot`` and
``summary_markdown`` derive the page from the tables), written by
:class:`~study.writer.ResultWriter` as CSV files, markdown tables and PNG plots:

``iterations``  PGPM iterations to tol = 1e-8 against h at fixed d/h and against d/h
                at fixed d (claims 7.1 and 7.4; Theorems 3.1 and 4.1), for the
                ``substructuring``, ``identity`` and ``exact`` preconditioners, and
                the other solver methods (``apgpm``, ``ssn``).
``spectrum``    extreme eigenvalues of B^{-1} A (A of (4.2)) and of B^{-1} D^2 J_h(xi_h)
                by Lanczos in the B inner product (claim 7.2, Theorem 4.1); the rate
                of Theorem 3.1 predicted from them; cond(M_s) (claim 7.3, (4.6)); the
                reference values of docs/method.md section 6 recomputed.
``projection``  the inexact projection (3.20) with its certified stopping rule (3.6):
                inner iterations per step and outer counts for several rho_in and caps,
                against the exact projection and against (3.20) stopped by (3.6) with
                the true optimum (what (3.6) itself demands).
``errors``      discretisation errors on the manufactured solutions of docs/method.md
                section 8 and their observed orders (claim 7.5), linear and carstensen
                material, square and L-shape, P1 flux (and P0 flux for comparison).
``variants``    the edge forms ``paper`` and ``sqrt-laplacian`` (iterations and kappa);
                the ``ufl`` and ``handwritten`` Jacobians (assembly time, iterates).
``adaptivity``  uniform against adaptive refinement on the singular L-shape (issue 19):
                dofs, error, estimator, efficiency index and rates per level, and the
                PGPM and ssn counts per level as the mesh grades inside the subdomains.

The other modules: :mod:`~study.sizes` (the sizes of the full and the quick
study), :mod:`~study.common` (the study's problems and small fits),
:mod:`~study.pencil` (the pencil (H, B) and its eigenvalues),
:mod:`~study.provenance`, :mod:`~study.writer` (the files),
:mod:`~study.discussion` (the README's prose) and
:mod:`~study.driver` (the command line and the README).

Every page states the machine, the versions, the git commit and the command. The
README of the output folder is generated last from the CSV files found there, so
parts run separately (``--only``) still give one consistent README.

The test problem is the manufactured contact problem on the square of width 0.5
(:func:`coupling.manufactured.square_contact`, Signorini arc = bottom side) with
the nonlinear material ``carstensen`` (rho(t) = 2 + 1/(1 + t)), unless a part says
otherwise; xi_0 = (0, 0); the solver options are the defaults of
:data:`coupling.options.DEFAULTS` (B = B_Omega + omega B_s with omega = 1/4, P1 flux,
exact projection) with method ``pgpm``, except where a table says otherwise. The
study reads the library and never changes it: each variant is its own
:class:`coupling.options.SolverOptions` or its own problem.

Usage::

    python -m study [--quick] [--out DIR] [--only PART ...] [--readme]

from the root of the source tree (``make study`` runs the full study); ``study`` is
research code beside the library, not part of the installed package.

Run times of the full and the quick study: docs/design/study.md.
"""
from study.common import check_solver_fields
from study.driver import PARTS, REGISTRY, build_parser, main
from study.errors import ERROR_KEYS
from study.iterations import summarize as summarize_iterations
from study.sizes import FULL, QUICK, Sizes
from study.writer import ResultWriter, read_csv

__all__ = [
    "main",
    "build_parser",
    "PARTS",
    "REGISTRY",
    "Sizes",
    "FULL",
    "QUICK",
    "ResultWriter",
    "read_csv",
    "check_solver_fields",
    "summarize_iterations",
    "ERROR_KEYS",
]
