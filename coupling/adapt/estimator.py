"""Residual a posteriori estimator of the discrete problem (2.3), per cell.

The formula, its terms and references (Carstensen-Stephan M2AN 1995; Aurada et al.
Comput Mech 2013; Veeser SINUM 2001; Braess Numer Math 2005): docs/design/estimator.md.
With sigma_h = rho(|grad u_h|) grad u_h the discrete interior flux, psi_h the exterior
flux (``solution.flux``), v_h = u_h + phi_h - u0 the trace of u_e and lambda_h the
discrete contact pressure on Gamma_s,

    eta_T^2 = h_T^2 ||f + div sigma_h||_T^2                                 volume
            + 1/2 sum_{E in T, interior} h_E ||[sigma_h . n]||_E^2           jumps
            + sum_{E in T, on Gamma} h_E ||sigma_h . n - psi_h - t0||_E^2    flux mismatch
            + sum_{E in T, on Gamma} h_E ||d/ds R_h||_E^2                    BIE residual
            + sum_{E in T, on Gamma_s} h_E ||(lambda_h)_+||_E^2
                                     + |(phi_h, lambda_h)_E|                 contact

R_h = (K - I)(v_h - a) - V psi_h is the residual of the first-kind (second) boundary
integral equation of docs/method.md section 2, evaluated by Galerkin matrices of bem_cpp on
the boundary with every panel bisected (on the coarse boundary it is zero by
construction of psi_h) and L2-projected there. Per cell, per term:
:class:`Estimate`. Interior terms by UFL with a DG0 test function (any material of
fem_py.forms.materials); note that for P1, sigma_h is constant on each cell, so the volume
term reduces to h_T^2 ||f||^2 for every material.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import ufl
from dolfinx import fem
from dolfinx import mesh as dmesh
from mpi4py import MPI
from petsc4py import PETSc
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.spatial import cKDTree

import bem_cpp
from coupling.options import HMATRIX_TOL
from fem_py.forms import as_ufl_data, compile_form
from fem_py.forms.interior import VOLUME_DATA_QUADRATURE
from fem_py.parallel import array_from_root
from fem_py.tags import SIGNORINI_TAG0

__all__ = ["Estimate", "estimate", "contact_pressure", "bie_residual", "TERMS"]

#: The terms of eta^2, in the order of the module docstring.
TERMS = ("volume", "jump", "flux", "bie", "contact_positive", "complementarity")
_QUADRATURE = {"quadrature_degree": 4}


@dataclass
class Estimate:
    """eta_T^2 of the owned cells and the global sums of the terms.

    Attributes
    ----------
    cells : (n_owned_cells,) float
        eta_T^2 (all terms).
    terms : dict
        Global sum of each term of :data:`TERMS` (squares; ``complementarity`` enters
        eta^2 unsquared, Braess 2005).
    total : float
        eta = sqrt(sum_T eta_T^2).
    """

    cells: np.ndarray
    terms: dict[str, float]
    total: float


def contact_pressure(problem: Any, u: Any) -> np.ndarray:
    """lambda_h at the boundary nodes: (A(u_h) - b_f)_i / m_i with the lumped boundary mass
    m_i (as coupling.io.quantities.boundary_flux; collective); for elasticity the traction
    sigma(u_h) n, node-major (d n,)."""
    residual = problem.functional.load.duplicate()
    problem.forms.assemble_residual(u, residual)
    residual.axpy(-1.0, problem.functional.load)
    r = problem.boundary.gather(residual)
    residual.destroy()
    return r / np.repeat(problem.boundary.lumped_mass, problem.components)


def _bisected(nodes: np.ndarray) -> np.ndarray:
    mid = 0.5 * (nodes + np.roll(nodes, -1, axis=0))
    return np.stack([nodes, mid], axis=1).reshape(-1, 2)


def _mass(lengths: np.ndarray, space: str) -> sp.csr_matrix:
    """The boundary mass matrix <v_j, psi_i> of the closed polygon with side ``lengths``
    (side i from node i to node i + 1): P1 tests, the cyclic tridiagonal
    (l_{i-1} + l_i)/3, l_i/6; P0 tests (panel i), l_i/2 at nodes i and i + 1 (as
    ``bem_cpp.mass``, sparse)."""
    n = len(lengths)
    i, j = np.arange(n), (np.arange(n) + 1) % n
    if space == "p0":
        half = 0.5 * lengths
        return sp.csr_matrix((np.concatenate([half, half]), (np.r_[i, i], np.r_[i, j])), (n, n))
    rows, cols = np.r_[i, i, j], np.r_[i, j, i]
    vals = np.r_[(lengths + np.roll(lengths, 1)) / 3, lengths / 6, lengths / 6]
    return sp.csr_matrix((vals, (rows, cols)), shape=(n, n))


def bie_residual(nodes: np.ndarray, ue: np.ndarray, flux: np.ndarray, a: float, space: str):
    """h_E ||d/ds R_h||^2_E per panel (n,) of the residual R_h = (K - I)(v_h - a) - V psi_h.

    V_h and K_h on the bisected boundary are applied as H-matrices
    (``bem_cpp.boundary_operators``, blocks to :data:`coupling.options.HMATRIX_TOL`).

    R_h is tested with the hats (``"p1"``) or indicators (``"p0"``) of the boundary with
    every panel bisected, and L2-projected onto that space; ``"p1"``: h_E ||d/ds R_h||^2
    of the projection; ``"p0"`` (no derivative): the inverse-estimate equivalent
    h_E^-1 ||R_h||^2 (the projection is piecewise constant).
    """
    fine = _bisected(nodes)
    v = _bisected(np.column_stack([ue, ue]))[:, 0]
    v[1::2] = 0.5 * (ue + np.roll(ue, -1))
    if space == "p1":
        psi = np.empty(2 * len(ue))
        psi[0::2], psi[1::2] = flux, 0.5 * (flux + np.roll(flux, -1))
    else:
        psi = np.repeat(flux, 2)
    lengths = np.linalg.norm(np.roll(fine, -1, axis=0) - fine, axis=1)
    layers = bem_cpp.boundary_operators(fine, space, tol=HMATRIX_TOL)  # V_h, K_h as H-matrices
    r = layers.double_layer(v - a) - _mass(lengths, space) @ (v - a) - layers.single_layer(psi)
    h = lengths[0::2] + lengths[1::2]
    if space == "p1":
        R = spla.spsolve(_mass(lengths, "p1").tocsc(), r)
        per_fine = (np.roll(R, -1) - R) ** 2 / lengths  # int |R'|^2 on each half panel
        return h * (per_fine[0::2] + per_fine[1::2])
    per_fine = r**2 / lengths  # int R^2 of the P0 projection r / l
    return (per_fine[0::2] + per_fine[1::2]) / h


def _boundary_function(problem: Any, values: np.ndarray, name: str) -> fem.Function:
    """The P1 function on problem.V with ``values`` (boundary order) at the boundary dofs."""
    fn = fem.Function(problem.V, name=name)
    problem.boundary.scatter_add(values, fn.vector)
    fn.x.scatter_forward()
    return fn


def _owned_cell_values(W: Any, vec: PETSc.Vec) -> np.ndarray:
    """The owned entries of a DG0 vector (ghosts summed), in the order of the owned cells
    (the DG0 dof of cell c is dofmap[c], not necessarily c)."""
    vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    n_cells = W.mesh.topology.index_map(W.mesh.topology.dim).size_local
    return vec.array_r[W.dofmap.list.array[:n_cells]].copy()


def _assemble_cellwise(W: Any, form: Any) -> np.ndarray:
    vec = fem.petsc.assemble_vector(compile_form(form))
    out = _owned_cell_values(W, vec)
    vec.destroy()
    return out


def _panel_cells(problem: Any, W: Any, per_panel: np.ndarray) -> np.ndarray:
    """Owned-cell sums of a per-panel quantity (boundary order), each panel to its cell
    (its exterior facet's cell, found by the facet midpoint)."""
    msh = problem.V.mesh
    tdim = msh.topology.dim
    msh.topology.create_connectivity(tdim - 1, tdim)
    facets = dmesh.exterior_facet_indices(msh.topology)
    mids = dmesh.compute_midpoints(msh, tdim - 1, facets)[:, :2]
    nodes = problem.boundary.nodes
    panel_mids = 0.5 * (nodes + np.roll(nodes, -1, axis=0))
    _, panel = cKDTree(panel_mids).query(mids)
    f2c = msh.topology.connectivity(tdim - 1, tdim)
    cells = np.array([f2c.links(f)[0] for f in facets], dtype=np.int32)
    vec = fem.Function(W)
    np.add.at(vec.x.array, W.dofmap.list.array[cells], per_panel[panel])
    return _owned_cell_values(W, vec.vector)


def estimate(problem: Any, solution: Any, *, f: Any = "0", t0: Any = "0") -> Estimate:
    """eta_T^2 per owned cell of ``solution`` of ``problem`` (collective).

    Parameters
    ----------
    problem, solution
        :class:`coupling.problem.SignoriniProblem` and the
        :class:`coupling.solvers.Solution` of it.
    f, t0
        The data the problem was built with (text, numbers or UFL on problem's mesh).
    """
    msh = problem.V.mesh
    comm = msh.comm
    W = fem.FunctionSpace(msh, ("DG", 0))
    w = ufl.TestFunction(W)
    u = solution.u
    sigma = problem.material.flux(ufl.grad(u))
    n = ufl.FacetNormal(msh)
    h_T, h_E = ufl.CellDiameter(msh), ufl.FacetArea(msh)
    f_ufl = as_ufl_data(f, msh, what="f")
    t0_ufl = as_ufl_data(t0, msh, boundary=True, what="t0")
    b = problem.boundary

    psi_nodes = np.asarray(solution.flux, dtype=float)
    if problem.flux_space == "p0":  # the P1 function of the nodal averages
        psi_nodes = 0.5 * (psi_nodes + np.roll(psi_nodes, 1))
    psi = _boundary_function(problem, psi_nodes, "psi")
    pressure = np.zeros(b.n_gamma)
    pressure[b.signorini] = contact_pressure(problem, u)[b.signorini]
    lam = _boundary_function(problem, pressure, "lambda")
    gap = np.zeros(b.n_gamma)
    gap[b.signorini] = solution.phi
    phi = _boundary_function(problem, gap, "phi")

    # the volume term by the load's own rule (f never evaluated at a vertex, three
    # times per cell); sigma_h is cellwise constant
    dx = ufl.dx(metadata=VOLUME_DATA_QUADRATURE)
    # sigma_h(u_h) is constant in each cell for P1 u_h, so the jump term is constant on
    # each interior facet: one quadrature point integrates it exactly
    dS = ufl.dS(metadata={"quadrature_degree": 0})
    ds = ufl.Measure("ds", domain=msh, subdomain_data=problem.domain.facet_tags,
                     metadata=_QUADRATURE)  # fmt: skip
    arcs = tuple(SIGNORINI_TAG0 + k for k in range(len(problem.domain.arcs)))
    jump = ufl.jump(sigma, n)
    cell = {
        "volume": _assemble_cellwise(W, h_T**2 * (f_ufl + ufl.div(sigma)) ** 2 * w * dx),
        "jump": _assemble_cellwise(W, h_E("+") * jump**2 * ufl.avg(w) * dS),
        "flux": _assemble_cellwise(W, h_E * (ufl.dot(sigma, n) - psi - t0_ufl) ** 2 * w * ds),
    }
    per_panel = array_from_root(
        comm,
        lambda: bie_residual(b.nodes, solution.ue, solution.flux, problem.a, problem.flux_space),
    )
    cell["bie"] = _panel_cells(problem, W, per_panel)
    if arcs:
        positive = h_E * ufl.max_value(lam, 0.0) ** 2 * w * ds(arcs)
        cell["contact_positive"] = _assemble_cellwise(W, positive)
        cell["complementarity"] = np.abs(_assemble_cellwise(W, phi * lam * w * ds(arcs)))
    else:
        zeros = np.zeros_like(cell["volume"])
        cell["contact_positive"] = cell["complementarity"] = zeros
    total = sum(cell[t] for t in TERMS)
    terms = {t: comm.allreduce(float(cell[t].sum()), op=MPI.SUM) for t in TERMS}
    return Estimate(cells=total, terms=terms, total=float(np.sqrt(sum(terms.values()))))
