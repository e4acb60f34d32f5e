"""The Signorini block omega B_s of B (docs/method.md section 6, "Signorini block"): its arcs
and its matrix M_s, with M_s^{-1} = (A^0_s)^{-1} + P_s C_s^{-1} P_s^T.

On each Signorini arc the same two-level structure as on the skeleton, one level up:
edge forms on the coarse edges of the arc for phi_e, and the discrete H^{1/2}_00
formula (5.1) on the coarse vertices of the arc (arc-length weights) for phi_v; for a
closed arc, distances along the curve and d * sum phi(v)^2 instead of the end-point
term (our extension). It is "factorised" exactly by the same edge inverses and one
small dense Cholesky factor of C_s.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from coupling.preconditioners.base import check_length, largest_eigenvalue
from coupling.preconditioners.edge_forms import EDGE_FORMS, closed_paper_form, paper_edge_form
from coupling.preconditioners.kernels import TwoLevelForm, block_diagonal_edge_forms
from fem_py.polyline import arc_length

__all__ = ["SignoriniArc", "SignoriniBlock", "signorini_form", "signorini_arcs"]


@dataclass(frozen=True, eq=False)
class SignoriniArc:
    """One Signorini arc of Gamma_s, as the preconditioner needs it.

    Attributes
    ----------
    coords : (m+1, 2) array
        Fine boundary nodes along the arc in counter-clockwise order, both end points
        included. For a closed arc (the whole boundary): the m nodes once, not repeated.
    coarse_vertex_mask : (m+1,) bool array
        Which of those nodes are coarse vertices; the two end points of an open arc
        always are (docs/method.md section 6 requires the arc ends to be coarse vertices).
    unknowns : int array
        For each node carrying a phi unknown, its index in the phi vector (length n_s):
        the m-1 interior nodes of an open arc, all m nodes of a closed arc, in order.
    closed : bool
        True when the arc is a whole closed boundary curve (no end points).
    """

    coords: np.ndarray
    coarse_vertex_mask: np.ndarray
    unknowns: np.ndarray
    closed: bool = False

    def __post_init__(self) -> None:
        coords = np.asarray(self.coords, dtype=float)
        mask = np.asarray(self.coarse_vertex_mask, dtype=bool)
        unknowns = np.asarray(self.unknowns, dtype=np.int64)
        if coords.ndim != 2 or coords.shape[1] != 2:
            raise ValueError(f"SignoriniArc.coords must have shape (k, 2), got {coords.shape}")
        k = coords.shape[0]
        if mask.shape != (k,):
            raise ValueError(
                f"SignoriniArc.coarse_vertex_mask must have shape ({k},), one flag per node, got "
                f"{mask.shape}"
            )
        expected = k if self.closed else k - 2
        if unknowns.shape != (expected,):
            raise ValueError(
                f"SignoriniArc.unknowns must have {expected} entries "
                f"({'all nodes of a closed arc' if self.closed else 'the interior nodes'}), got "
                f"{unknowns.shape}"
            )
        if self.closed:
            if not mask.any():
                raise ValueError(
                    "a closed SignoriniArc needs at least one coarse vertex in coarse_vertex_mask"
                )
        elif k < 2 or not (mask[0] and mask[-1]):
            raise ValueError(
                "the two end points of an open SignoriniArc must be coarse vertices (mask[0] and "
                "mask[-1] True)"
            )
        object.__setattr__(self, "coords", coords)
        object.__setattr__(self, "coarse_vertex_mask", mask)
        object.__setattr__(self, "unknowns", unknowns)


def signorini_form(arcs: Sequence[SignoriniArc], subdomain_size: float, kind: str) -> TwoLevelForm:
    """M_s of docs/method.md section 6 ("Signorini block") as a two-level form on the phi unknowns.

    On each arc: edge forms A^0_gamma on the coarse edges of the arc (phi_e), and the
    formula (5.1) one level up on the coarse vertices (arc-length positions, so uneven
    coarse edges get arc-length weights); for a closed arc the distances are taken
    along the curve and the end-point term is d * sum phi(v)^2. Arcs do not couple.
    """
    n_s = sum(len(arc.unknowns) for arc in arcs)
    every = np.concatenate([arc.unknowns for arc in arcs]) if arcs else np.zeros(0, np.int64)
    if not np.array_equal(np.sort(every), np.arange(n_s)):
        raise ValueError(
            f"the unknowns of the Signorini arcs must number the phi vector 0..{n_s - 1}, each once"
        )
    groups = []
    rows, cols, vals = [], [], []
    coarse_nodes, coarse_blocks = [], []
    n_c = 0
    for arc in arcs:
        if arc.closed:
            # start at a coarse vertex and repeat it at the end: a chain of coarse edges
            k = arc.coords.shape[0]
            order = (np.arange(k + 1) + np.argmax(arc.coarse_vertex_mask)) % k
            pts, phi_index = arc.coords[order], arc.unknowns[order]
            corners = np.flatnonzero(arc.coarse_vertex_mask[order])  # includes 0 and k
            c_pos = corners[:-1]
        else:
            pts = arc.coords
            phi_index = np.concatenate([[-1], arc.unknowns, [-1]])  # the end points carry no phi
            corners = np.flatnonzero(arc.coarse_vertex_mask)
            c_pos = corners[1:-1]
        s = arc_length(pts)
        c_index = np.full(len(pts), -1, dtype=np.int64)
        c_index[c_pos] = n_c + np.arange(len(c_pos))
        if arc.closed:
            c_index[-1] = c_index[0]
            coarse_blocks.append(closed_paper_form(s[c_pos], s[-1], subdomain_size))
        else:
            coarse_blocks.append(paper_edge_form(s[corners]) if len(c_pos) else np.zeros((0, 0)))
        coarse_nodes.append(phi_index[c_pos])
        rows.append(phi_index[c_pos])
        cols.append(c_index[c_pos])
        vals.append(np.ones(len(c_pos)))
        n_c += len(c_pos)
        for a, b in zip(corners[:-1], corners[1:]):
            inner = np.arange(a + 1, b)
            groups.append((phi_index[inner][None, :], pts[a : b + 1][None]))
            t = (s[inner] - s[a]) / (s[b] - s[a])
            for end, weight in ((a, 1.0 - t), (b, t)):
                if c_index[end] >= 0:
                    rows.append(phi_index[inner])
                    cols.append(np.full(len(inner), c_index[end]))
                    vals.append(weight)
    interp = sp.csr_matrix(
        (_concat(vals, float), (_concat(rows, np.int64), _concat(cols, np.int64))), shape=(n_s, n_c)
    )
    a0, a0_inv = block_diagonal_edge_forms(groups, n_s, kind)
    coarse = sla.block_diag(*coarse_blocks) if coarse_blocks else np.zeros((0, 0))
    return TwoLevelForm(a0, a0_inv, interp, _concat(coarse_nodes, np.int64), coarse)


def _concat(parts: list[np.ndarray], dtype: type) -> np.ndarray:
    return np.concatenate(parts).astype(dtype) if parts else np.zeros(0, dtype=dtype)


class SignoriniBlock:
    """omega B_s of docs/method.md section 6 ("Signorini block"): the Signorini half of B.

    Small (one unknown per Signorini node) and replicated on every rank; shared by the
    serial and the distributed substructuring preconditioners.
    """

    def _init_signorini(
        self, arcs: Sequence[SignoriniArc], subdomain_size: float, kind: str, weight: float
    ) -> None:
        """Check the options shared by B_Omega and B_s, and build omega M_s."""
        if kind not in EDGE_FORMS:
            raise ValueError(f"edge_form must be one of {EDGE_FORMS}, got {kind!r}")
        if not subdomain_size > 0.0:
            raise ValueError(f"subdomain_size must be positive, got {subdomain_size}")
        if not weight > 0.0:
            raise ValueError(f"signorini_weight must be positive, got {weight}")
        self.edge_form, self.subdomain_size = kind, float(subdomain_size)
        self.signorini_weight = float(weight)
        self._signorini = signorini_form(tuple(arcs), subdomain_size, kind)
        self.n_signorini = self._signorini.n
        self._lambda_max: float | None = None

    def apply_signorini(self, g: np.ndarray) -> np.ndarray:
        """phi = (omega M_s)^{-1} g with M_s^{-1} = (A^0_s)^{-1} + P_s C_s^{-1} P_s^T (exact)."""
        return self._signorini.solve(check_length(g, self.n_signorini, "g")) / self.signorini_weight

    def matvec_signorini(self, phi: np.ndarray) -> np.ndarray:
        """omega M_s phi, the matrix of omega B_s (docs/method.md section 6)."""
        return self.signorini_weight * self._signorini.matvec(
            check_length(phi, self.n_signorini, "phi")
        )

    @property
    def signorini_metric(self) -> np.ndarray:
        """omega M_s as a dense n_s x n_s array (the metric of the projection (3.19)-(3.20))."""
        return self.signorini_weight * self._signorini.matrix.toarray()

    @property
    def lambda_max_signorini(self) -> float:
        """Largest eigenvalue of omega M_s (0 without Signorini unknowns); bounds theta in "
        "(3.20)."""
        if self._lambda_max is None:  # of M_s, computed on first use
            m = self._signorini.matrix
            self._lambda_max = largest_eigenvalue(m) if m.shape[0] else 0.0
        return self.signorini_weight * self._lambda_max


