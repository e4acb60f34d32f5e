"""The size of a run before it runs: the counts of the domain and a memory estimate.

Peak resident memory of ``fembem solve`` (whole process, outputs included), fitted to
runs on the square at N = 1.6e4 .. 1.6e7 dofs (docs/design/memory.md):

    memory ~ ranks * PROCESS_BYTES + DOF_BYTES * N + BOUNDARY_BYTES * n^2
             (+ ranks * PLOT_PROCESS_BYTES + PLOT_DOF_BYTES * N with the plots)

(the interpreter and its libraries per rank; meshes, forms, factors and vectors per
dof; the dense boundary matrices (V, K, W, S_h: five n x n arrays) while S_h is formed,
n the boundary dofs; matplotlib and the rasterised images of the plots). With the
H-matrix S_h (``[solver] boundary_operator``) the boundary term is
HMATRIX_BOUNDARY_BYTES * n instead, for all ranks together: under MPI each rank holds the
blocks of its own rows of S_h (0.50-0.54 of the serial bytes per rank on 2 ranks) and the
estimator's V, K live on rank 0 alone.

A body in R^3 has its own constants (``DomainSize.dim``): tetrahedra carry more
matrix entries per dof (DOF_BYTES_3D), the dense boundary matrices are eight n x n
arrays (V_h, K_h, W_h, S_h and the P0 single layer of Nedelec's identity on the 2n
triangles, four), the H-matrix S_h holds about 20 KB per boundary dof at the 3D tol 1e-6
(its blocks in single precision; its ranks grow like |log tol|^3 in 3D), and the amg
preconditioner's M_s = E^T W_h E is dense: SIGNORINI_BYTES_3D n_s^2 (M_s in single
precision, as the H-matrix's blocks, and one n_s x n_s double array at most in a nested
run: the factor of its block M_s[I, I] that the projection keeps for the Newton steps;
M_s's own factor only where a step solves with the whole M_s), n_s the Signorini
unknowns, which grow like N^(2/3).
Fitted to whole `fembem solve` runs of the box with figures and XDMF (16^3 .. 128^3
cubes) and library runs (12^3 .. 24^3; docs/design/memory.md, "Bodies in R^3").

The elastic equation (``[problem] equation = "elasticity"``) is the same model with its
own constants (:func:`memory_constants`): :func:`equation_size` gives the counts d per
node (N, n and n_s the unknowns) and ``DomainSize.components`` = d, which selects the
constants and settles ``"auto"`` as the solve does, on the boundary nodes n / d at the
Lame S_h's crossover (bem_cpp.defaults: 1,000 nodes of a polygon, 2,000 vertices of a
surface). On the plane the scalar constants hold (DOF_BYTES_ELASTIC a tenth more per
unknown) and the dense Lame operators are five (2 n_v)^2 arrays as Laplace's. On a body
the dense Lame operators are nine (3 n_v)^2 arrays, M_s = E^T W_h E (read from the
H-matrices of S_h; single precision with them) and M_s^{-1} are SIGNORINI_BYTES_ELASTIC_3D
n_s^2 on every rank, and the Lame H-matrix S_h (its blocks in single precision at the 3D
tolerances, as the Laplace S_h's) is the largest part of the peak; the least squares of
DOF_BYTES_ELASTIC_3D (2.5 KB) and HMATRIX_BOUNDARY_BYTES_ELASTIC_3D (50 KB) share it between
the two terms (n / N falls only from 0.26 to 0.12 over the runs): refit both together
(bench/elastic_memory.py --fit) when S_h changes.
Fitted to whole `fembem solve` runs of bench/elastic.py's square (2,178 .. 2.1e6 dofs) and
box (6^3 .. 48^3 cubes), figures and XDMF (docs/design/memory.md, "Elasticity (2026-12-07)"
and "Refitted after the 48^3 cuts").
"""
from __future__ import annotations

import dataclasses
from typing import Any

from coupling.distributed import boundary_operator_kind
from coupling.options import RunConfig
from fem_py.mesh import DomainSize

__all__ = [
    "equation_size",
    "PLOT_PROCESS_BYTES",
    "PLOT_DOF_BYTES",
    "PROCESS_BYTES",
    "DOF_BYTES",
    "BOUNDARY_BYTES",
    "HMATRIX_BOUNDARY_BYTES",
    "DOF_BYTES_3D",
    "BOUNDARY_BYTES_3D",
    "HMATRIX_BOUNDARY_BYTES_3D",
    "SIGNORINI_BYTES_3D",
    "DOF_BYTES_ELASTIC",
    "DOF_BYTES_ELASTIC_3D",
    "BOUNDARY_BYTES_ELASTIC",
    "BOUNDARY_BYTES_ELASTIC_3D",
    "HMATRIX_BOUNDARY_BYTES_ELASTIC",
    "HMATRIX_BOUNDARY_BYTES_ELASTIC_3D",
    "SIGNORINI_BYTES_ELASTIC",
    "SIGNORINI_BYTES_ELASTIC_3D",
    "MemoryConstants",
    "memory_constants",
    "memory_estimate",
    "memory_available",
    "check_memory",
    "size_of_domain",
]

