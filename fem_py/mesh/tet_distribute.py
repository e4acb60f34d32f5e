"""A checked 3D mesh (``fem_py.mesh.tet_file.SolidFile``, on rank 0) as a distributed
DOLFINx mesh with facet tags named after its physical surface groups (docs/method.md
section 11): the ``geometry.mesh`` counterpart of ``box_mesh`` and ``ball_mesh``.

Surface group k (in the order given, by default the file's) gets the facet tag k + 1,
on its boundary triangles; ``names`` maps the group key (its name, or its number as
text) to that tag. A boundary triangle in two of the groups is refused (one facet, one
tag): give the groups that matter (for example the Signorini ones) as ``groups``; with
``others`` the file's other surface groups follow them, each tagged unless it shares a
boundary triangle with a group tagged before it (then it is left out whole).
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np
from dolfinx import cpp
from dolfinx import mesh as dmesh
from mpi4py import MPI

from fem_py.mesh.placed import p1_domain
from fem_py.mesh.tet_checks import boundary_faces, row_codes
from fem_py.mesh.tet_file import SolidFile
from fem_py.parallel import run_on_root

__all__ = ["group_tags", "solid_mesh"]


def group_tags(
    solid: SolidFile, groups: Sequence[str] | None = None, others: bool = False
) -> tuple[np.ndarray, np.ndarray, dict[str, int]]:
    """The tagged boundary triangles of ``solid`` (pure): the ``groups`` (default: all of
    the file's), then with ``others`` the file's other groups that overlap none before.

    Returns
    -------
    facets : (k, 3) int
        Boundary triangles (node numbers) lying in the groups.
    values : (k,) int32
        Their tags: 1 + the position of their group in ``groups``.
    names : dict
        Group key -> tag.

    Raises
    ------
    ValueError
        ``mesh: ...`` for an unknown group or a boundary triangle in two groups.
    """
    keys = list(solid.surfaces) if groups is None else [str(g) for g in groups]
    required = len(keys)
    if others:
        keys += [k for k in solid.surfaces if k not in keys]
    unknown = [k for k in keys if k not in solid.surfaces]
    if unknown:
        raise ValueError(f"mesh: {solid.source} has no physical surface group {unknown[0]!r}")
    boundary = np.sort(boundary_faces(solid.cells)[0], axis=1)
    surfaces = [np.sort(np.reshape(solid.surfaces[k], (-1, 3)), axis=1) for k in keys]
    codes = row_codes(np.vstack([boundary, *surfaces]).astype(np.int64))
    boundary_code, offset = codes[: len(boundary)], len(boundary)
    owner = np.full(len(boundary), -1, dtype=np.int64)
    names: dict[str, int] = {}
    for k, key in enumerate(keys):
        on = np.isin(boundary_code, codes[offset : offset + len(surfaces[k])])
        offset += len(surfaces[k])
        clash = on & (owner >= 0)
        if clash.any() and k >= required:
            continue  # another group of the file, overlapping one tagged already
        if clash.any():
            other = keys[int(owner[clash][0])]
            raise ValueError(
                f"mesh: surface groups {other!r} and {key!r} of {solid.source} share boundary "
                "triangles; a facet has one tag: name groups that do not overlap"
            )
        owner[on] = k
        names[key] = k + 1
    tagged = owner >= 0
    return boundary[tagged], (owner[tagged] + 1).astype(np.int32), names


def solid_mesh(
    comm: MPI.Comm,
    solid: SolidFile | None,
    groups: Sequence[str] | None = None,
    others: bool = False,
) -> tuple[dmesh.Mesh, Any, dict[str, int]]:
    """The distributed tetrahedral mesh of ``solid`` and its named facet tags
    (collective; ``solid`` is read on rank 0, None elsewhere; ``groups``, ``others``: as
    :func:`group_tags`).

    Returns
    -------
    mesh : dolfinx.mesh.Mesh
    facet_tags : MeshTags
        Tag ``names[key]`` on the boundary triangles of surface group ``key``.
    names : dict
        Group key -> facet tag (:func:`group_tags`).
    """
    tagged = run_on_root(comm, lambda: group_tags(solid, groups, others))
    if comm.rank == 0:
        cells = np.asarray(solid.cells, dtype=np.int64)
        x = np.asarray(solid.x, dtype=float)
        facets, values, names = tagged
    else:
        cells, x = np.empty((0, 4), dtype=np.int64), np.empty((0, 3))
        facets, values, names = np.empty((0, 3), np.int64), np.empty(0, np.int32), None
    names = comm.bcast(names, root=0) if comm.size > 1 else names
    msh = dmesh.create_mesh(comm, cells, x, p1_domain("tetrahedron"))
    # the tags follow the facets to their owners (entities given by input node numbers)
    entities, local_values = cpp.io.distribute_entity_data(msh._mesh, 2, facets, values)
    msh.topology.create_connectivity(2, 0)
    msh.topology.create_connectivity(2, 3)
    facet_tags = dmesh.meshtags_from_entities(
        msh, 2, cpp.graph.AdjacencyList_int32(entities), local_values.astype(np.int32)
    )
    return msh, facet_tags, names
