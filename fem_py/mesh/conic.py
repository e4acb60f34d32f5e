"""The disk and the ellipse: generated curved Omegas (``shape = "disk"`` with ``radius``,
``shape = "ellipse"`` with ``semi_axes = (a, b)``, both with ``center``).

Both are the ellipse x = cx + a cos t, y = cy + b sin t (a = b = radius for the disk), t
the parameter angle (it increases counter-clockwise with the polar angle). :func:`conic_arcs`
checks the Signorini arcs (point pairs on the curve, from the first to the second
counter-clockwise, or ``"all"``) and returns them as parameter pairs; :func:`conic_mesh`
meshes Omega with gmsh at size h (call it on one rank: circle arcs for the disk, ellipse
arcs otherwise, each piece below pi, the arc ends as mesh nodes) and returns it with one
physical curve group per arc (``arc<k>``), ready for ``fem_py.mesh.own_mesh.prepare_mesh`` and
the automatic partition into subdomains; :func:`conic_domain` builds the domain of
both shapes (``fem_py.mesh.build_domain``).
"""
from __future__ import annotations

import dataclasses
import math
from typing import Any, Sequence

import numpy as np

from fem_py.mesh.domain import domain_from_prepared
from fem_py.mesh.gmsh_mesh import gmsh_session
from fem_py.mesh.own_mesh import mesh_of_model, prepare_mesh
from fem_py.mesh.shapes import checked_center
from fem_py.spec import GeometrySpec

__all__ = ["CONICS", "conic_axes", "conic_arcs", "conic_mesh", "conic_plan", "conic_domain"]

#: The shapes of this module.
CONICS = ("disk", "ellipse")

_TOL = 1e-8


def _curve(center: tuple[float, float], axes: tuple[float, float]) -> str:
    """The curve as messages call it."""
    a, b = axes
    about = f"about ({center[0]:g}, {center[1]:g})"
    if a == b:
        return f"circle of radius {a:g} {about}"
    return f"ellipse of semi-axes ({a:g}, {b:g}) {about}"


def conic_arcs(signorini: Any, center: tuple[float, float], axes: tuple[float, float]) -> Any:
    """The arcs as (start, end) parameter angles in [0, 2 pi) (end after start CCW), or
    ``"all"``; ``axes`` = (a, b), the semi-axes along x and y. Raises a one-line
    ``ValueError`` naming ``signorini``."""
    if isinstance(signorini, str):
        if signorini == "all":
            return "all"
        signorini = [signorini]
    items = list(signorini)
    if items == ["all"]:
        return "all"
    curve = _curve(center, axes)
    out = []
    for k, a in enumerate(items):
        try:
            pts = np.asarray(a, dtype=float)
        except (TypeError, ValueError):
            pts = np.zeros(0)
        if pts.shape != (2, 2) or not np.all(np.isfinite(pts)):
            raise ValueError(
                f"signorini arc {k}: the {curve.split()[0]} takes arcs [[x0, y0], [x1, y1]] "
                f"(points on the curve) or 'all', got {a!r}"
            )
        rel = (pts - np.asarray(center)) / np.asarray(axes)  # on the unit circle
        r = np.linalg.norm(rel, axis=1)
        if np.any(np.abs(r - 1.0) > 1e-6):
            i = int(np.argmax(np.abs(r - 1.0)))
            raise ValueError(
                f"signorini arc {k}: point ({pts[i, 0]:g}, {pts[i, 1]:g}) is not on the {curve}"
            )
        t0, t1 = (float(np.arctan2(q[1], q[0]) % (2 * math.pi)) for q in rel)
        if abs(t1 - t0) < _TOL:
            raise ValueError(f"signorini arc {k}: its end equals its start; use 'all'")
        out.append((t0, t1))
    for i in range(len(out)):
        for j in range(i + 1, len(out)):
            if _overlap(out[i], out[j]):
                raise ValueError(
                    f"signorini arcs {i} and {j} overlap; arcs may only touch at end points"
                )
    return out


