"""The PNG bytes of a run's figures: one resolution and one encoding for every kind of
figure (:mod:`coupling.io.figures`, :mod:`coupling.io.body_figures`,
:mod:`coupling.io.elastic_figures`)."""
from __future__ import annotations

import io
from typing import Any, Callable, Collection, Iterable

import matplotlib

matplotlib.use("Agg")  # before anything of pyplot is imported: no display
import matplotlib.pyplot as plt  # noqa: E402

__all__ = ["DPI", "PNG", "draw_pngs"]

#: The resolution of the figures.
DPI = 110
#: PNG encoding: zlib level 1 (the same pixels as the default 6 in half the time, files
#: ~25% larger; docs/design/speed.md, "Outputs (helper, 2026-12-02)").
PNG = {"compress_level": 1}


def draw_pngs(
    figures: dict[str, Callable[[], Any]],
    names: Iterable[str],
    skip: Collection[str] = (),
    bbox: Callable[[str, Any], Any] = lambda name, fig: "tight",
) -> dict[str, bytes]:
    """{name: PNG bytes} of the figures ``figures[name]()`` built at :data:`DPI`, for the
    ``names`` in their order but those in ``skip``; a builder may return None (no such
    figure for this run). ``bbox(name, fig)``: the ``bbox_inches`` to save it with."""
    pngs = {}
    for name in (n for n in names if n not in skip):
        with plt.rc_context({"figure.dpi": DPI}):
            fig = figures[name]()
        if fig is None:
            continue
        buffer = io.BytesIO()
        fig.savefig(buffer, dpi=DPI, bbox_inches=bbox(name, fig), format="png", pil_kwargs=PNG)
        plt.close(fig)
        pngs[name] = buffer.getvalue()
    return pngs
