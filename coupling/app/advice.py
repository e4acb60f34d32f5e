"""Warnings about inputs that are valid but likely not what the user wants.

Pure functions returning the warning lines; the command line prints them on stderr.
"""
from __future__ import annotations

from typing import Any, Sequence

__all__ = ["material_warnings", "arc_warnings", "ALPHA_MIN", "CONDITION_MAX"]

#: alpha below this, or beta/alpha above CONDITION_MAX, gets a warning
ALPHA_MIN = 1e-6
CONDITION_MAX = 1e3


def material_warnings(material: Any) -> list[str]:
    """A small alpha or a large beta/alpha (docs/method.md section 1): the constants of the
    structure condition alpha (t - s) <= t rho(t) - s rho(s) <= beta (t - s) bound the
    condition of the interior energy, so the iteration counts grow with beta/alpha."""
    alpha, beta = material.alpha, material.beta
    out = []
    if alpha < ALPHA_MIN:
        out.append(
            f"material: alpha = {alpha:.3g} < {ALPHA_MIN:g}: the interior energy is "
            "nearly degenerate, so the discrete problem is ill-conditioned and the "
            "solvers may stall"
        )
    elif beta / alpha > CONDITION_MAX:
        out.append(
            f"material: beta/alpha = {beta / alpha:.3g} > {CONDITION_MAX:g}: the "
            "condition of the interior energy grows with beta/alpha, and so do the "
            "iteration counts"
        )
    return out


def arc_warnings(
    arc_lengths: Sequence[float], closed: Sequence[bool], gamma_length: float
) -> list[str]:
    """An open Signorini arc longer than half of Gamma is often one given from the wrong
    end (an arc runs counter-clockwise from its first point to its second). ``closed``:
    the arcs whose ends the user did not choose (the whole boundary, a side or a group
    named), which get no warning."""
    out = []
    for i, (length, whole) in enumerate(zip(arc_lengths, closed)):
        if not whole and length > 0.5 * gamma_length:
            out.append(
                f"geometry.signorini[{i}]: the arc covers {length / gamma_length:.0%} "
                "of Gamma; an arc runs counter-clockwise from its first point to its "
                "second: swap them if you meant the other part"
            )
    return out
