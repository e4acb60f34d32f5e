"""Omega meshed and distributed with its coarse partition: the :class:`Domain` built from a
:class:`GeometrySpec` (``build``: the square, the L-shape and polygons in ``polygon``, the
disk and the ellipse in ``conic``, users' mesh files in ``own_mesh``; in 3D the
:class:`SolidDomain` of the box, the ball and tetrahedral files in ``solid``; the pieces:
``shapes``, ``structured``, ``gmsh_mesh``, ``distribute``), its local refinement
and the split of the subdomains it grades (``refinement``, ``grading``), point location
(``location``) and the facts a user checks (``facts``)."""
from fem_py.mesh.build import build_domain, domain_size, spec_dimension
from fem_py.mesh.conic import CONICS
from fem_py.mesh.domain import (
    CORNER_ANGLE,
    Domain,
    DomainSize,
    domain_from_mesh,
    domain_from_prepared,
)
from fem_py.mesh.facts import mesh_facts, shortest_facet, subdomain_diameters
from fem_py.mesh.grading import split_cells, split_graded_subdomains, subdomain_grading
from fem_py.mesh.location import interpolate_p1, locate
from fem_py.mesh.refinement import boundary_transfer, locate_cells, refine_domain, transfer_p1
from fem_py.mesh.shapes import SHAPES, Arc
from fem_py.mesh.solid import SolidDomain
from fem_py.spec import GeometrySpec

__all__ = [
    "Arc",
    "CONICS",
    "CORNER_ANGLE",
    "Domain",
    "DomainSize",
    "GeometrySpec",
    "SHAPES",
    "SolidDomain",
    "boundary_transfer",
    "build_domain",
    "domain_from_mesh",
    "domain_from_prepared",
    "domain_size",
    "interpolate_p1",
    "locate",
    "locate_cells",
    "mesh_facts",
    "refine_domain",
    "shortest_facet",
    "spec_dimension",
    "split_cells",
    "split_graded_subdomains",
    "subdomain_grading",
    "subdomain_diameters",
    "transfer_p1",
]
