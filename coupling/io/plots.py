"""The PNG figures of a run (:data:`PLOT_FILES`), from the arrays of fields.npz, written
on rank 0.

Every figure is drawn from the arrays of fields.npz (:mod:`coupling.io.outputs`) and the
iteration history alone, so it can be redrawn from the outputs of a finished run. The
data flow: :func:`exterior_samples` evaluates u_e on the whole-plane grid (bem_cpp),
:func:`figure_inputs` rasterises u_h on an image-sized grid
(:func:`coupling.io.figure_data.rasterise`) and collects what the figures need (a few MB
at any mesh size), :func:`coupling.io.figures.render` draws them to PNG bytes, in this
process or in the figure process (:mod:`coupling.io.figure_worker`), and
:func:`write_pngs` writes the files. :func:`write_plots` does all of it here.
"""
from __future__ import annotations

from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from coupling.io.atomic import atomic_write
from coupling.io.evaluation import ExteriorSamples, exterior_samples
from coupling.io.figure_data import PLOT_FILES, FigureInputs, PixelGrid, rasterise

__all__ = [
    "PLOT_FILES",
    "ExteriorSamples",
    "boundary_figure_inputs",
    "exterior_samples",
    "figure_inputs",
    "history_arrays",
    "write_pngs",
    "write_plots",
]

#: The boundary arrays of fields.npz that the figures draw.
_BOUNDARY_FIELDS = (
    "boundary_x",
    "phi",
    "pressure",
    "dn_ue",
    "flux_space",
    "signorini",
    "active",
    "ue",
)


def figure_inputs(
    fields: dict,
    history: Sequence,
    *,
    tol: float,
    exterior: ExteriorSamples | None = None,
    stop_measure: float | None = None,
    levels: Sequence[dict] | None = None,
    adaptive: bool = False,
) -> FigureInputs:
    """What the figures are drawn from: u_h of ``fields`` (``x``, ``triangles``, ``u``)
    rasterised on a grid of :data:`coupling.io.figure_data.RASTER_PIXELS` pixels along
    the longer side, the boundary arrays, the samples of u_e (``exterior``) and the
    iteration records of ``history`` (``iteration``, ``energy``, ``step_norm``,
    ``contact``) as arrays, with ``stop_measure`` (the quantity the stopping rule tested
    last, when not the last ``step_norm``: ``coupling.solvers.records.RunResult``) as
    ``stop``, and the ``levels`` of a run over several (:func:`history_arrays`). Without
    ``exterior`` there are no samples yet (None; to be set with ``_replace``): no
    whole_plane.png from these inputs."""
    x, u = fields["x"], fields["u"]
    grid = PixelGrid.covering(x.min(axis=0), x.max(axis=0))
    early = boundary_figure_inputs(
        fields, history, tol=tol, stop_measure=stop_measure, levels=levels, adaptive=adaptive
    )
    return early._replace(
        image=rasterise(x, fields["triangles"], u, grid),
        grid=grid,
        u_range=(float(u.min()), float(u.max())),
        exterior_points=None if exterior is None else exterior.points,
        exterior_ue=None if exterior is None else exterior.ue,
    )


def boundary_figure_inputs(
    boundary: dict,
    history: Sequence,
    *,
    tol: float,
    stop_measure: float | None = None,
    levels: Sequence[dict] | None = None,
    adaptive: bool = False,
) -> FigureInputs:
    """The inputs of the figures drawn from the boundary arrays (``boundary``: those of
    fields.npz) and the iteration records alone, boundary.png and history.png: no image of
    u_h and no samples of u_e yet. The figure process draws them while the run gathers and
    rasterises u_h (:class:`coupling.io.outputs.RunOutputs`)."""
    return FigureInputs(
        image=None,
        grid=None,
        u_range=None,
        boundary={k: boundary[k] for k in _BOUNDARY_FIELDS},
        exterior_points=None,
        exterior_ue=None,
        history=history_arrays(history, stop_measure, levels, adaptive),
        tol=float(tol),
    )


def history_arrays(
    history: Sequence,
    stop_measure: float | None = None,
    levels: Sequence[dict] | None = None,
    adaptive: bool = False,
) -> dict:
    """The iteration records of ``history`` (``iteration``, ``energy``, ``step_norm``,
    ``contact``) as arrays, with ``stop_measure`` as ``stop`` (history.png's data); of a
    run over several levels (``levels``: the records of summary.json's ``levels``, coarsest
    first, ``history`` the final level's) also each level's ``dofs`` and ``iterations``
    (``level_dofs``, ``level_iterations``) and whether they are ``adaptive`` or nested
    (``level_kind``)."""
    levels = levels or []
    return {
        key: np.array([getattr(r, key) for r in history], dtype=float)
        for key in ("iteration", "energy", "step_norm", "contact")
    } | {
        "stop": np.array([] if stop_measure is None else [stop_measure], dtype=float),
        "level_dofs": np.array([r["dofs"] for r in levels], dtype=float),
        "level_iterations": np.array([r["iterations"] for r in levels], dtype=float),
        "level_kind": np.array("adaptive" if adaptive else "nested"),
    }


def write_pngs(out: Path, pngs: dict[str, bytes]) -> list[str]:
    """Write the PNG files ``pngs`` ({name: bytes}) into ``out`` (each atomically);
    returns their names."""
    for name, data in pngs.items():
        atomic_write(Path(out) / name, lambda p, data=data: p.write_bytes(data))
    return list(pngs)


def write_plots(
    out: Path,
    fields: dict,
    history: Sequence,
    *,
    tol: float,
    exterior: Callable[[], ExteriorSamples] | None = None,
) -> list[str]:
    """Draw the figures of :data:`PLOT_FILES` in this process, write them into ``out``
    and return their names.

    Parameters
    ----------
    fields
        The arrays of fields.npz (:func:`coupling.io.outputs.write_outputs`).
    history
        The iteration records (``iteration``, ``energy``, ``step_norm``, ``contact``);
        no history.png when empty.
    tol
        The solver tolerance, drawn in history.png.
    exterior
        Returns the samples of u_e of whole_plane.png (:func:`exterior_samples` of
        ``fields``, e.g. computed meanwhile in a thread); default: computed here.
    """
    from coupling.io.figures import render

    samples = exterior() if exterior is not None else exterior_samples(fields)
    return write_pngs(out, render(figure_inputs(fields, history, tol=tol, exterior=samples)))
