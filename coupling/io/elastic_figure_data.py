"""What the figures of an elastic run are drawn from (:mod:`coupling.io.elastic_figures`).

From the arrays of fields.npz (:mod:`coupling.io.outputs`), the body's material and the
iteration history, on rank 0:

- :func:`elastic_inputs`: the deformed body, the displacement magnified by
  :func:`magnification` (the largest displacement about a tenth of the body's size),
  coloured by the von Mises stress of sigma(u_h) per cell
  (:func:`coupling.io.stress.von_mises`, from the P1 gradient and the material): in 2D
  rasterised on a :class:`PixelGrid` of the deformed body (a size independent of the
  mesh), in 3D on the surface triangles (the
  stress of the tetrahedron under each); the boundary arrays of signorini.png; the
  history arrays of history.png;
- :func:`exterior_section`: u_e and the von Mises stress of sigma(u_e) of the medium on
  the plane around the body (2D) or on a section (3D), by the representation formula
  with Kelvin's kernel,
  the body left blank (the costly part: direct sums, computed in a thread while the
  figure process draws the rest).

The module imports NumPy alone, so that the figure process unpickles its inputs without
MPI; :func:`exterior_section` imports bem_cpp and the point location of
:mod:`fem_py.mesh.location3d` (the run's side), :func:`surface_cells` scipy's k-d tree.
No matplotlib.
"""
from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from coupling.io.figure_data import PixelGrid, rasterise
from coupling.io.stress import cell_gradients, equivalent_stress, von_mises

__all__ = [
    "ELASTIC_PLOT_FILES",
    "ElasticFigureInputs",
    "elastic_inputs",
    "exterior_section",
    "exterior_von_mises",
    "magnification",
    "surface_cells",
]

#: The figures of an elastic run, in the order they are written.
ELASTIC_PLOT_FILES = ("deformed.png", "signorini.png", "exterior.png", "history.png")
#: The largest displacement drawn, as a share of the body's size (deformed.png).
DISPLACEMENT_SHARE = 0.1
#: Samples of u_e along each side of exterior.png's square (2D; direct sums of Kelvin's
#: kernel: points times panels) and at most along each side of its section (3D: points
#: times triangles).
EXTERIOR_SAMPLES_2D, EXTERIOR_SAMPLES_3D = 81, 49
#: The section's samples (3D) are fewer on a fine surface: at most this many sample-
#: triangle pairs (2 s measured at 49 x 49 samples and 3,072 triangles), but at least
#: 25 samples along a side (8 s at 64^3 cubes).
EXTERIOR_PAIRS_3D, EXTERIOR_SAMPLES_3D_MIN = 49 * 49 * 3072, 25
#: The boundary arrays that signorini.png draws.
_BOUNDARY_FIELDS = ("boundary_x", "boundary_u", "ue", "pressure", "phi", "active", "signorini")


class ElasticFigureInputs(NamedTuple):
    """The arrays of the figures of an elastic run (a few MB at any mesh size in 2D; a
    body's surface triangulation in 3D).

    ``dim`` is d; ``factor`` the magnification of the displacement in deformed.png;
    ``deformed`` what deformed.png draws (2D: ``image``, the von Mises stress rasterised
    on ``grid`` over the deformed body; 3D: ``corners`` (t, 3, 3) of the deformed
    surface triangles and ``stress`` (t,) per triangle; both: ``range``, the stress's
    (min, max) over the cells, and the ``largest`` |u_h| at a node); ``boundary`` the
    boundary arrays of fields.npz that signorini.png draws (``boundary_x``,
    ``boundary_u``, ``pressure`` = n.sigma n, ``phi`` = jump.n, ``active``,
    ``signorini``, the trace ``ue``; 3D also ``boundary_triangles``); ``exterior``
    exterior.png's |u_e| (:func:`exterior_section`; None: not computed yet, no
    exterior.png from these inputs); ``history`` and ``tol`` those of history.png.
    """

    dim: int
    factor: float
    deformed: dict
    boundary: dict
    exterior: dict | None
    history: dict
    tol: float


def exterior_von_mises(fields: dict, points: np.ndarray, kernel: Any) -> np.ndarray:
    """The von Mises stress (m,) of sigma(u_e), the medium's stress by the representation
    formula (``bem_cpp.exterior_stress``, Kelvin's kernel ``("lame", E, nu)``), at
    exterior ``points`` (m, d), from the boundary arrays of ``fields``; in 2D (plane
    strain) with sigma_zz = nu (sigma_xx + sigma_yy)."""
    import bem_cpp

    surface = fields.get("boundary_triangles")
    stress = bem_cpp.exterior_stress(
        fields["boundary_x"],
        fields["ue"],
        fields["dn_ue"],
        np.asarray(points, dtype=float),
        a=np.asarray(fields["a"], dtype=float),
        flux=str(fields["flux_space"]),
        kernel=kernel,
        **({} if surface is None else {"triangles": surface}),
    )
    d = stress.shape[-1]
    sigma = np.zeros((len(stress), 3, 3))
    sigma[:, :d, :d] = stress
    if d == 2:
        sigma[:, 2, 2] = float(kernel[2]) * (stress[:, 0, 0] + stress[:, 1, 1])
    return equivalent_stress(sigma)


