"""Residual a posteriori estimator of the discrete problem (2.3), per cell, in 2D and 3D.

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
construction of psi_h) and L2-projected there. In 3D (a body, docs/method.md section 11)
E runs over the facets (triangles), d/ds is the surface gradient grad_Gamma, the boundary
is refined by splitting every triangle into four at its edge midpoints, and h_E is the
facet size |E|^(1/(d-1)) (the length of a segment, the square root of a triangle's
area), so that every term has the scaling of the 2D one. Per cell, per term:
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
from coupling.options import ESTIMATOR_HMATRIX_NODES_3D, ESTIMATOR_HMATRIX_TOL_3D, HMATRIX_TOL
from fem_py.forms import as_ufl_data, compile_form
from fem_py.forms.interior import VOLUME_DATA_QUADRATURE
from fem_py.parallel import array_from_root
from fem_py.tags import SIGNORINI_TAG0

__all__ = [
    "Estimate",
    "estimate",
    "contact_pressure",
    "bie_residual",
    "surface_bie_residual",
    "TERMS",
]

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


def _split_triangles(nodes: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, ...]:
    """Every triangle split into four at its edge midpoints: (fine nodes (n + e, 3),
    fine triangles (4 m, 3) with the children of triangle t in rows 4 t .. 4 t + 3, same
    orientation, and the edges (e, 2) whose midpoints are the fine nodes n .. n + e - 1)."""
    m = len(triangles)
    sides = np.stack(
        [triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]], axis=1
    ).reshape(-1, 2)
    edges, side_edge = np.unique(np.sort(sides, axis=1), axis=0, return_inverse=True)
    mid = len(nodes) + side_edge.reshape(m, 3)  # midpoints of (a b), (b c), (c a)
    a, b, c = triangles.T
    ab, bc, ca = mid.T
    children = np.stack(
        [
            np.column_stack([a, ab, ca]),
            np.column_stack([ab, b, bc]),
            np.column_stack([ca, bc, c]),
            np.column_stack([ab, bc, ca]),
        ],
        axis=1,
    ).reshape(-1, 3)
    fine = np.vstack([nodes, 0.5 * (nodes[edges[:, 0]] + nodes[edges[:, 1]])])
    return fine, children, edges


def _surface_mass(nodes: np.ndarray, triangles: np.ndarray, space: str) -> sp.csr_matrix:
    """The mass matrix <v_j, psi_i> of the P1 hats v_j on the triangles: P1 tests (area/12
    (1 + delta_ij)) or P0 tests (triangle i: area/3 at its three nodes), as ``bem_cpp.mass``,
    sparse."""
    area = _areas(nodes, triangles)
    n = len(nodes)
    if space == "p0":
        rows = np.repeat(np.arange(len(triangles)), 3)
        return sp.csr_matrix((np.repeat(area / 3, 3), (rows, triangles.ravel())), (len(area), n))
    rows = np.repeat(triangles, 3, axis=1).ravel()
    cols = np.tile(triangles, (1, 3)).ravel()
    local = (np.ones((3, 3)) + np.eye(3)).ravel() / 12
    return sp.csr_matrix((np.outer(area, local).ravel(), (rows, cols)), shape=(n, n))


def _areas(nodes: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    x = nodes[triangles]
    return 0.5 * np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), axis=1)


def _surface_gradient_squared(nodes: np.ndarray, triangles: np.ndarray, R: np.ndarray):
    """|grad_Gamma R|^2 on each triangle of the P1 function with nodal values R: d^T G^-1 d
    with d = (R_b - R_a, R_c - R_a) and G the Gram matrix of the edges b - a, c - a."""
    x = nodes[triangles]
    e1, e2 = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]
    g11, g12, g22 = (np.einsum("md,md->m", u, v) for u, v in ((e1, e1), (e1, e2), (e2, e2)))
    d1, d2 = R[triangles[:, 1]] - R[triangles[:, 0]], R[triangles[:, 2]] - R[triangles[:, 0]]
    return (g22 * d1**2 - 2 * g12 * d1 * d2 + g11 * d2**2) / (g11 * g22 - g12**2)


def surface_bie_residual(
    nodes: np.ndarray,
    triangles: np.ndarray,
    ue: np.ndarray,
    flux: np.ndarray,
    a: float,
    space: str,
    *,
    compression: str = "auto",
) -> np.ndarray:
    """The 3D :func:`bie_residual`: h_E ||grad_Gamma R_h||^2_E per triangle E (m,) of the
    surface ``nodes`` (n, 3), ``triangles`` (m, 3), h_E = |E|^(1/2).

    R_h = (K - I)(v_h - a) - V psi_h is tested with the hats (``"p1"``) or indicators
    (``"p0"``) of the surface with every triangle split into four at its edge midpoints
    (v_h and psi_h prolonged exactly) and L2-projected onto that space; ``"p1"``:
    h_E ||grad_Gamma R_h||^2 of the projection summed over the four children; ``"p0"``:
    the inverse-estimate equivalent h_E^-1 ||R_h||^2. V_h and K_h on the split surface are
    bem_cpp's dense Galerkin matrices (``compression="none"``; O(n^2) memory and time) or
    H-matrices applied once (``"hmatrix"``, P1 only, blocks to
    :data:`coupling.options.ESTIMATOR_HMATRIX_TOL_3D`); ``"auto"``: the H-matrices for the
    P1 flux from :data:`coupling.options.ESTIMATOR_HMATRIX_NODES_3D` split-surface nodes on.
    """
    nodes, triangles = np.asarray(nodes, dtype=float), np.asarray(triangles, dtype=np.int64)
    fine, children, edges = _split_triangles(nodes, triangles)
    ue = np.asarray(ue, dtype=float)
    v = np.concatenate([ue, 0.5 * (ue[edges[:, 0]] + ue[edges[:, 1]])])
    flux = np.asarray(flux, dtype=float)
    if space == "p1":
        psi = np.concatenate([flux, 0.5 * (flux[edges[:, 0]] + flux[edges[:, 1]])])
    else:
        psi = np.repeat(flux, 4)
    if compression == "auto":
        large = space == "p1" and len(fine) >= ESTIMATOR_HMATRIX_NODES_3D
        compression = "hmatrix" if large else "none"
    if compression == "hmatrix":
        layers = bem_cpp.boundary_operators(
            fine, space, tol=ESTIMATOR_HMATRIX_TOL_3D, triangles=children
        )
        r = layers.double_layer(v - a) - layers.single_layer(psi)
    else:
        K = bem_cpp.double_layer(fine, space, triangles=children)
        V = bem_cpp.single_layer(fine, space, triangles=children)
        r = K @ (v - a) - V @ psi
        del K, V
    r -= _surface_mass(fine, children, space) @ (v - a)
    h = np.sqrt(_areas(nodes, triangles))
    fine_area = _areas(fine, children)
    if space == "p1":
        R = spla.spsolve(_surface_mass(fine, children, "p1").tocsc(), r)
        per_fine = _surface_gradient_squared(fine, children, R) * fine_area
        return h * per_fine.reshape(-1, 4).sum(axis=1)
    per_fine = r**2 / fine_area  # int R^2 of the P0 projection r / |t|
    return per_fine.reshape(-1, 4).sum(axis=1) / h


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
    """Owned-cell sums of a per-panel (per-triangle in 3D) quantity (boundary order), each
    panel to its cell (its exterior facet's cell, found by the facet midpoint)."""
    msh = problem.V.mesh
    tdim = msh.topology.dim
    msh.topology.create_connectivity(tdim - 1, tdim)
    facets = dmesh.exterior_facet_indices(msh.topology)
    mids = dmesh.compute_midpoints(msh, tdim - 1, facets)[:, :tdim]
    nodes = problem.boundary.nodes
    if tdim == 3:
        panel_mids = nodes[problem.boundary.triangles].mean(axis=1)
    else:
        panel_mids = 0.5 * (nodes + np.roll(nodes, -1, axis=0))
    _, panel = cKDTree(panel_mids).query(mids)
    f2c = msh.topology.connectivity(tdim - 1, tdim)
    cells = np.array([f2c.links(f)[0] for f in facets], dtype=np.int32)
    vec = fem.Function(W)
    np.add.at(vec.x.array, W.dofmap.list.array[cells], per_panel[panel])
    return _owned_cell_values(W, vec.vector)


def _nodal_flux(problem: Any, flux: np.ndarray) -> np.ndarray:
    """psi_h as nodal values: the P1 coefficients, or for the P0 flux space the averages of
    the panels (2D) or the area-weighted averages of the triangles (3D) at each node."""
    b = problem.boundary
    if problem.flux_space != "p0":
        return flux
    if problem.V.mesh.topology.dim == 2:
        return 0.5 * (flux + np.roll(flux, 1))
    weights = np.repeat(b.triangle_areas, 3)
    total = np.bincount(b.triangles.ravel(), weights=weights, minlength=b.n_gamma)
    summed = np.bincount(
        b.triangles.ravel(), weights=weights * np.repeat(flux, 3), minlength=b.n_gamma
    )
    return summed / total


def _signorini_facets(problem: Any) -> tuple[int, ...] | None:
    """The facet tags of Gamma_s: the arcs' in 2D, the Signorini faces' in 3D; None for
    Gamma_s = Gamma in 3D (every exterior facet), () for no Gamma_s."""
    domain = problem.domain
    if problem.V.mesh.topology.dim == 2:
        return tuple(SIGNORINI_TAG0 + k for k in range(len(domain.arcs)))
    if domain.signorini == "all":
        return None
    return tuple(int(t) for t in domain.signorini)


def _facet_size(msh: Any) -> Any:
    """h_E = |E|^(1/(d-1)): the facet length in 2D, sqrt(area) in 3D."""
    area = ufl.FacetArea(msh)
    return area if msh.topology.dim == 2 else ufl.sqrt(area)


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
    h_T, h_E = ufl.CellDiameter(msh), _facet_size(msh)
    f_ufl = as_ufl_data(f, msh, what="f")
    t0_ufl = as_ufl_data(t0, msh, boundary=True, what="t0")
    b = problem.boundary

    # the P1 function of psi_h (P0: of its nodal averages)
    psi_nodes = _nodal_flux(problem, np.asarray(solution.flux, dtype=float))
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
    contact = _signorini_facets(problem)
    jump = ufl.jump(sigma, n)
    cell = {
        "volume": _assemble_cellwise(W, h_T**2 * (f_ufl + ufl.div(sigma)) ** 2 * w * dx),
        "jump": _assemble_cellwise(W, h_E("+") * jump**2 * ufl.avg(w) * dS),
        "flux": _assemble_cellwise(W, h_E * (ufl.dot(sigma, n) - psi - t0_ufl) ** 2 * w * ds),
    }
    if msh.topology.dim == 3:
        args = (b.nodes, b.triangles, solution.ue, solution.flux, problem.a, problem.flux_space)
        per_panel = array_from_root(comm, lambda: surface_bie_residual(*args), all_cores=True)
    else:
        args = (b.nodes, solution.ue, solution.flux, problem.a, problem.flux_space)
        per_panel = array_from_root(comm, lambda: bie_residual(*args))
    cell["bie"] = _panel_cells(problem, W, per_panel)
    if contact is None or contact:
        on_s = ds if contact is None else ds(contact)
        positive = h_E * ufl.max_value(lam, 0.0) ** 2 * w * on_s
        cell["contact_positive"] = _assemble_cellwise(W, positive)
        cell["complementarity"] = np.abs(_assemble_cellwise(W, phi * lam * w * on_s))
    else:
        zeros = np.zeros_like(cell["volume"])
        cell["contact_positive"] = cell["complementarity"] = zeros
    total = sum(cell[t] for t in TERMS)
    terms = {t: comm.allreduce(float(cell[t].sum()), op=MPI.SUM) for t in TERMS}
    return Estimate(cells=total, terms=terms, total=float(np.sqrt(sum(terms.values()))))
