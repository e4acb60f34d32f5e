"""The disk: a generated curved Omega (``shape = "disk"``, ``radius``, ``center``).

:func:`disk_arcs` checks the Signorini arcs (point pairs on the circle, from the first to
the second counter-clockwise, or ``"all"``); :func:`disk_mesh` meshes the disk with
gmsh at size h (call it on one rank), the arc ends as mesh nodes, and returns it with
one physical curve group per arc (``arc<k>``), ready for ``fem_py.own_mesh.prepare_mesh``
and the automatic partition into subdomains.
"""
from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

__all__ = ["disk_arcs", "disk_mesh", "disk_plan", "disk_domain"]

_TOL = 1e-8


def disk_arcs(signorini: Any, center: tuple[float, float], radius: float) -> Any:
    """The arcs as (start angle, end angle) pairs in [0, 2 pi) (end after start CCW), or
    ``"all"``. Raises a one-line ``ValueError`` naming ``signorini``."""
    if isinstance(signorini, str):
        if signorini == "all":
            return "all"
        signorini = [signorini]
    items = list(signorini)
    if items == ["all"]:
        return "all"
    out = []
    for k, a in enumerate(items):
        try:
            pts = np.asarray(a, dtype=float)
        except (TypeError, ValueError):
            pts = np.zeros(0)
        if pts.shape != (2, 2) or not np.all(np.isfinite(pts)):
            raise ValueError(
                f"signorini arc {k}: the disk takes arcs [[x0, y0], [x1, y1]] (points on "
                f"the circle) or 'all', got {a!r}"
            )
        rel = pts - np.asarray(center)
        r = np.linalg.norm(rel, axis=1)
        if np.any(np.abs(r - radius) > 1e-6 * radius):
            i = int(np.argmax(np.abs(r - radius)))
            raise ValueError(
                f"signorini arc {k}: point ({pts[i, 0]:g}, {pts[i, 1]:g}) is not on the "
                f"circle of radius {radius:g} about ({center[0]:g}, {center[1]:g})"
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


def disk_mesh(center: tuple[float, float], radius: float, h: float, arcs: Any) -> Any:
    """The disk meshed at size h by gmsh (one session) as a ``fem_py.own_mesh.MeshFile``
    with the curve groups ``arc0``, ``arc1``, ... (``arcs`` from :func:`disk_arcs`; with
    ``"all"`` the group ``all``)."""
    import gmsh

    from fem_py.own_mesh import mesh_of_model

    cuts = set()
    if arcs != "all":
        cuts = {t for a in arcs for t in a}
    cuts = sorted(cuts) or [0.0]
    # keep every circle piece below pi (gmsh's circle arcs): add points half way
    full = []
    for i, t in enumerate(cuts):
        nxt = cuts[(i + 1) % len(cuts)] + (2 * math.pi if i + 1 == len(cuts) else 0.0)
        span = nxt - t
        pieces = max(1, math.ceil(span / (0.6 * math.pi)))
        full.extend(t + span * j / pieces for j in range(pieces))
    ends = full[1:] + [full[0] + 2 * math.pi]
    mids = [0.5 * (t0 + t1) for t0, t1 in zip(full, ends)]  # of the circle pieces
    gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        gmsh.model.add("fembem_disk")
        geo = gmsh.model.geo
        cx, cy = center
        c = geo.addPoint(cx, cy, 0.0, h)
        pts = [
            geo.addPoint(cx + radius * math.cos(t), cy + radius * math.sin(t), 0.0, h) for t in full
        ]
        lines = [geo.addCircleArc(pts[i], c, pts[(i + 1) % len(pts)]) for i in range(len(pts))]
        surf = geo.addPlaneSurface([geo.addCurveLoop(lines)])
        geo.synchronize()
        gmsh.model.addPhysicalGroup(2, [surf], 1)
        if arcs == "all":
            gmsh.model.setPhysicalName(1, gmsh.model.addPhysicalGroup(1, lines, 100), "all")
        else:
            for k, a in enumerate(arcs):
                mine = [line for line, t in zip(lines, mids) if _inside(t, a)]
                group = gmsh.model.addPhysicalGroup(1, mine, 100 + k)
                gmsh.model.setPhysicalName(1, group, f"arc{k}")
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
        gmsh.model.mesh.generate(2)
        return mesh_of_model("the disk")
    finally:
        gmsh.finalize()


def _positive(name: str, val: Any) -> float:
    if (
        isinstance(val, bool)
        or not isinstance(val, (int, float))
        or not val > 0
        or not (math.isfinite(val))
    ):
        raise ValueError(f"{name} must be a positive number, got {val!r}")
    return float(val)


def disk_plan(h, subdomain_size, center, radius, signorini, allow_large) -> tuple:
    """Checks of a disk (identical on every rank, no communication): (h, d, center,
    radius, arcs of :func:`disk_arcs`)."""
    h, d, r = (
        _positive("h", h),
        _positive("subdomain_size", subdomain_size),
        _positive("radius", radius),
    )
    if d < 2 * h:
        raise ValueError(
            f"subdomain_size d={d:g} is smaller than 2h={2 * h:g}; increase "
            "subdomain_size or decrease h"
        )
    try:
        cx, cy = (float(c) for c in center)
    except (TypeError, ValueError):
        raise ValueError(f"center must be a pair (x, y), got {center!r}") from None
    if not (math.isfinite(cx) and math.isfinite(cy)):
        raise ValueError(f"center must be finite, got {center!r}")
    if 2 * r >= 1.0 and not allow_large:
        raise ValueError(
            f"diam(Omega) = {2 * r:.4g} >= 1: the single-layer operator may not be "
            "elliptic (METHOD.md section 2); shrink the radius, or opt out with "
            "allow_large (geometry.allow_large = true) at your own risk"
        )
    return h, d, (cx, cy), r, disk_arcs(signorini, (cx, cy), r)


def disk_domain(comm, h, subdomain_size, center, radius, signorini, allow_large) -> Any:
    """``fem_py.geometry.build_domain`` of the disk (collective): gmsh on rank 0, then
    as a mesh file (``fem_py.geometry.domain_from_prepared``)."""
    from fem_py.geometry import domain_from_prepared
    from fem_py.own_mesh import prepare_mesh

    h, d, c, r, arcs = disk_plan(h, subdomain_size, center, radius, signorini, allow_large)
    names = "all" if arcs == "all" else [f"arc{k}" for k in range(len(arcs))]
    domain = domain_from_prepared(
        comm,
        lambda: prepare_mesh(
            disk_mesh(c, r, h, arcs), signorini=names, subdomain_size=d, allow_large=True
        ),
        d,
        "disk",
    )
    return dataclasses.replace(domain, h=h)
