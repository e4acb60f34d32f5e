"""The coarse matrix C of the substructuring preconditioner (docs/method.md section 6):
``coarse_space = "graph"`` (the paper's coarse graph Laplacian) and ``"galerkin"``
(Pi^T S Pi + d * boundary term, by probing with a distance-2 colouring), and the
``"auto"`` choice by how the subdomains were made (issue 17).

The probed Galerkin matrix is checked against Pi^T S Pi formed densely (round-off:
the two differ only by the order of the same sparse Cholesky solves), and the PGPM
counts on an imported unstructured mesh against the generated mesh with the same h
and d/h (docs/design/coarse_space.md).
"""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from mpi4py import MPI

from coupling.distributed import gather_matrix
from coupling.options import SolverOptions
from coupling.preconditioners import coarse_space
from coupling.preconditioners.kernels import (
    coarse_vertex_pattern,
    galerkin_coarse_matrix,
    hat_support_on_gamma,
    probing_colours,
)
from coupling.preconditioners.substructuring import skeleton_form
from coupling.problem import SignoriniProblem
from fem_py.forms import make_material
from fem_py.mesh import GeometrySpec, build_domain
from mesh_files import square_msh

COMM = MPI.COMM_WORLD


def _domains(tmp_path):
    h = 1 / 24
    return {
        "lshape": build_domain(
            COMM,
            GeometrySpec(
                "lshape", h=h, subdomain_size=4 * h, signorini=["bottom"], structured=False
            ),
        ),
        "imported": build_domain(
            COMM,
            GeometrySpec(
                mesh=str(square_msh(tmp_path / "sq.msh", h)),
                subdomain_size=4 * h,
                signorini=["bottom"],
            ),
        ),
    }


def test_probing_colours_separate_the_columns_of_every_row():
    rng = np.random.default_rng(3)
    a = sp.random(300, 300, density=0.01, random_state=rng, format="csr")
    pattern = ((a + a.T + sp.identity(300)) != 0).astype(float).tocsr()
    colour = probing_colours(pattern)
    for i in range(300):
        cols = pattern.indices[pattern.indptr[i] : pattern.indptr[i + 1]]
        assert len(np.unique(colour[cols])) == len(cols), i
    # deterministic: the colouring is a function of the pattern
    assert np.array_equal(colour, probing_colours(pattern))


def test_galerkin_coarse_matrix_is_the_energy_of_the_coarse_functions(tmp_path):
    for name, domain in _domains(tmp_path).items():
        problem = SignoriniProblem(domain, make_material("linear"), f="1")
        a = gather_matrix(problem.forms.assemble_stiffness()).tocsr()
        c = domain.coarse
        sk, ii = np.asarray(c.skeleton_dofs), np.asarray(c.interior_dofs)
        x = problem.V.tabulate_dof_coordinates()[:, :2]
        interp = skeleton_form(c, x, domain.subdomain_size, a.shape[0], "paper").interp
        a_ii, a_is, a_ss = a[ii][:, ii].tocsc(), a[ii][:, sk], a[sk][:, sk]

        def schur(p):
            return a_ss @ p - a_is.T @ spla.spsolve(a_ii, a_is @ p)

        p = interp.toarray()
        # the boundary term: min(d, the length of Gamma each coarse hat covers); with
        # straight coarse edges on Gamma that length is the sum of the two chords at v
        ends = np.asarray(c.edge_vertices)[np.asarray(c.edge_on_boundary, dtype=bool)]
        xy = np.asarray(c.vertex_coords)
        chord = np.linalg.norm(xy[ends[:, 0]] - xy[ends[:, 1]], axis=1)
        support = np.bincount(ends.ravel(), np.repeat(chord, 2), minlength=len(xy))
        assert np.allclose(hat_support_on_gamma(c), support, rtol=1e-12, atol=0), name
        weight = np.where(support > 0, np.minimum(domain.subdomain_size, support), 0.0)
        dense = p.T @ schur(p) + np.diag(weight)
        probed = galerkin_coarse_matrix(
            c, domain.subdomain_size, lambda e: interp.T @ schur(interp @ e)
        ).toarray()
        assert np.abs(probed - dense).max() <= 1e-12 * np.abs(dense).max(), name
        # entries only where two vertices share a subdomain: the probing pattern
        outside = coarse_vertex_pattern(c).toarray() == 0
        assert np.abs(dense[outside]).max() <= 1e-12 * np.abs(dense).max(), name
        assert np.all(np.linalg.eigvalsh(probed) > 0), name


def test_auto_is_galerkin_on_subdomains_made_of_cells(tmp_path):
    domains = _domains(tmp_path)
    assert coarse_space(domains["lshape"], "auto") == "graph"
    assert coarse_space(domains["imported"], "auto") == "galerkin"
    assert coarse_space(domains["imported"], "graph") == "graph"
    with pytest.raises(ValueError, match="coarse_space must be one of"):
        SolverOptions(coarse_space="exact")