def _span(a: tuple[float, float]) -> float:
    return (a[1] - a[0]) % (2 * math.pi)


def _inside(t: float, a: tuple[float, float]) -> bool:
    r = (t - a[0]) % (2 * math.pi)
    return _TOL < r < _span(a) - _TOL


def _overlap(a, b) -> bool:
    mid_a, mid_b = a[0] + 0.5 * _span(a), b[0] + 0.5 * _span(b)
    return (
        _inside(b[0], a)
        or _inside(a[0], b)
        or _inside(mid_a, b)
        or _inside(mid_b, a)
        or abs(((a[0] - b[0] + math.pi) % (2 * math.pi)) - math.pi) < _TOL
    )


def conic_mesh(center: tuple[float, float], axes: tuple[float, float], h: float, arcs: Any) -> Any:
    """The ellipse of semi-axes ``axes`` (a circle when they are equal) meshed at size h by
    gmsh (one session) as a ``fem_py.mesh.own_mesh.MeshFile`` with the curve groups ``arc0``,
    ``arc1``, ... (``arcs`` from :func:`conic_arcs`; with ``"all"`` the group ``all``)."""
    cuts = set()
    if arcs != "all":
        cuts = {t for a in arcs for t in a}
    cuts = sorted(cuts) or [0.0]
    (cx, cy), (a, b) = center, axes
    if a != b:
        cuts = _quadrant_cuts(cuts, 0.5 * h / max(a, b))
    # keep every piece below pi (gmsh's circle and ellipse arcs): add points half way
    full = []
    for i, t in enumerate(cuts):
        nxt = cuts[(i + 1) % len(cuts)] + (2 * math.pi if i + 1 == len(cuts) else 0.0)
        span = nxt - t
        pieces = max(1, math.ceil(span / (0.6 * math.pi)))
        full.extend(t + span * j / pieces for j in range(pieces))
    ends = full[1:] + [full[0] + 2 * math.pi]
    mids = [0.5 * (t0 + t1) for t0, t1 in zip(full, ends)]  # of the pieces
    with gmsh_session() as gmsh:
        gmsh.model.add("fembem_conic")
        geo = gmsh.model.geo
        c = geo.addPoint(cx, cy, 0.0, h)
        pts = [geo.addPoint(cx + a * math.cos(t), cy + b * math.sin(t), 0.0, h) for t in full]
        major = None  # circle arcs; else a point on the major axis (inside, off the nodes)
        if a != b:
            major = geo.addPoint(cx + 0.5 * a * (a > b), cy + 0.5 * b * (b > a), 0.0, h)
        lines = [_piece(geo, pts[i], c, major, pts[(i + 1) % len(pts)]) for i in range(len(pts))]
        surf = geo.addPlaneSurface([geo.addCurveLoop(lines)])
        geo.synchronize()
        gmsh.model.addPhysicalGroup(2, [surf], 1)
        if arcs == "all":
            gmsh.model.setPhysicalName(1, gmsh.model.addPhysicalGroup(1, lines, 100), "all")
        else:
            for k, arc in enumerate(arcs):
                mine = [line for line, t in zip(lines, mids) if _inside(t, arc)]
                group = gmsh.model.addPhysicalGroup(1, mine, 100 + k)
                gmsh.model.setPhysicalName(1, group, f"arc{k}")
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
        gmsh.model.mesh.generate(2)
        return mesh_of_model("the disk" if a == b else "the ellipse")


