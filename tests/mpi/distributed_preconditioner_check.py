"""B_Omega^{-1} g, B_Omega g and the Signorini block of the distributed substructuring
preconditioner against the serial one applied to the gathered problem (rank 0), for
the meshes named on the command line (the unstructured L-shape with the Galerkin coarse
matrix); writes the worst relative differences and the
partition facts to the JSON file in argv[1]."""
import json
import sys

import numpy as np
from mpi4py import MPI

from coupling.distributed import gather_owned_rows, gather_rows
from coupling.preconditioners import SubstructuringPreconditioner, problem_arcs
from coupling.preconditioners.distributed import (
    DistributedSubstructuringPreconditioner,
    subdomain_ranks,
)
from coupling.problem import SignoriniProblem
from fem_py.forms import make_material
from fem_py.mesh import GeometrySpec, build_domain

MESHES = {
    "square": dict(shape="square", h=1 / 32, subdomain_size=1 / 8, signorini=["bottom"]),
    "lshape-unstructured": dict(
        shape="lshape",
        h=1 / 24,
        subdomain_size=1 / 6,
        signorini=["bottom", "notch_left"],
        structured=False,
    ),
    "square-all": dict(shape="square", h=1 / 16, subdomain_size=1 / 4, signorini="all"),
}

comm = MPI.COMM_WORLD
report = {}
for name, kwargs in MESHES.items():
    domain = build_domain(comm, GeometrySpec(**{"structured": False, **kwargs}))
    problem = SignoriniProblem(domain, make_material("linear"), f="1")
    index_map = problem.V.dofmap.index_map
    n_cells = domain.mesh.topology.index_map(2).size_local
    ranks = subdomain_ranks(comm, domain.cell_tags, n_cells, domain.coarse.n_subdomains)
    stiffness = problem.forms.stiffness_rows()  # owned rows, global columns (the serial B)
    arcs = problem_arcs(problem)
    # the unstructured case also checks the Galerkin coarse matrix (its probing products)
    coarse_space = "galerkin" if "unstructured" in name else "graph"
    dist = DistributedSubstructuringPreconditioner(
        comm,
        problem.forms.stiffness_local(),  # this rank's cells' share, local numbers
        index_map,
        domain.coarse,
        ranks,
        domain.subdomain_size,
        arcs,
        edge_form="sqrt-laplacian" if "unstructured" in name else "paper",
        signorini_weight=0.25,
        coarse_space=coarse_space,
    )
    r0, r1 = index_map.local_range
    g = np.random.default_rng(7).standard_normal(index_map.size_global)
    phi = np.random.default_rng(8).standard_normal(dist.n_signorini)
    applied = gather_rows(comm, dist.apply_omega(g[r0:r1]))
    product = gather_rows(comm, dist.matvec_omega(g[r0:r1]))
    csr = gather_owned_rows(comm, stiffness)
    x = gather_rows(comm, problem.V.tabulate_dof_coordinates()[: r1 - r0, :2])
    if comm.rank == 0:
        serial = SubstructuringPreconditioner(
            csr,
            domain.coarse,
            x,
            domain.subdomain_size,
            arcs,
            edge_form=dist.edge_form,
            signorini_weight=0.25,
            coarse_space=coarse_space,
        )
        rel = lambda a, b: float(np.abs(a - b).max() / np.abs(b).max())  # noqa: E731
        report[name] = {
            "apply": rel(applied, serial.apply_omega(g)),
            "matvec": rel(product, serial.matvec_omega(g)),
            "signorini": rel(dist.apply_signorini(phi), serial.apply_signorini(phi)),
            "coarse_factor": type(dist._coarse).__name__,
            "subdomains": int(domain.coarse.n_subdomains),
            "owned_subdomains": np.bincount(ranks, minlength=comm.size).tolist(),
        }
        serial.destroy()
    dist.destroy()
if comm.rank == 0:
    with open(sys.argv[1], "w") as f:
        json.dump(report, f)