#: The process itself: the libraries imported (dolfinx, PETSc, bem_cpp; no sympy with a
#: built-in material) and the small runs' arrays: 134 MB measured for a 1,089-dof square
#: without figures, 2026-12-06 (200 MB while every run imported sympy; docs/design/memory.md)
PROCESS_BYTES = 135e6
DOF_BYTES = 1.05e3  # fitted to the H-matrix runs at 1e6, 4e6 and 1.6e7 dofs
BOUNDARY_BYTES = 5 * 8.0
#: The H-matrix S_h operator and the estimator's V, K per boundary dof: 86 MB at n =
#: 16,000 (circle) and 23 MB at 8,000, rounded up (docs/design/hmatrix.md)
HMATRIX_BOUNDARY_BYTES = 8e3
PLOT_PROCESS_BYTES = 40e6
PLOT_DOF_BYTES = 0.02e3
DOF_BYTES_3D = 3e3
BOUNDARY_BYTES_3D = 8 * 8.0
HMATRIX_BOUNDARY_BYTES_3D = 20e3
SIGNORINI_BYTES_3D = 4.0 + 8.0


#: The constants of the elastic equation (``[problem] equation = "elasticity"``), per
#: unknown (d per node), per boundary unknown n (d per node of Gamma) and per gap unknown
#: n_s; fitted to whole `fembem solve` runs of bench/elastic.py's square and box with
#: figures and XDMF (docs/design/memory.md, "Elasticity (2026-12-07)", which lists the
#: runs). The plane: 1,150 B per unknown (the square at 526,338 .. 2,101,250 dofs with the
#: H-matrix S_h: 1.09-1.10 KB measured, rounded up); the dense Lame operators five
#: (2 n_v)^2 arrays as Laplace's (the dense S_h asked for at 132,098 and 526,338 dofs:
#: 1.04, 1.06x); the H-matrix S_h and M_s are below 3% of any peak measured (n <= 8,192,
#: n_s <= 2,046): the scalar 8 KB and the body's 16 B, not fitted.
DOF_BYTES_ELASTIC = 1.15e3
BOUNDARY_BYTES_ELASTIC = 5 * 8.0
HMATRIX_BOUNDARY_BYTES_ELASTIC = 8e3
SIGNORINI_BYTES_ELASTIC = 16.0
#: The body: 2.5 KB per unknown and 50 KB per boundary unknown (the Lame H-matrix S_h, its
#: blocks in single precision), least squares over the box's one-rank H-matrix runs from
#: 20^3 to 48^3 cubes after the 48^3 cuts (bench/elastic_memory.json: 2.3 KB and 48.5 KB),
#: rounded up; the two share S_h (its bytes per boundary unknown grow with n): refit both
#: together (bench/elastic_memory.py --fit) when S_h changes. The dense Lame operators nine
#: (3 n_v)^2 arrays, 72 n^2 bytes (the box at 12^3 .. 20^3 cubes, dense); M_s = E^T W_h E
#: and M_s^{-1} (or a factor), 16 n_s^2 bytes on every rank (not fitted; 12 with M_s in
#: single precision, the H-matrix runs: 0.5 GB of the 48^3 run's 3.8 GB).
DOF_BYTES_ELASTIC_3D = 2.5e3
BOUNDARY_BYTES_ELASTIC_3D = 9 * 8.0
HMATRIX_BOUNDARY_BYTES_ELASTIC_3D = 50e3
SIGNORINI_BYTES_ELASTIC_3D = 16.0


@dataclasses.dataclass(frozen=True)
class MemoryConstants:
    """The fitted bytes of one equation on one kind of domain: per dof, per n^2 (the dense
    boundary matrices), per boundary dof n (the H-matrix S_h) and per n_s^2 (the dense M_s
    of the amg preconditioner; 0 where the model has none)."""

    dof: float
    dense_boundary: float
    hmatrix_boundary: float
    signorini: float


def memory_constants(components: int, dim: int) -> MemoryConstants:
    """The constants of the scalar equation (``components`` 1) or of elasticity (d) in
    ``dim`` dimensions (read from the module's names at each call: they can be updated)."""
    if components == 1 and dim == 2:
        return MemoryConstants(DOF_BYTES, BOUNDARY_BYTES, HMATRIX_BOUNDARY_BYTES, 0.0)
    if components == 1:
        return MemoryConstants(
            DOF_BYTES_3D, BOUNDARY_BYTES_3D, HMATRIX_BOUNDARY_BYTES_3D, SIGNORINI_BYTES_3D
        )
    if dim == 2:
        return MemoryConstants(
            DOF_BYTES_ELASTIC,
            BOUNDARY_BYTES_ELASTIC,
            HMATRIX_BOUNDARY_BYTES_ELASTIC,
            SIGNORINI_BYTES_ELASTIC,
        )
    return MemoryConstants(
        DOF_BYTES_ELASTIC_3D,
        BOUNDARY_BYTES_ELASTIC_3D,
        HMATRIX_BOUNDARY_BYTES_ELASTIC_3D,
        SIGNORINI_BYTES_ELASTIC_3D,
    )