def signorini_arcs(
    boundary: Any, coarse_vertex_dofs: np.ndarray, transmission_tag: int
) -> list[SignoriniArc]:
    """The Signorini arcs of a problem in the form of the preconditioner.

    Parameters
    ----------
    boundary
        ``fem_py.boundary.BoundaryMap``: boundary nodes in counter-clockwise order, their
        dofs, the facet tag of every panel and the positions of the phi unknowns.
    coarse_vertex_dofs
        Dofs of the coarse vertices (``fem_py.partition.coarse.CoarseStructure.vertex_dofs``).
    transmission_tag
        The facet tag of Gamma_t (every other tag is one Signorini arc).

    Returns
    -------
    list of SignoriniArc
        For each arc the nodes along it (counter-clockwise, ends included), the
        coarse-vertex flags and the phi indices; one closed arc for Gamma_s = Gamma.
    """
    b = boundary
    n = b.n_gamma
    phi_index = np.full(n, -1)
    phi_index[b.signorini] = np.arange(b.signorini.size)
    is_vertex = np.isin(b.dofs, coarse_vertex_dofs)
    arcs = []
    for tag in np.unique(b.panel_tags[b.panel_tags != transmission_tag]):
        panels = b.panel_tags == tag
        if panels.all():
            arcs.append(SignoriniArc(b.nodes, is_vertex, phi_index, closed=True))
            continue
        # the arc starts at the panel whose predecessor is not on it
        first = np.flatnonzero(panels & ~np.roll(panels, 1))
        if first.size != 1:
            raise ValueError(
                f"Signorini arc with facet tag {tag} is not one connected "
                "arc of the boundary; give each arc separately"
            )
        length = int(panels.sum())
        nodes = (first[0] + np.arange(length + 1)) % n
        arcs.append(SignoriniArc(b.nodes[nodes], is_vertex[nodes], phi_index[nodes[1:-1]]))
    return arcs
