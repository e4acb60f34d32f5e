"""What Omega to build: :class:`GeometrySpec`, the one input of ``fem_py.mesh.build_domain``
and ``fem_py.mesh.domain_size`` (and the ``[geometry]`` section of a run configuration,
whose defaults are the field defaults here).

The spec is a plain record: ``build_domain`` checks its values (identically on every
rank, before any collective call) and raises one-line errors naming the field. Omega's
dimension ``dim`` is derived from the shape (``"box"`` and ``"ball"`` are bodies in R^3,
the other shapes planar) or, for a mesh file, read from the file when the domain is built
(``fem_py.mesh.build.spec_dimension``); ``fem_py.mesh.build`` dispatches on it.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["GeometrySpec", "DIMENSIONS", "SOLID_SHAPES", "PLANAR_ONLY"]

#: The dimensions of Omega that ``fem_py.mesh.build_domain`` builds.
DIMENSIONS = (2, 3)
#: The shapes of a body in R^3 (docs/method.md section 11); every other shape is planar.
SOLID_SHAPES = ("box", "ball")
#: The fields that mean nothing for a body in R^3 (no polygon, no ellipse, no coarse
#: partition into subdomains, no diameter condition on V), with what to do instead.
PLANAR_ONLY = {
    "vertices": "a polygon is planar",
    "semi_axes": "an ellipse is planar",
    "subdomain_size": "a 3D body has no coarse partition",
    "subdomains": "a 3D body has no coarse partition",
    "structured": "the box is structured and the ball is meshed by gmsh",
    "allow_large": "in 3D V is elliptic for every body",
}


@dataclass(frozen=True)
class GeometrySpec:
    """Omega, its mesh and its coarse partition into subdomains (docs/method.md sections 1, 6).

    Attributes
    ----------
    shape
        ``"square"`` (``center``, ``width``), ``"lshape"`` (``center``, ``width``: the
        square of that width minus its upper-right quarter), ``"polygon"``
        (``vertices``, counter-clockwise), ``"disk"`` (``center``, ``radius``) or
        ``"ellipse"`` (``center``, ``semi_axes`` (a, b)); in 3D ``"box"`` (``center``
        [x, y, z], ``width``: round(width/h) cubes per side, six tetrahedra each) or
        ``"ball"`` (``center`` [x, y, z], ``radius``). Ignored when ``mesh`` is given.
    center, width, vertices, radius, semi_axes
        The shape's parameters (the others are ignored; ``vertices`` only with
        ``"polygon"``). The default center (0, 0) is (0, 0, 0) for a 3D shape.
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
        groups. () for none (``fem_py.mesh.polygon``). In 3D: face names of the box or
        the ball, names of physical surface groups of a mesh file, or ``"all"``.
    allow_large
        Allow diam(Omega) >= 1 (then V is not guaranteed elliptic, docs/method.md section 2).
    mesh
        A gmsh mesh file (MSH 2.2 or 4.1, linear triangles or linear tetrahedra) instead
        of a generated shape.
    subdomains
        With ``mesh``: ``"auto"`` (the automatic partition of size ``subdomain_size``) or
        ``"physical"`` (the physical surface groups).
    dim
        The dimension of Omega: derived from the shape (left 0, or given equal); with
        ``mesh``, 0 (read from the file when built) or the file's dimension.
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
    dim: int = 0

    def __post_init__(self) -> None:
        if self.dim not in (0, *DIMENSIONS):
            raise ValueError(
                f"dim: Omega of dimension {self.dim!r} is not built (dimensions {DIMENSIONS})"
            )
        if self.mesh:
            return  # the file tells (fem_py.mesh.build.spec_dimension)
        dim = 3 if self.shape in SOLID_SHAPES else 2
        if self.dim not in (0, dim):
            raise ValueError(f"dim: shape {self.shape!r} is {dim}D, not {self.dim}D")
        object.__setattr__(self, "dim", dim)
        if dim == 3:
            self._check_solid_fields()

    def _check_solid_fields(self) -> None:
        """A 3D shape: the default center becomes (0, 0, 0); planar fields refused."""
        if tuple(self.center) == GeometrySpec.center:
            object.__setattr__(self, "center", (0.0, 0.0, 0.0))
        if self.vertices:
            raise ValueError(
                f"vertices: {PLANAR_ONLY['vertices']}; drop vertices for shape {self.shape!r}"
            )
        signorini = () if self.signorini == "all" else self.signorini
        items = [signorini] if isinstance(signorini, str) else list(signorini)
        if any(not isinstance(item, (str, int)) for item in items):
            raise ValueError(
                f"signorini: shape {self.shape!r} takes face names or 'all', not coordinate "
                "arcs (arcs are planar)"
            )
