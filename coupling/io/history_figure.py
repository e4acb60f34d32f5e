"""history.png of a run, planar or not: the relative B-norm step and the relative energy
excess of each iteration against the tolerance, and the size of the contact set; for a
run over several levels (nested, or adaptive: ``level_iterations`` in the history) those
of the final level, and the iterations of every level with their total beneath."""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402

__all__ = ["figure_history"]


def figure_history(history: dict, tol: float):
    it, energy = history["iteration"], history["energy"]
    step, contact = history["step_norm"], history["contact"]
    counts = history.get("level_iterations", np.zeros(0))
    several = len(counts) >= 2
    ratios = [3, 1.3, 1.6] if several else [3, 1.3]
    fig, axes = plt.subplots(
        len(ratios), 1, figsize=(6.5, 8.0 if several else 5.5), height_ratios=ratios
    )
    ax, contact_ax = axes[0], axes[1]
    contact_ax.sharex(ax)
    style = ".-" if len(it) <= 60 else "-"  # points while they can be told apart
    ax.semilogy(
        it, step, style, label=r"$\Vert\xi_{k+1} - \xi_k\Vert_B \,/\, \Vert\xi_{k+1}\Vert_B$"
    )
    best = energy.min(initial=np.inf)  # J* below: the lowest energy reached
    keep = energy > best
    if keep.any():  # a curve (and its legend entry) only where J_h is above J*
        ax.semilogy(
            it[keep],
            (energy[keep] - best) / max(abs(best), 1e-300),
            style if keep.sum() > 1 else ".",
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
    ax.tick_params(labelbottom=False)
    title = f"Convergence ({len(it)} iterations)"
    if several:
        kind = str(history.get("level_kind", "nested"))
        title = (
            f"Convergence on the final level ({len(it)} iterations);\n"
            f"{int(counts.sum())} iterations in all over {len(counts)} {kind} levels"
        )
    ax.set_title(title)
    contact_ax.step(it, contact, where="post", color="tab:red")
    if len(contact):  # at least two integers in the range, so the ticks can be integers
        contact_ax.set_ylim(max(contact.min() - 1.0, -0.5), contact.max() + 1.0)
    contact_ax.set(xlabel="iteration $k$" + (" (final level)" if several else ""))
    contact_ax.set_ylabel("contact nodes")
    contact_ax.grid(alpha=0.3, lw=0.5)
    for axis in (contact_ax.xaxis, contact_ax.yaxis):  # counts: no fractional ticks
        axis.set_major_locator(MaxNLocator(integer=True))
    if several:
        _levels(axes[2], history["level_dofs"], counts)
    fig.tight_layout()
    return fig


def _levels(ax, dofs: np.ndarray, counts: np.ndarray) -> None:
    """The iterations of each level as bars, labelled with its dofs."""
    k = np.arange(len(counts))
    bars = ax.bar(k, counts, color="tab:blue", width=0.6)
    ax.bar_label(bars, labels=[f"{int(c)}" for c in counts], fontsize=8)
    ax.set_xticks(k, [f"{int(n):,}" for n in dofs], fontsize=8)
    ax.set(xlabel="level (dofs)", ylabel="iterations")
    ax.set_ylim(0, 1.2 * max(float(counts.max()), 1.0))
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.grid(alpha=0.3, lw=0.5, axis="y")
