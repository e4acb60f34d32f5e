"""PNG figures of a solved problem (matplotlib, Agg backend), written on rank 0."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.path import Path as PolygonPath  # noqa: E402
from matplotlib.tri import Triangulation  # noqa: E402

import bem_cpp  # noqa: E402

__all__ = ["write_plots", "arc_length"]


def arc_length(nodes: np.ndarray) -> np.ndarray:
    """Arc length s at each boundary node (s = 0 at the first node)."""
    seg = np.linalg.norm(np.diff(nodes, axis=0), axis=1)
    return np.concatenate([[0.0], np.cumsum(seg)])


def _save(fig, path: Path, atomic_write) -> None:
    atomic_write(path, lambda p: fig.savefig(p, dpi=130, bbox_inches="tight", format="png"))
    plt.close(fig)


def _mark_contact(ax, fields: dict) -> None:
    nodes = fields["boundary_x"]
    closed = np.vstack([nodes, nodes[:1]])
    ax.plot(closed[:, 0], closed[:, 1], "k-", lw=0.8)
    s_nodes = nodes[fields["signorini"]]
    active = fields["active"]
    ax.plot(*s_nodes[~active].T, "o", ms=2.5, color="tab:blue", label="Signorini: gap > 0")
    ax.plot(*s_nodes[active].T, "o", ms=2.5, color="tab:red", label="Signorini: contact")
    if len(s_nodes):
        ax.legend(loc="upper right", fontsize=7)


def write_plots(out: Path, problem, result, fields: dict, atomic_write) -> None:
    """u over Omega, boundary quantities, the whole-plane picture and the history."""
    tri = Triangulation(fields["x"][:, 0], fields["x"][:, 1], fields["triangles"])

    fig, ax = plt.subplots(figsize=(5.5, 4.5))
    im = ax.tripcolor(tri, fields["u"], shading="gouraud", cmap="viridis")
    fig.colorbar(im, ax=ax, label="u_h")
    _mark_contact(ax, fields)
    ax.set_aspect("equal")
    ax.set_title("u_h in Omega; Signorini nodes marked")
    _save(fig, out / "u.png", atomic_write)

    nodes = fields["boundary_x"]
    s = arc_length(np.vstack([nodes, nodes[:1]]))
    fig, axes = plt.subplots(3, 1, figsize=(7, 6.5), sharex=True)
    gap = np.zeros(len(nodes))
    gap[fields["signorini"]] = fields["phi"]
    axes[0].plot(s[:-1], gap, ".-", ms=2)
    axes[0].set_ylabel("gap phi_h")
    flux = fields["dn_ue"]
    s_flux = s[:-1] if flux.size == len(nodes) and str(fields["flux_space"]) == "p1" \
        else 0.5 * (s[:-1] + s[1:])
    axes[1].plot(s_flux, flux, ".-", ms=2, color="tab:green")
    axes[1].set_ylabel("du_e/dn")
    contact = np.zeros(len(nodes))
    contact[fields["signorini"][fields["active"]]] = 1
    axes[2].step(s[:-1], contact, where="mid", color="tab:red")
    axes[2].set_ylabel("contact")
    axes[2].set_xlabel("arc length along Gamma (counter-clockwise)")
    fig.suptitle("Boundary quantities")
    _save(fig, out / "boundary.png", atomic_write)

    lo, hi = nodes.min(axis=0), nodes.max(axis=0)
    centre, half = 0.5 * (lo + hi), 1.0 * (hi - lo).max()
    g = np.linspace(-1, 1, 121) * half
    X, Y = np.meshgrid(centre[0] + g, centre[1] + g)
    points = np.column_stack([X.ravel(), Y.ravel()])
    outside = ~PolygonPath(nodes).contains_points(points, radius=-1e-9)
    # Keep a margin of about one panel so the picture shows u_e, not quadrature noise.
    h = np.linalg.norm(np.diff(np.vstack([nodes, nodes[:1]]), axis=0), axis=1).max()
    dist = np.min(np.linalg.norm(points[:, None, :] - nodes[None, ::max(1, len(nodes) // 400)],
                                 axis=2), axis=1)
    outside &= dist > h
    ue = np.full(points.shape[0], np.nan)
    ue[outside] = bem_cpp.exterior_potential(nodes, fields["ue"], flux, points[outside],
                                             a=float(fields["a"]),
                                             flux=str(fields["flux_space"]))
    vmin = np.nanmin([np.nanmin(ue), fields["u"].min()])
    vmax = np.nanmax([np.nanmax(ue), fields["u"].max()])
    fig, ax = plt.subplots(figsize=(6, 5))
    ax.pcolormesh(X, Y, ue.reshape(X.shape), shading="auto", cmap="viridis", vmin=vmin,
                  vmax=vmax)
    im = ax.tripcolor(tri, fields["u"], shading="gouraud", cmap="viridis", vmin=vmin,
                      vmax=vmax)
    fig.colorbar(im, ax=ax, label="u_h inside, u_e outside")
    _mark_contact(ax, fields)
    ax.set_aspect("equal")
    ax.set_title("Whole plane: u_h in Omega, u_e (representation formula) outside")
    _save(fig, out / "whole_plane.png", atomic_write)

    history = result.history
    if history:
        it = np.array([r.iteration for r in history])
        energy = np.array([r.energy for r in history])
        step = np.array([r.step_norm for r in history])
        fig, ax = plt.subplots(figsize=(6, 4))
        ax.semilogy(it, step, label="||xi_k+1 - xi_k||_B / ||xi_k+1||_B")
        excess = energy - energy.min()
        keep = excess > 0
        ax.semilogy(it[keep], excess[keep] / max(abs(energy.min()), 1e-300),
                    label="(J_h - min J_h) / |min J_h|")
        ax.set_xlabel("PGPM iteration")
        ax.legend()
        ax.set_title("Convergence history")
        _save(fig, out / "history.png", atomic_write)
