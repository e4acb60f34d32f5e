"""The boundary map of a domain, by its dimension: the 2D ``BoundaryMap`` of a planar
:class:`fem_py.mesh.Domain`, the 3D ``SurfaceMap`` of a :class:`fem_py.mesh.SolidDomain`
(docs/method.md sections 4 and 11); both give T, E, ``gather`` and ``scatter_add``."""
from __future__ import annotations

from typing import Any

from fem_py.boundary.map import BoundaryMap
from fem_py.boundary.surface import SurfaceMap

__all__ = ["boundary_map"]


def boundary_map(V: Any, domain: Any) -> BoundaryMap | SurfaceMap:
    """The boundary map of ``domain`` on its P1 space ``V`` (collective)."""
    if domain.dim == 3:
        return SurfaceMap(V, domain.facet_tags, domain.signorini, order=domain.node_order)
    return BoundaryMap(V, domain)
