"""solution.xdmf and solution.h5: the mesh, its tags, u_h and the boundary fields of a run,
for ParaView and other XDMF readers.

Rank 0 writes both files from what the outputs gather there anyway (u_h and the mesh in
the input numbering of the nodes, :func:`fem_py.dofs.gather_p1`), in the layout DOLFINx's
``XDMFFile`` gives them: the mesh ``/Mesh/mesh/{geometry,topology}``, the tags
``/MeshTags/<name>/{topology,Values}`` (the subdomains of a planar domain; the faces of
a body: the box's six, the ball's two hemispheres, every surface group of a mesh file
that overlaps no Signorini group, each value named in an XDMF ``Information`` element)
and one dataset ``/Function/<name>/0`` of nodal values per function (u_h, then
:data:`BOUNDARY_FIELDS`). The nodes and cells are in the input numbering, so the
files are the same for any number of ranks.

DOLFINx 0.5's writer took 0.8-1.2 s at 10^6 dofs, and 18 s of the 25 s of outputs at
1.6e7: its ``write_function`` evaluates a function at every node (a point evaluation,
about 100 ns a node) and the four boundary fields, nonzero at a few thousand nodes,
were half of that (docs/design/speed.md). Here a boundary field is a chunked dataset
whose fill value is 0, with only the chunks that hold a node of Gamma stored.
"""
from __future__ import annotations

import os
import shutil
from pathlib import Path
from typing import NamedTuple
from xml.sax.saxutils import quoteattr

import numpy as np

from fem_py.dofs import input_indices, input_node_numbers, tag_array
from fem_py.parallel import gather_to_root

__all__ = [
    "BOUNDARY_FIELDS",
    "XdmfTags",
    "gather_xdmf_inputs",
    "owned_cell_tags",
    "write_solution_xdmf",
]

#: The boundary fields of solution.xdmf (name -> key of
#: :func:`coupling.io.outputs.boundary_fields`): nodal fields, their values on Gamma and
#: 0 elsewhere.
BOUNDARY_FIELDS = {"gap": "phi", "ue": "ue", "pressure": "pressure", "contact": "active"}

#: Rows per chunk of a boundary field's dataset (512 KB of float64).
CHUNK_ROWS = 2**16

#: XDMF's names of the cells and of their facets, by the number of nodes of a cell.
_TOPOLOGY = {3: ("Triangle", "PolyLine"), 4: ("Tetrahedron", "Triangle")}


class XdmfTags(NamedTuple):
    """What rank 0 needs besides the gathered u_h: the tags ``name`` on ``entities``
    (cells or facets, node tuples in the input numbering) with ``values``, the input
    index of every node of Gamma (boundary order) and the names of the tag values (a
    body's faces or surface groups: name -> value; written as XDMF ``Information``)."""

    name: str
    entities: np.ndarray
    values: np.ndarray
    gamma_nodes: np.ndarray
    names: dict = {}


def owned_cell_tags(domain) -> np.ndarray | None:
    """The subdomain tag of every owned cell of a planar ``domain`` (local cell order, -1
    where a cell has none), to be gathered with the cells
    (:func:`fem_py.dofs.gather_p1_and_cells`); None for a body (its tags are facets)."""
    if domain.dim == 3:
        return None
    cells = domain.mesh.topology.index_map(domain.cell_tags.dim)
    return tag_array(domain.cell_tags, cells.size_local + cells.num_ghosts)[: cells.size_local]


