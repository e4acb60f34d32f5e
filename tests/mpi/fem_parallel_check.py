"""Partition-independent quantities of fem_py, computed on any communicator.

Run by tests/test_fem_mpi.py under ``mpirun -n 2`` (``python fem_parallel_check.py out.json``)
and compared with the same function called in serial. Also checks, on every rank, that
the global dof numbers stored in CoarseStructure and BoundaryMap point at the right
coordinates (the part that can only go wrong in parallel).
"""
from __future__ import annotations

import sys

import numpy as np
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from fem_py.boundary import BoundaryMap
from fem_py.dofs import p1_space
from fem_py.forms import InteriorForms, check_jacobian, make_material
from fem_py.mesh import GeometrySpec, build_domain

DOMAINS = {
    "square": dict(
        shape="square", h=1 / 16, subdomain_size=1 / 8, signorini=[((-0.2, -0.25), (0.25, 0.1))]
    ),
    "lshape": dict(
        shape="lshape",
        h=1 / 16,
        subdomain_size=1 / 8,
        structured=True,
        signorini=["notch_bottom", "notch_left"],
    ),
}


def _global_coords(V) -> np.ndarray:
    """(N, 2) coordinates of every global dof, on every rank."""
    im = V.dofmap.index_map
    n = im.size_local
    X = V.tabulate_dof_coordinates()[:n, :2]
    out = np.zeros((im.size_global, 2))
    out[np.arange(*im.local_range)] = X
    return V.mesh.comm.allreduce(out)


def _numbering_ok(dom, V, bm) -> dict:
    comm = dom.mesh.comm
    X = _global_coords(V)
    c = dom.coarse
    ok = {
        "vertex_dofs": bool(np.allclose(X[c.vertex_dofs], c.vertex_coords, atol=1e-14)),
        "edge_dofs": all(
            np.allclose(X[d], x, atol=1e-14) for d, x in zip(c.edge_dofs, c.edge_coords)
        ),
        "boundary_dofs": bool(np.allclose(X[bm.dofs], bm.nodes, atol=1e-14)),
    }
    # interior dofs of every local cell carry that cell's subdomain id
    sub = np.full(c.n_dofs, -1)
    sub[c.interior_dofs] = c.subdomain_of_interior_dof
    im = V.dofmap.index_map
    cells = V.dofmap.list.array.reshape(-1, 3)
    glob = np.asarray(im.local_to_global(cells.ravel().astype(np.int32))).reshape(-1, 3)
    tags = np.full(len(cells), -1)
    tags[dom.cell_tags.indices] = dom.cell_tags.values
    s = sub[glob]
    ok["interior_subdomains"] = bool(np.all((s < 0) | (s == tags[:, None])))
    return {k: comm.allreduce(v, op=MPI.LAND) for k, v in ok.items()}


def compute(comm) -> dict:
    out = {}
    material = make_material("carstensen")
    for name, kw in DOMAINS.items():
        kw = {"structured": False, **kw}
        dom = build_domain(comm, GeometrySpec(kw.pop("shape"), **kw))
        V = p1_space(dom.mesh)
        bm = BoundaryMap(V, dom)
        forms = InteriorForms(V, material, "sin(3*x)*y")
        u = fem.Function(V)
        u.interpolate(lambda x: np.sin(3 * x[0] + 1) * np.cos(2 * x[1]) + x[0] * x[1])
        b = forms.create_vector()
        forms.assemble_residual(u, b)
        A = forms.create_matrix()
        norms = {}
        for kind in ("ufl", "handwritten"):
            forms.assemble_jacobian(u, A, kind)
            norms[kind] = A.norm(PETSc.NormType.FROBENIUS)
        bf = forms.assemble_load()
        K = forms.assemble_stiffness()
        c = dom.coarse
        out[name] = {
            "energy": forms.energy(u),
            "residual_norm": b.norm(),
            "jacobian_norm_ufl": norms["ufl"],
            "jacobian_norm_handwritten": norms["handwritten"],
            "load_norm": bf.norm(),
            "stiffness_norm": K.norm(PETSc.NormType.FROBENIUS),
            "n_dofs": c.n_dofs,
            "n_subdomains": c.n_subdomains,
            "n_skeleton_facets": c.n_skeleton_facets,
            "vertex_coords": c.vertex_coords.tolist(),
            "vertex_on_boundary": c.vertex_on_boundary.tolist(),
            "edge_vertices": c.edge_vertices.tolist(),
            "edge_arc": c.edge_arc.tolist(),
            "edge_subdomains": c.edge_subdomains.tolist(),
            "edge_coords": [x.tolist() for x in c.edge_coords],
            "interior_per_subdomain": np.bincount(
                c.subdomain_of_interior_dof, minlength=c.n_subdomains
            ).tolist(),
            "boundary_nodes": bm.nodes.tolist(),
            "signorini": bm.signorini.tolist(),
            "arc_of_signorini": bm.arc_of_signorini.tolist(),
            "trace_u": bm.gather(u.vector).tolist(),
            "boundary_load": forms.boundary_load("1 + x*nx", bm).tolist(),
            "jacobian_check_passed": check_jacobian(dom, material, n_states=1)["passed"],
            "numbering_ok": _numbering_ok(dom, V, bm),
        }
        for obj in (b, A, bf, K):
            obj.destroy()
    return out


if __name__ == "__main__":
    from saved import save_json  # beside this script (tests import compute() alone)

    save_json(MPI.COMM_WORLD, sys.argv[1], compute(MPI.COMM_WORLD))
