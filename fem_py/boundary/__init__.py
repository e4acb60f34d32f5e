"""The boundary map of docs/method.md section 4: the boundary nodes in counter-clockwise order
(``order``: the walk of the exterior facets on rank 0) and the trace T, the extension E
and the boundary data on them (``map``)."""
from fem_py.boundary.map import BoundaryMap

__all__ = ["BoundaryMap"]