def magnification(x: np.ndarray, u: np.ndarray, share: float = DISPLACEMENT_SHARE) -> float:
    """The factor the displacement ``u`` (N, d) is drawn magnified by: the number 1, 2 or 5
    times a power of ten nearest (logarithmically) to share * (the body's size, the
    longest side of its bounding box) / max |u|; 1 for u = 0."""
    largest = float(np.sqrt(np.einsum("ij,ij->i", u, u)).max(initial=0.0))
    size = float(np.ptp(x, axis=0).max())
    if not largest > 0.0 or not size > 0.0:
        return 1.0
    exact = np.log10(share * size / largest)
    decade = np.floor(exact)
    steps = np.log10([1.0, 2.0, 5.0, 10.0])
    return float(10.0 ** (decade + steps[np.argmin(np.abs(exact - decade - steps))]))


def surface_cells(
    x: np.ndarray, cells: np.ndarray, nodes: np.ndarray, triangles: np.ndarray
) -> np.ndarray:
    """The tetrahedron (row of ``cells``) under each surface triangle (t,): the boundary
    ``nodes`` (n, 3) matched to the mesh nodes ``x`` by a k-d tree, the triangles
    (``triangles`` (t, 3), rows of ``nodes``) to the faces of the tetrahedra with three
    boundary nodes."""
    from scipy.spatial import cKDTree

    index = cKDTree(x).query(nodes)[1]  # the mesh node of each boundary node
    on = np.zeros(len(x), bool)
    on[index] = True
    near = np.flatnonzero(on[cells].sum(axis=1) >= 3)
    faces = np.sort(
        np.concatenate([np.delete(cells[near], k, axis=1) for k in range(4)]), axis=1
    )  # face k of a tetrahedron leaves out its vertex k
    owner = np.tile(near, 4)
    keys = _row_keys(faces)
    order = np.argsort(keys, kind="stable")
    wanted = _row_keys(np.sort(index[triangles], axis=1))
    if len(keys) == 0:
        raise ValueError("no tetrahedron has a face on the surface")
    at = np.minimum(np.searchsorted(keys[order], wanted), len(keys) - 1)
    if np.any(keys[order][at] != wanted):
        raise ValueError("a surface triangle is no face of the mesh's tetrahedra")
    return owner[order][at]


def _row_keys(rows: np.ndarray) -> np.ndarray:
    """One comparable key per row of three node numbers (a structured view)."""
    rows = np.ascontiguousarray(rows, dtype=np.int64)
    return rows.view([("a", np.int64), ("b", np.int64), ("c", np.int64)]).ravel()


def elastic_inputs(
    fields: dict, material: Any, history: dict, *, tol: float
) -> ElasticFigureInputs:
    """The inputs of deformed.png, signorini.png and history.png (``exterior`` None: no
    exterior.png from them yet) from ``fields`` (the arrays of fields.npz: ``x``, ``u``,
    ``triangles`` or ``cells`` and the boundary arrays), the body's ``material`` and the
    history arrays (:func:`coupling.io.plots.history_arrays`)."""
    x, u = fields["x"], fields["u"]
    d = x.shape[1]
    factor = magnification(x, u)
    cells = fields["triangles"] if d == 2 else fields["cells"]
    boundary = {k: fields[k] for k in _BOUNDARY_FIELDS}
    if d == 2:
        stress = von_mises(cell_gradients(x, cells, u), material)
        moved = x + factor * u
        # the stress constant on each triangle: every triangle its own three nodes
        corners = moved[cells].reshape(-1, 2)
        lo = np.minimum(moved.min(axis=0), x.min(axis=0))
        hi = np.maximum(moved.max(axis=0), x.max(axis=0))
        grid = PixelGrid.covering(lo, hi)
        image = rasterise(
            corners, np.arange(len(corners)).reshape(-1, 3), np.repeat(stress, 3), grid
        )
        deformed = dict(image=image, grid=grid)
    else:
        triangles = fields["boundary_triangles"]
        boundary["boundary_triangles"] = triangles
        under = surface_cells(x, cells, fields["boundary_x"], triangles)
        stress = von_mises(cell_gradients(x, cells[under], u), material)
        moved = fields["boundary_x"] + factor * fields["boundary_u"]
        deformed = dict(corners=moved[triangles], stress=stress)
    deformed["largest"] = float(np.sqrt(np.einsum("ij,ij->i", u, u)).max(initial=0.0))
    deformed["range"] = (float(stress.min()), float(stress.max())) if len(stress) else (0.0, 0.0)
    return ElasticFigureInputs(d, factor, deformed, boundary, None, history, float(tol))


