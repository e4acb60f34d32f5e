"""The boundary map of docs/method.md section 4: the boundary nodes in counter-clockwise order
(``order``: the walk of the exterior facets on rank 0) and the trace T, the extension E
and the boundary data on them (``map``); in 3D the oriented surface triangulation
(``surface``); the map of a domain of either dimension (``of_domain``)."""
from fem_py.boundary.map import BoundaryMap
from fem_py.boundary.of_domain import boundary_map
from fem_py.boundary.surface import SurfaceMap

__all__ = ["BoundaryMap", "SurfaceMap", "boundary_map"]
