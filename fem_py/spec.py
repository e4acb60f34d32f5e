"""What Omega to build: :class:`GeometrySpec`, the one input of ``fem_py.mesh.build_domain``
and ``fem_py.mesh.domain_size`` (and the ``[geometry]`` section of a run configuration,
whose defaults are the field defaults here).

The spec is a plain record: ``build_domain`` checks its values (identically on every
rank, before any collective call) and raises one-line errors naming the field. Omega's
dimension ``dim`` is derived from the shape (every shape and mesh file is planar so
far); ``fem_py.mesh.build`` dispatches on it.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["GeometrySpec", "DIMENSIONS"]

#: The dimensions of Omega that ``fem_py.mesh.build_domain`` builds.
DIMENSIONS = (2,)


@dataclass(frozen=True)
class GeometrySpec:
    """Omega, its mesh and its coarse partition into subdomains (docs/method.md sections 1, 6).

    Attributes
    ----------
    shape
        ``"square"`` (``center``, ``width``), ``"lshape"`` (``center``, ``width``: the
        square of that width minus its upper-right quarter), ``"polygon"``
        (``vertices``, counter-clockwise), ``"disk"`` (``center``, ``radius``) or
        ``"ellipse"`` (``center``, ``semi_axes`` (a, b)). Ignored when ``mesh`` is given.
    center, width, vertices, radius, semi_axes
        The shape's parameters (the others are ignored; ``vertices`` only with
        ``"polygon"``).
    h
        Fine mesh size (structured: h = coarse edge / round(d/h)).
    subdomain_size
        Coarse size d >= 2h.
    structured
        Square, L-shape, polygon: uniform refinement of the coarse cells instead of an
        unstructured gmsh mesh.
    signorini
        The Signorini arcs: point pairs on Gamma (counter-clockwise from the first to
        the second), side names, or ``"all"``; with ``mesh``, names of physical curve
        groups. () for none (``fem_py.mesh.polygon``).
    allow_large
        Allow diam(Omega) >= 1 (then V is not guaranteed elliptic, docs/method.md section 2).
    mesh
        A gmsh mesh file (MSH 2.2 or 4.1, linear triangles) instead of a generated shape.
    subdomains
        With ``mesh``: ``"auto"`` (the automatic partition of size ``subdomain_size``) or
        ``"physical"`` (the physical surface groups).
    dim
        The dimension of Omega (2).
    """

    shape: str = "square"
    center: Any = (0.0, 0.0)
    width: float = 0.5
    vertices: Any = ()
    h: float = 1.0 / 32
    subdomain_size: float = 1.0 / 8
    structured: bool = True
    signorini: Any = ()
    allow_large: bool = False
    mesh: str = ""
    subdomains: str = "auto"
    radius: float = 0.25
    semi_axes: Any = (0.3, 0.2)
    dim: int = 2

    def __post_init__(self) -> None:
        if self.dim not in DIMENSIONS:
            raise ValueError(
                f"dim: Omega of dimension {self.dim!r} is not built (dimensions {DIMENSIONS})"
            )
