"""history.png of a run, planar or not: the relative B-norm step and the relative energy
excess of each iteration against the tolerance, and the size of the contact set."""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

__all__ = ["figure_history"]


def figure_history(history: dict, tol: float):
    it, energy = history["iteration"], history["energy"]
    step, contact = history["step_norm"], history["contact"]
    fig, axes = plt.subplots(
        2, 1, figsize=(6.5, 5.5), sharex=True, gridspec_kw=dict(height_ratios=[3, 1.3])
    )
    ax = axes[0]
    ax.semilogy(it, step, label=r"$\Vert\xi_{k+1} - \xi_k\Vert_B \,/\, \Vert\xi_{k+1}\Vert_B$")
    best = energy.min()  # J* below: the lowest energy reached
    keep = energy > best
    ax.semilogy(
        it[keep],
        (energy[keep] - best) / max(abs(best), 1e-300),
        label=r"$(J_h(\xi_k) - J^*) \,/\, |J^*|$,  $J^*$: lowest $J_h$ reached",
    )
    stop = history.get("stop", np.zeros(0))
    if len(stop) and len(it):  # the stopping rule tested the PGPM step from the last iterate
        ax.semilogy(
            it[-1:],
            stop,
            "v",
            color="k",
            label=r"stopping test: $\Vert$PGPM step at $\xi_k\Vert_B \,/\, \Vert\xi_k\Vert_B$",
        )
    ax.axhline(tol, color="0.4", ls="--", lw=0.8, label=f"tol = {tol:g}")
    ax.set_ylabel("relative size")
    ax.grid(alpha=0.3, lw=0.5, which="both")
    ax.legend(fontsize=8)
    ax.set_title(f"Convergence ({len(it)} iterations)")
    axes[1].step(it, contact, where="post", color="tab:red")
    axes[1].set(xlabel="iteration $k$", ylabel="contact nodes")
    axes[1].grid(alpha=0.3, lw=0.5)
    fig.tight_layout()
    return fig
