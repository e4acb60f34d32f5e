"""The facet tags of a domain's boundary: Gamma_t and the Signorini arcs (docs/method.md
section 1). Every exterior facet of a ``fem_py.mesh.Domain`` carries one of them."""
from __future__ import annotations

__all__ = ["GAMMA_T_TAG", "SIGNORINI_TAG0"]

#: Facet tag of Gamma_t (the exterior facets outside every Signorini arc).
GAMMA_T_TAG = 1
#: Facet tag of the first Signorini arc (arc k has tag SIGNORINI_TAG0 + k).
SIGNORINI_TAG0 = 100