def exterior_section(fields: dict, kernel: Any, plane: str = "auto") -> dict:
    """|u_e| of the medium for exterior.png by the representation formula with the
    problem's ``kernel`` (Kelvin's, ``("lame", E, nu)``) from the boundary arrays of
    ``fields``: in 2D at the samples of :func:`coupling.io.evaluation.exterior_samples`
    (``points`` (m, 2), ``ue`` (m, 2)) on the square twice the body's box, the trace
    ``ue`` on Gamma beside them, and the von Mises stress of sigma(u_e) there (``stress``
    (m,), :func:`exterior_von_mises`); in 3D on the section by ``plane`` (``[output] slice``:
    ``"x = c"``, ``"y = c"``, ``"z = c"``, or ``"auto"``, the plane z = z_c through the
    middle of the body's box): the ``axis`` across it, its coordinate ``value``, the
    ``names`` of the two in-plane axes, ``ue`` (k, k, 3) at the pixel centres of
    ``extent``, NaN inside the body (``inside``) and next to a boundary node, the von
    Mises stress of sigma(u_e) on every other of those samples (``stress``, NaN where
    u_e is and closer to a boundary node than their spacing, on the pixels of
    ``stress_extent``, twice as large), and the section of
    Gamma, ``outline`` (m, 2, 2) in the plane's coordinates."""
    from coupling.io.evaluation import exterior_from_fields  # bem_cpp, the mesh libraries

    if fields["x"].shape[1] == 2:
        from coupling.io.evaluation import exterior_samples

        samples = exterior_samples(fields, EXTERIOR_SAMPLES_2D, kernel=kernel)
        stress = exterior_von_mises(fields, samples.points, kernel)
        return dict(points=samples.points, ue=samples.ue, stress=stress)
    from scipy.spatial import cKDTree

    from coupling.io.body_figure_data import plane_section
    from coupling.options import parse_slice
    from fem_py.mesh import interpolate_p1

    nodes = fields["boundary_x"]
    lo, hi = nodes.min(axis=0), nodes.max(axis=0)
    k, value = parse_slice(plane) or (2, float(0.5 * (lo[2] + hi[2])))
    i, j = (a for a in range(3) if a != k)
    centre = 0.5 * (lo + hi)
    half = 0.5 * float(max(hi[i] - lo[i], hi[j] - lo[j]))
    triangles = len(fields["boundary_triangles"])
    k_side = int(np.sqrt(EXTERIOR_PAIRS_3D / max(triangles, 1)))
    k_side = min(max(k_side, EXTERIOR_SAMPLES_3D_MIN), EXTERIOR_SAMPLES_3D)
    g = np.linspace(-2.0, 2.0, k_side) * half
    g = g + (g[1] - g[0]) / 3.0  # no sample on a face at a round coordinate
    X, Y = np.meshgrid(centre[i] + g, centre[j] + g)
    points = np.empty((X.size, 3))
    points[:, i], points[:, j], points[:, k] = X.ravel(), Y.ravel(), value
    inside = np.isfinite(
        interpolate_p1(fields["x"], fields["cells"], np.zeros(len(fields["x"])), points)
    )
    # samples within half a pixel of a boundary node are left out: the formula refuses a
    # point on Gamma, and a sample that close shows nothing the trace does not
    step = float(g[1] - g[0])
    distance = cKDTree(nodes).query(points)[0]  # to the nearest boundary node
    outside = ~inside & (distance > 0.5 * step)
    ue = np.full((len(points), 3), np.nan)
    if outside.any():
        ue[outside] = exterior_from_fields(fields, points[outside], kernel=kernel)
    # the stress on every other sample along each axis (its kernel costs about three
    # times the displacement's), farther from Gamma than their spacing: closer, the
    # data's error is amplified like h / distance (bem_cpp.exterior_stress)
    coarse = np.zeros(X.shape, bool)
    coarse[::2, ::2] = True
    coarse = coarse.ravel() & outside & (distance > 2.0 * step)
    stress = np.full(len(points), np.nan)
    if coarse.any():
        stress[coarse] = exterior_von_mises(fields, points[coarse], kernel)
    extent = (
        centre[i] + g[0] - step / 2,
        centre[i] + g[-1] + step / 2,
        centre[j] + g[0] - step / 2,
        centre[j] + g[-1] + step / 2,
    )
    return dict(
        axis="xyz"[k],
        value=float(value),
        names=("xyz"[i], "xyz"[j]),
        ue=ue.reshape(X.shape + (3,)),
        stress=stress.reshape(X.shape)[::2, ::2],
        stress_extent=(  # pixels of side 2 step centred on every other sample
            centre[i] + g[0] - step,
            centre[i] + g[0] + (2 * len(g[::2]) - 1) * step,
            centre[j] + g[0] - step,
            centre[j] + g[0] + (2 * len(g[::2]) - 1) * step,
        ),
        inside=inside.reshape(X.shape),
        extent=extent,
        outline=plane_section(nodes, fields["boundary_triangles"], k, float(value))[:, :, [i, j]],
    )
