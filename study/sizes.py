"""Problem sizes of the study's parts: the full study and ``--quick``."""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Sizes", "FULL", "QUICK", "WIDTH", "REFERENCE_KAPPA"]

WIDTH = 0.5  # width of the manufactured square and L-shape (coupling.manufactured)

#: kappa of (A, B) measured on the structured reference implementation of docs/method.md
#: section 6 (square of width 0.5, P0 flux, omega = 1), keyed by (cells, d/h). These
#: are the published inputs the ``spectrum`` part recomputes, not measurements of ours.
REFERENCE_KAPPA = {
    (16, 4): 38.9,
    (32, 4): 40.3,
    (64, 4): 41.0,
    (128, 4): 41.6,
    (16, 8): 44.6,
    (32, 8): 52.1,
    (64, 8): 53.8,
    (128, 8): 54.3,
    (64, 16): 67.3,
    (128, 32): 85.3,
}


@dataclass(frozen=True)
class Sizes:
    """Problem sizes of every part (cells = cells per side of the bounding square,
    h = 0.5 / cells; fixed d means d = 0.5 / ``d_subdomains``, 4 subdomains per side)."""

    ratio_series: tuple[tuple[int, tuple[int, ...]], ...]  # iterations: (d/h, cells) at fixed d/h
    d_cells: tuple[int, ...]  # iterations and spectrum: cells at fixed d
    identity_cells: tuple[int, ...]  # iterations with B = identity (count ~ h^-2)
    exact_cells: tuple[int, ...]  # iterations with the exact block preconditioner
    spectrum_cells: tuple[int, ...]  # eigenvalues at fixed d/h = 4
    spectrum_d_cells: tuple[int, ...]  # eigenvalues at fixed d
    cond_cells: tuple[int, ...]  # cond(M_s), both series
    reference: tuple[tuple[int, int], ...]  # (cells, d/h) of the docs/method.md reference kappa
    projection_cells: tuple[int, ...]  # the exact projection runs at all of them
    projection_configs: tuple[tuple[float, int, int], ...]  # inexact: (rho_in, cap, up to cells)
    oracle_rho: tuple[tuple[float, int], ...]  # (3.20) stopped by (3.6) with the true q*:
    #                                            (rho_in, up to cells)
    error_cells: tuple[int, ...]
    edge_cells: tuple[int, ...]  # edge forms at fixed d/h = 4
    edge_d_cells: tuple[int, ...]  # edge forms at fixed d
    edge_kappa_max_cells: int  # kappa of the edge-form runs up to this size
    jacobian_cells: tuple[int, ...]
    adapt_max_dofs: int  # adaptivity: the largest level (first mesh h = 1/16, d = 1/8)
    d_subdomains: int = 4
    spectrum_ratio: int = 4


FULL = Sizes(
    ratio_series=((4, (32, 64, 128, 256, 512)), (8, (32, 64, 128, 256))),
    d_cells=(16, 32, 64, 128, 256, 512),
    identity_cells=(4, 8, 16),
    exact_cells=(16, 32, 64, 128),
    spectrum_cells=(16, 32, 64, 128, 256),
    spectrum_d_cells=(16, 32, 64, 128, 256),
    cond_cells=(16, 32, 64, 128, 256, 512),
    reference=tuple(REFERENCE_KAPPA),
    projection_cells=(32, 64, 128, 256),
    projection_configs=(
        (0.1, 1000, 128),
        (0.5, 1000, 128),
        (0.9, 1000, 256),
        (0.5, 1, 128),
        (0.5, 3, 128),
        (0.5, 10, 128),
    ),
    oracle_rho=((0.1, 128), (0.5, 256), (0.9, 256)),
    error_cells=(8, 16, 32, 64, 128, 256),
    edge_cells=(32, 64, 128, 256),
    edge_d_cells=(16, 32, 64, 128),
    edge_kappa_max_cells=128,
    jacobian_cells=(64, 256),
    adapt_max_dofs=40000,
)

QUICK = Sizes(
    ratio_series=((4, (8, 16, 32, 64)),),
    d_cells=(16, 32, 64),
    identity_cells=(4, 8),
    exact_cells=(8, 16, 32),
    spectrum_cells=(8, 16, 32),
    spectrum_d_cells=(16, 32, 64),
    cond_cells=(8, 16, 32, 64),
    reference=((16, 4), (32, 4)),
    projection_cells=(16, 32),
    projection_configs=((0.5, 1000, 32), (0.5, 3, 32)),
    oracle_rho=((0.5, 32),),
    error_cells=(8, 16, 32),
    edge_cells=(16, 32),
    edge_d_cells=(16, 32),
    edge_kappa_max_cells=32,
    jacobian_cells=(16,),
    adapt_max_dofs=1500,
)
