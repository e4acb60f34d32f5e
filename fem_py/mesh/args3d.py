"""The arguments of the built-in 3D shapes checked once: a point and positive sizes,
each refused in one line naming its ``[geometry]`` key."""
from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["checked_point", "checked_positive"]


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