def gather_xdmf_inputs(
    problem, cells: np.ndarray | None, cell_tags: np.ndarray | None
) -> XdmfTags | None:
    """The tags of ``problem``'s domain and its Gamma nodes gathered to rank 0 in the
    input numbering, in an order that does not depend on the ranks (collective; None on
    the other ranks). A planar domain's tags are its subdomains: ``cell_tags`` (of
    :func:`owned_cell_tags`) of the gathered ``cells`` (both given on rank 0); a body's
    are its named faces (facet tags), gathered here."""
    from dolfinx.cpp.mesh import entities_to_geometry

    domain, V = problem.domain, problem.V
    msh, comm = domain.mesh, problem.comm
    tagged = None
    if domain.dim == 3:
        tags = domain.facet_tags
        owned = tags.indices < msh.topology.index_map(tags.dim).size_local
        # the facets' nodes (the C++ mesh's geometry) in the input numbering
        nodes = entities_to_geometry(msh._mesh, tags.dim, tags.indices[owned], False)
        tagged = (input_node_numbers(msh)[nodes], tags.values[owned])
    positions, local = problem.boundary.owned(V.dofmap.index_map.local_range)
    parts = gather_to_root(comm, (tagged, (positions, input_indices(V)[local])))
    if comm.rank != 0:
        return None
    if domain.dim == 3:
        entities = np.concatenate([t[0] for t, _ in parts]).astype(np.int64)
        values = np.concatenate([t[1] for t, _ in parts])
        order = np.lexsort(np.sort(entities, axis=1).T[::-1])
        name = "faces"
    else:  # all cells tagged (the subdomains cover the domain): no copy of the cells
        order = slice(None) if (cell_tags >= 0).all() else np.flatnonzero(cell_tags >= 0)
        entities, values, name = cells, cell_tags, "subdomains"
    gamma_nodes = np.empty(problem.boundary.n_gamma, dtype=np.int64)
    for _, (where, numbers) in parts:
        gamma_nodes[where] = numbers
    values = values[order].astype(np.int32, copy=False)
    names = dict(getattr(domain, "names", None) or {})  # a body's faces or surface groups
    return XdmfTags(name, entities[order], values, gamma_nodes, names)


def write_solution_xdmf(
    out: Path,
    fields: dict[str, np.ndarray],
    tags: XdmfTags,
    on_gamma: dict[str, np.ndarray],
) -> None:
    """solution.xdmf and solution.h5 in ``out`` (rank 0), written in a temporary subfolder
    and then moved (the .xdmf names its .h5 relatively, so both keep their final names).

    ``fields`` holds the gathered ``x`` (N, gdim), ``u`` (N,) and the cells
    (``triangles`` or, for a body, ``cells``), ``tags`` those of
    :func:`gather_xdmf_inputs` and ``on_gamma`` the boundary arrays
    (:func:`coupling.io.outputs.boundary_fields`) of :data:`BOUNDARY_FIELDS`."""
    x, u = fields["x"], fields["u"]
    cells = fields["cells"] if "cells" in fields else fields["triangles"]
    tmp = Path(out) / ".xdmf-tmp"
    tmp.mkdir(exist_ok=True)
    names = ["u", *BOUNDARY_FIELDS]
    try:
        _write_h5(tmp / "solution.h5", x, cells, tags, u, on_gamma)
        (tmp / "solution.xdmf").write_text(_xdmf_text(x.shape, cells.shape, tags, names))
        # the .h5 first: a solution.xdmf under its final name always has its data
        for name in ("solution.h5", "solution.xdmf"):
            os.replace(tmp / name, Path(out) / name)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _h5py():
    """h5py, in Debian's build on the MPI HDF5 library that DOLFINx uses (its ``h5py``
    package would otherwise load the serial build's library into a one-rank process: a
    second HDF5 library beside DOLFINx's)."""
    os.environ.setdefault("H5PY_ALWAYS_USE_MPI", "1")
    import h5py

    return h5py


def _write_h5(
    path: Path,
    x: np.ndarray,
    cells: np.ndarray,
    tags: XdmfTags,
    u: np.ndarray,
    on_gamma: dict[str, np.ndarray],
) -> None:
    h5py = _h5py()
    n_nodes = len(x)
    order = np.argsort(tags.gamma_nodes, kind="stable")
    rows = tags.gamma_nodes[order]
    with h5py.File(path, "w") as f:
        f["/Mesh/mesh/geometry"] = np.asarray(x, dtype=float)
        f["/Mesh/mesh/topology"] = np.asarray(cells, dtype=np.int64)
        f[f"/MeshTags/{tags.name}/topology"] = tags.entities
        f[f"/MeshTags/{tags.name}/Values"] = tags.values.reshape(-1, 1)
        f["/Function/u/0"] = np.asarray(u, dtype=float).reshape(-1, 1)
        for name, key in BOUNDARY_FIELDS.items():
            values = np.asarray(on_gamma[key], dtype=float)[order]
            _sparse_column(f, f"/Function/{name}/0", n_nodes, rows, values)