def _quadrant_cuts(cuts: list[float], delta: float) -> list[float]:
    """``cuts`` (sorted parameter angles) and the ellipse's vertices t = k pi/2 as piece
    ends: gmsh's ellipse arc through two mirror images (t0 + t1 = 0 mod pi) is undetermined,
    and pieces inside one quadrant are not. A vertex closer than ``delta`` to a cut on one
    side is left out (no facet much shorter than h) unless a cut lies within 2 delta on
    its other side; the piece across it is then far from symmetric."""
    out = list(cuts)
    for k in range(4):
        off = [(c - k * math.pi / 2 + math.pi) % (2 * math.pi) - math.pi for c in cuts]
        near = [o for o in off if abs(o) < 2 * delta]
        if any(abs(o) < _TOL for o in near):
            continue  # a cut already
        close = [o for o in near if abs(o) < delta]
        if close and all(o * close[0] > 0 for o in near):
            continue
        out.append(k * math.pi / 2)
    return sorted(t % (2 * math.pi) for t in out)


def _piece(geo: Any, start: int, center: int, major: int | None, end: int) -> int:
    """A gmsh geo arc (below pi) from ``start`` to ``end``: of a circle when ``major`` is
    None, else of the ellipse with that major axis point."""
    if major is None:
        return geo.addCircleArc(start, center, end)
    return geo.addEllipseArc(start, center, major, end)


def _positive(name: str, val: Any) -> float:
    if (
        isinstance(val, bool)
        or not isinstance(val, (int, float))
        or not val > 0
        or not (math.isfinite(val))
    ):
        raise ValueError(f"{name} must be a positive number, got {val!r}")
    return float(val)


def conic_axes(shape: str, radius: float, semi_axes: Sequence[float] | None) -> tuple:
    """The semi-axes (a, b) of ``shape``: (radius, radius) for the disk, ``semi_axes``
    for the ellipse (two positive numbers). Raises a one-line ``ValueError`` naming the
    argument."""
    if shape == "disk":
        r = _positive("radius", radius)
        return r, r
    if semi_axes is None:
        raise ValueError("semi_axes: the ellipse needs its semi-axes [a, b] (a along x, b along y)")
    try:
        a, b = semi_axes
    except (TypeError, ValueError):
        raise ValueError(
            f"semi_axes must be a pair [a, b] (a along x, b along y), got {semi_axes!r}"
        ) from None
    return _positive("semi_axes a", a), _positive("semi_axes b", b)


def conic_plan(spec: GeometrySpec) -> tuple:
    """Checks of a disk or an ellipse (identical on every rank, no communication): (h, d,
    center, semi-axes (a, b), arcs of :func:`conic_arcs`)."""
    shape = spec.shape
    h, d = _positive("h", spec.h), _positive("subdomain_size", spec.subdomain_size)
    axes = conic_axes(shape, spec.radius, spec.semi_axes)
    if d < 2 * h:
        raise ValueError(
            f"subdomain_size d={d:g} is smaller than 2h={2 * h:g}; increase "
            "subdomain_size or decrease h"
        )
    cx, cy = checked_center(spec.center)
    diam = 2 * max(axes)
    if diam >= 1.0 and not spec.allow_large:
        what = "the radius" if shape == "disk" else "semi_axes"
        raise ValueError(
            f"diam(Omega) = {diam:.4g} >= 1: the single-layer operator may not be "
            f"elliptic (docs/method.md section 2); shrink {what}, or opt out with "
            "allow_large (geometry.allow_large = true) at your own risk"
        )
    return h, d, (cx, cy), axes, conic_arcs(spec.signorini, (cx, cy), axes)


def conic_domain(comm: Any, spec: GeometrySpec) -> Any:
    """The domain of the disk or the ellipse of ``spec`` (collective): gmsh on rank 0,
    then as a mesh file (``fem_py.mesh.domain.domain_from_prepared``)."""
    h, d, c, axes, arcs = conic_plan(spec)
    names = "all" if arcs == "all" else [f"arc{k}" for k in range(len(arcs))]
    domain = domain_from_prepared(
        comm,
        lambda: prepare_mesh(
            conic_mesh(c, axes, h, arcs), signorini=names, subdomain_size=d, allow_large=True
        ),
        d,
        spec.shape,
    )
    return dataclasses.replace(domain, h=h)
