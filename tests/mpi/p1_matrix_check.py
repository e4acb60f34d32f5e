"""fem_py.forms.P1Matrix against DOLFINx's PETSc assembly of the same forms, on any
communicator: Jacobian products y = A x (both Jacobian kinds), the stiffness matrix's
owned rows, and the ranks' local shares of it, which sum to it. Run by
tests/test_p1_matrix.py in serial and under ``mpirun -n 3``, where a rank's owned rows
reach columns that none of its own cells has (``python p1_matrix_check.py out.json``)."""
from __future__ import annotations

import sys

import numpy as np
import scipy.sparse as sp
from dolfinx import fem
from mpi4py import MPI

from fem_py.dofs import p1_space
from fem_py.forms import InteriorForms, P1Matrix, make_material
from fem_py.mesh import GeometrySpec, build_domain


def compute(comm: MPI.Comm) -> dict:
    domain = build_domain(
        comm, GeometrySpec("square", h=1 / 32, subdomain_size=1 / 8, signorini=["bottom"])
    )
    V = p1_space(domain.mesh)
    forms = InteriorForms(V, make_material("carstensen"), "1")
    u = fem.Function(V)
    u.interpolate(lambda x: np.sin(3 * x[0] + 1) * np.cos(2 * x[1]) + x[0] * x[1])
    petsc, p1 = forms.create_matrix(), forms.create_p1_matrix()
    x, y, y_p1 = forms.create_vector(), forms.create_vector(), forms.create_vector()
    x.array[:] = np.random.default_rng(comm.rank).standard_normal(x.array.size)
    out = {"extra_columns": comm.allreduce(int(p1._x is not None), op=MPI.SUM)}

    def largest(a: np.ndarray) -> float:
        return comm.allreduce(float(np.abs(a).max(initial=0.0)), op=MPI.MAX)

    for kind in ("ufl", "handwritten"):
        forms.assemble_jacobian(u, petsc, kind)
        forms.assemble_jacobian(u, p1, kind)
        petsc.mult(x, y)
        p1.mult(x, y_p1)
        out[f"product_{kind}"] = largest(y.array - y_p1.array) / largest(y.array)
        with y_p1.localForm() as local:
            out[f"ghosts_zero_{kind}"] = largest(local.array[p1.n_owned :]) == 0.0
    forms.assemble_stiffness(petsc)
    indptr, indices, data = petsc.getValuesCSR()
    r0, r1 = petsc.getOwnershipRange()
    reference = sp.csr_matrix((data, indices, indptr), shape=(r1 - r0, petsc.getSize()[1]))
    rows = forms.stiffness_rows(p1)
    out["stiffness_rows"] = largest((reference - rows).data) / largest(reference.data)
    out["stiffness_shape"] = list(rows.shape) == [r1 - r0, petsc.getSize()[1]]
    # a new P1Matrix for the stiffness alone gives the same rows
    alone = forms.stiffness_rows()
    out["stiffness_alone"] = largest((alone - rows).data)
    # the ranks' shares (their cells' sums, local numbers) add up to the whole matrix
    local = forms.stiffness_local(p1).tocoo()
    index_map = V.dofmap.index_map
    row_global = np.concatenate([np.arange(r0, r1), index_map.ghosts])
    n = petsc.getSize()[0]
    total, whole = np.zeros((n, n)), np.zeros((n, n))
    np.add.at(total, (row_global[local.row], p1._global(local.col)), local.data)
    whole[r0:r1] = reference.toarray()
    for a in (total, whole):
        comm.Allreduce(MPI.IN_PLACE, a, op=MPI.SUM)
    out["stiffness_local"] = float(np.abs(total - whole).max() / np.abs(whole).max())
    out["is_p1_matrix"] = isinstance(p1, P1Matrix)
    for obj in (petsc, x, y, y_p1):
        obj.destroy()
    return out


if __name__ == "__main__":
    from saved import save_json  # beside this script (tests import compute() alone)

    save_json(MPI.COMM_WORLD, sys.argv[1], compute(MPI.COMM_WORLD))