def _sparse_column(f, name: str, n_rows: int, rows: np.ndarray, values: np.ndarray) -> None:
    """The dataset ``name`` (n_rows, 1) of the open file ``f``: ``values`` at the sorted
    ``rows``, 0 elsewhere (chunks without one of ``rows`` not stored)."""
    chunk = max(1, min(CHUNK_ROWS, n_rows))
    dataset = f.create_dataset(
        name, shape=(n_rows, 1), dtype="f8", chunks=(chunk, 1), fillvalue=0.0
    )
    block_of = rows // chunk
    starts = np.flatnonzero(np.r_[True, block_of[1:] != block_of[:-1]]) if len(rows) else []
    block = np.zeros((chunk, 1))
    for start, end in zip(starts, [*starts[1:], len(rows)]):
        low = int(block_of[start]) * chunk
        high = min(low + chunk, n_rows)
        block[:] = 0.0
        block[rows[start:end] - low, 0] = values[start:end]
        dataset[low:high] = block[: high - low]


def _xdmf_text(
    x_shape: tuple[int, ...], cells_shape: tuple[int, ...], tags: XdmfTags, functions: list[str]
) -> str:
    """The XML of solution.xdmf, as DOLFINx 0.5's XDMFFile writes it."""
    (n_nodes, gdim), (n_cells, per_cell) = x_shape, cells_shape
    cell_type, facet_type = _TOPOLOGY[per_cell]
    n_tagged, per_entity = tags.entities.shape
    tag_type = cell_type if per_entity == per_cell else facet_type
    h5 = "solution.h5"
    lines = [
        '<?xml version="1.0"?>',
        '<!DOCTYPE Xdmf SYSTEM "Xdmf.dtd" []>',
        '<Xdmf Version="3.0" xmlns:xi="http://www.w3.org/2001/XInclude">',
        "  <Domain>",
        '    <Grid Name="mesh" GridType="Uniform">',
        f'      <Topology TopologyType="{cell_type}" NumberOfElements="{n_cells}" '
        f'NodesPerElement="{per_cell}">',
        f'        <DataItem Dimensions="{n_cells} {per_cell}" NumberType="Int" Format="HDF">'
        f"{h5}:/Mesh/mesh/topology</DataItem>",
        "      </Topology>",
        f'      <Geometry GeometryType="{"XYZ"[:gdim]}">',
        f'        <DataItem Dimensions="{n_nodes} {gdim}" Format="HDF">'
        f"{h5}:/Mesh/mesh/geometry</DataItem>",
        "      </Geometry>",
        "    </Grid>",
        f'    <Grid Name="{tags.name}" GridType="Uniform">',
        *(
            f'      <Information Name={quoteattr(str(key))} Value="{int(value)}" />'
            for key, value in tags.names.items()
        ),
        '      <xi:include xpointer="xpointer(/Xdmf/Domain/Grid/Geometry)" />',
        f'      <Topology TopologyType="{tag_type}" NumberOfElements="{n_tagged}" '
        f'NodesPerElement="{per_entity}">',
        f'        <DataItem Dimensions="{n_tagged} {per_entity}" NumberType="Int" '
        f'Format="HDF">{h5}:/MeshTags/{tags.name}/topology</DataItem>',
        "      </Topology>",
        f'      <Attribute Name="{tags.name}" AttributeType="Scalar" Center="Cell">',
        f'        <DataItem Dimensions="{n_tagged} 1" Format="HDF">'
        f"{h5}:/MeshTags/{tags.name}/Values</DataItem>",
        "      </Attribute>",
        "    </Grid>",
    ]
    for name in functions:
        lines += [
            f'    <Grid Name="{name}" GridType="Collection" CollectionType="Temporal">',
            f'      <Grid Name="{name}" GridType="Uniform">',
            "        <xi:include xpointer=\"xpointer(/Xdmf/Domain/Grid[@GridType='Uniform'][1]"
            '/*[self::Topology or self::Geometry])" />',
            '        <Time Value="0" />',
            f'        <Attribute Name="{name}" AttributeType="Scalar" Center="Node">',
            f'          <DataItem Dimensions="{n_nodes} 1" Format="HDF">'
            f"{h5}:/Function/{name}/0</DataItem>",
            "        </Attribute>",
            "      </Grid>",
            "    </Grid>",
        ]
    return "\n".join(lines + ["  </Domain>", "</Xdmf>", ""])