def memory_estimate(
    size: DomainSize, ranks: int = 1, *, plots: bool = True, boundary_operator: str = "auto"
) -> int:
    """Bytes of peak resident memory of a solve of ``size`` on ``ranks`` ranks (all ranks
    together), with or without the plots, for ``[solver] boundary_operator``; ``size`` the
    counts of the equation (:func:`equation_size`: ``size.components`` unknowns per node)."""
    c = memory_constants(size.components, size.dim)
    per_rank = PROCESS_BYTES + (PLOT_PROCESS_BYTES if plots else 0.0)
    per_dof = c.dof + (PLOT_DOF_BYTES if plots else 0.0)
    n = float(size.boundary_dofs)
    # "auto" decides on the boundary nodes, with the crossover of the equation's kernel
    kernel = "laplace" if size.components == 1 else "lame"
    nodes = size.boundary_dofs // size.components
    if boundary_operator_kind(boundary_operator, nodes, size.dim, kernel=kernel) == "hmatrix":
        boundary = c.hmatrix_boundary * n
    else:
        boundary = c.dense_boundary * n**2
    # the dense M_s of the amg preconditioner, on every rank
    boundary += ranks * c.signorini * float(size.signorini_dofs) ** 2
    return int(ranks * per_rank + per_dof * size.dofs + boundary)


def memory_available() -> int:
    """Bytes the kernel says new processes can use without swapping (MemAvailable), or the
    process's address-space limit (``ulimit -v``) if that is lower."""
    import resource

    with open("/proc/meminfo") as meminfo:
        for line in meminfo:
            if line.startswith("MemAvailable:"):
                available = int(line.split()[1]) * 1024
                break
        else:
            raise OSError("MemAvailable not found in /proc/meminfo")
    limit = resource.getrlimit(resource.RLIMIT_AS)[0]
    return available if limit == resource.RLIM_INFINITY else min(available, int(limit))


def _gb(n: float) -> str:
    return f"{n / 1e9:.3g} GB"


def equation_size(size: DomainSize, config: RunConfig) -> DomainSize:
    """The unknowns of ``config``'s equation on a domain of ``size`` (P1 node counts): the
    same for the scalar equation; for elasticity d per node, and d gap unknowns per
    Signorini node with ``"slip"`` (the normal gap and the slips), one with ``"stick"``;
    ``size.components`` = d (counts that are already the equation's are returned as
    they are)."""
    if config.problem.equation == "scalar" or size.components > 1:
        return size
    d = size.dim
    gaps = d if config.problem.tangential == "slip" else 1
    return dataclasses.replace(
        size,
        components=d,
        dofs=d * size.dofs,
        boundary_dofs=d * size.boundary_dofs,
        signorini_dofs=gaps * size.signorini_dofs,
    )


def check_memory(
    size: DomainSize, ranks: int, *, plots: bool, boundary_operator: str = "auto"
) -> None:
    """Refuse a run whose estimate exceeds the memory available (one-line ValueError)."""
    need = memory_estimate(size, ranks, plots=plots, boundary_operator=boundary_operator)
    have = memory_available()
    if need > have:
        raise ValueError(
            f"the run needs about {_gb(need)} of memory ({size.dofs:.3g} dofs, "
            f"{size.boundary_dofs:.3g} on Gamma) but {_gb(have)} are available; increase "
            "geometry.h (fewer dofs) or run on a machine with more memory"
        )


def size_of_domain(domain: Any) -> DomainSize:
    """The sizes of a built domain (collective): the P1 counts, L (0 in 3D: no coarse
    partition), and the shortest and longest fine facet (edge in 3D)."""
    from fem_py.boundary import boundary_map
    from fem_py.dofs import p1_space
    from fem_py.mesh import shortest_facet

    V = p1_space(domain.mesh)
    boundary = boundary_map(V, domain)
    solid = domain.dim == 3
    return DomainSize(
        dofs=V.dofmap.index_map.size_global,
        boundary_dofs=boundary.n_gamma,
        signorini_dofs=boundary.n_signorini,
        subdomains=0 if solid else domain.coarse.n_subdomains,
        h_min=domain.h_min if solid else shortest_facet(domain),
        h_max=domain.h_max,
        dim=domain.dim,
    )
