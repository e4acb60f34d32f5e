"""The ``[geometry]`` arguments of 3D bodies checked once: a point, positive sizes and
the Signorini names, each refused in one line naming its key."""
from __future__ import annotations

from typing import Any, Mapping

import numpy as np

__all__ = ["checked_point", "checked_positive", "signorini_tags"]


def checked_point(center: Any, key: str = "center") -> np.ndarray:
    """``center`` as a (3,) array of finite numbers; else a one-line ``ValueError``."""
    try:
        c = np.asarray([float(v) for v in center], dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{key} must be a point [x, y, z], got {center!r}") from None
    if c.shape != (3,) or not np.all(np.isfinite(c)):
        raise ValueError(f"{key} must be a point [x, y, z] of finite numbers, got {center!r}")
    return c


def checked_positive(key: str, value: Any) -> float:
    """``value`` as a finite number > 0; else a one-line ``ValueError`` naming ``key``."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{key} must be a positive number, got {value!r}") from None
    if not (np.isfinite(v) and v > 0):
        raise ValueError(f"{key} must be a positive number, got {value!r}")
    return v


def signorini_tags(signorini: Any, names: Mapping[str, int]) -> tuple[int, ...] | str:
    """The facet tags of the Signorini names (faces of a built-in shape, or groups of a
    file: ``names`` from ``box_mesh``, ``ball_mesh`` or ``solid_mesh``), or ``"all"``;
    the argument of ``fem_py.boundary.surface.SurfaceMap``.

    Raises
    ------
    ValueError
        A name not in ``names``, or ``"all"`` among other names.
    """
    items = [signorini] if isinstance(signorini, (str, int)) else list(signorini)
    keys = [str(item) for item in items]
    if "all" in keys:
        if len(keys) != 1:
            raise ValueError("signorini: 'all' (the whole surface) cannot be combined with names")
        return "all"
    unknown = [k for k in keys if k not in names]
    if unknown:
        raise ValueError(
            f"signorini: unknown face or group {unknown[0]!r}; use one of "
            f"{', '.join(names)} or 'all'"
        )
    return tuple(sorted({int(names[k]) for k in keys}))
