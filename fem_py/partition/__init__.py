"""Subdomains: the automatic partition of a triangle mesh into subdomains of size d
(``cells``) and the coarse structure the substructuring preconditioner needs (coarse
vertices and edges as chains of fine dofs: ``coarse``, ``chains``, stored as ``ragged``
arrays). Importing it does not
load DOLFINx (``coarse`` loads it in ``compute_coarse_structure``), so the preconditioners
use :class:`Ragged` without it."""
from fem_py.partition.cells import cell_adjacency, part_diameters, partition_cells
from fem_py.partition.coarse import CoarseStructure, compute_coarse_structure
from fem_py.partition.ragged import Ragged, as_ragged

__all__ = [
    "CoarseStructure",
    "Ragged",
    "as_ragged",
    "cell_adjacency",
    "compute_coarse_structure",
    "part_diameters",
    "partition_cells",
]
