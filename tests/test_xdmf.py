"""solution.xdmf/.h5 (``coupling.io.xdmf``): the XML names every dataset with its shape,
the datasets hold the mesh, u_h, the tags and the boundary fields of fields.npz, and the
files of a run on 2 ranks equal those on 1 (the input numbering), for a square and a box.

The checks are independent of the writer: the geometry and the cells must be fields.npz's
(gathered by another path), a boundary field must equal fields.npz's boundary array at
the node with that node's coordinates and vanish at every other node, and the subdomain
tags must group the cells into the squares of side d (the face tags: into the box's
faces). Tolerances: exact for what is copied (coordinates, cells, tags, boundary values);
between 1 and 2 ranks u_h differs by the round-off of the reductions (1e-12, as in
tests/test_rank_independence.py) and the coordinates by the last bit of x0 + i h.
"""
from __future__ import annotations

import os
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from scipy.spatial import cKDTree

from conftest import LOAD_CASE, run_cli, run_mpi

os.environ.setdefault("H5PY_ALWAYS_USE_MPI", "1")  # the build on DOLFINx's HDF5 library
h5py = pytest.importorskip("h5py")

SQUARE = (
    '[geometry]\nshape = "square"\nh = 0.03125\nsubdomain_size = 0.125\nstructured = true\n'
    'signorini = ["bottom"]\n' + LOAD_CASE + "[output]\nplots = false\n"
)
BOX = (
    '[geometry]\nshape = "box"\nwidth = 0.5\nh = 0.125\nsignorini = ["bottom"]\n'
    '[data]\nf = "1"\nt0 = "-1"\nu0 = "0.02*x"\n[output]\nplots = false\n'
)
FIELDS = {"gap": "phi", "ue": "ue", "pressure": "pressure", "contact": "active"}


def _solve(tmp_path, name: str, text: str, ranks: int):
    config = tmp_path / f"{name}.toml"
    config.write_text(text)
    out = tmp_path / f"{name}-{ranks}"
    args = ("solve", str(config), "--out", str(out), "--quiet")
    proc = run_cli(*args) if ranks == 1 else run_mpi(ranks, "-m", "coupling.app.cli", *args)
    assert proc.returncode == 0, proc.stderr
    return out


def _read(out) -> tuple[dict, dict, dict]:
    """(datasets of solution.h5 named by the XML, {name: Dimensions}, fields.npz)."""
    root = ET.parse(out / "solution.xdmf").getroot()
    items = {}
    for item in root.iter("DataItem"):
        assert item.get("Format") == "HDF"
        file, path = item.text.split(":")
        assert file == "solution.h5"
        items[path] = tuple(int(n) for n in item.get("Dimensions").split())
    with h5py.File(out / "solution.h5", "r") as h5:
        data = {path: h5[path][...] for path in items}
    for path, shape in items.items():
        assert data[path].shape == shape, path
    with np.load(out / "fields.npz") as f:
        fields = {k: f[k] for k in f.files}
    return data, items, fields


def _check_against_fields(data: dict, fields: dict, cells_key: str) -> None:
    x = data["/Mesh/mesh/geometry"]
    np.testing.assert_array_equal(x, fields["x"])
    np.testing.assert_array_equal(data["/Mesh/mesh/topology"], fields[cells_key])
    np.testing.assert_array_equal(data["/Function/u/0"][:, 0], fields["u"])
    # each boundary node is found among the mesh nodes by its coordinates (equal up to
    # the last bit: the boundary map's come from the mesh geometry, x from the dofs)
    distance, rows = cKDTree(x).query(fields["boundary_x"])
    assert distance.max() <= 1e-15 and len(set(rows)) == len(rows)
    inside = np.ones(len(x), dtype=bool)
    inside[rows] = False
    for name, key in FIELDS.items():
        values = data[f"/Function/{name}/0"][:, 0]
        np.testing.assert_array_equal(values[rows], fields[key].astype(float), err_msg=name)
        assert not values[inside].any(), name
    assert data["/Function/contact/0"].sum() == fields["active"].sum() > 0


def _check_ranks(one: dict, two: dict) -> None:
    assert one.keys() == two.keys()
    for path in one:
        if path.startswith("/Function/"):
            np.testing.assert_allclose(two[path], one[path], rtol=0, atol=1e-12, err_msg=path)
        elif path == "/Mesh/mesh/geometry":
            np.testing.assert_allclose(two[path], one[path], rtol=0, atol=1e-15)
        else:
            np.testing.assert_array_equal(two[path], one[path], err_msg=path)


@pytest.mark.mpi
def test_square_xdmf_holds_the_run_and_is_the_same_on_two_ranks(tmp_path):
    runs = {ranks: _read(_solve(tmp_path, "square", SQUARE, ranks)) for ranks in (1, 2)}
    data, items, fields = runs[1]
    names = {f"/Function/{n}/0" for n in ("u", *FIELDS)} | {
        "/Mesh/mesh/geometry",
        "/Mesh/mesh/topology",
        "/MeshTags/subdomains/topology",
        "/MeshTags/subdomains/Values",
    }
    assert set(items) == names
    _check_against_fields(data, fields, "triangles")
    # the subdomain tags: every cell tagged, 4 x 4 squares of side d = 0.125 of 32 cells each
    x, cells = data["/Mesh/mesh/geometry"], data["/MeshTags/subdomains/topology"]
    np.testing.assert_array_equal(cells, fields["triangles"])
    tags = data["/MeshTags/subdomains/Values"][:, 0]
    assert sorted(np.unique(tags, return_counts=True)[1]) == [32] * 16
    centroids = x[cells].mean(axis=1)
    for tag in np.unique(tags):
        spread = np.ptp(centroids[tags == tag], axis=0)
        assert np.all(spread < 0.125), tag
    _check_ranks(data, runs[2][0])


@pytest.mark.mpi
def test_box_xdmf_holds_the_run_and_is_the_same_on_two_ranks(tmp_path):
    runs = {ranks: _read(_solve(tmp_path, "box", BOX, ranks)) for ranks in (1, 2)}
    data, items, fields = runs[1]
    assert "/MeshTags/faces/Values" in items
    _check_against_fields(data, fields, "cells")
    # the face tags: every boundary triangle once, each on one face of the box
    x, faces = data["/Mesh/mesh/geometry"], data["/MeshTags/faces/topology"]
    assert faces.shape == (12 * 4**2, 3)
    assert len({tuple(sorted(f)) for f in faces}) == len(faces)
    tags = data["/MeshTags/faces/Values"][:, 0]
    for tag in np.unique(tags):
        corners = x[faces[tags == tag]].reshape(-1, 3)
        assert np.count_nonzero(np.ptp(corners, axis=0) < 1e-15) == 1, tag  # a plane x_i = c
        assert np.all(np.abs(corners).max(axis=1) == pytest.approx(0.25)), tag
    _check_ranks(data, runs[2][0])


def test_a_mesh_file_body_tags_every_named_surface_group(tmp_path):
    """Issue 66, item 9: solution.xdmf of a body from a mesh file tagged its Signorini
    groups only; every surface group is there now, named (XDMF Information), and DOLFINx
    reads the file back."""
    from mpi4py import MPI

    from dolfinx import io as dio
    from solid_files import solid_msh

    solid_msh(tmp_path / "cube.msh", h=0.25)  # groups "bottom" and 7 (unnamed: the rest)
    text = (
        '[geometry]\nmesh = "cube.msh"\nsignorini = ["bottom"]\n'
        '[data]\nf = "1"\nt0 = "-1"\n[output]\nplots = false\n'
    )
    data, items, fields = _read(_solve(tmp_path, "cube", text, 1))
    faces, tags = data["/MeshTags/faces/topology"], data["/MeshTags/faces/Values"][:, 0]
    assert len(faces) == len(fields["boundary_triangles"])  # every boundary triangle
    x = data["/Mesh/mesh/geometry"]
    bottom = np.isclose(x[faces][:, :, 2], 0.0).all(axis=1)
    assert set(tags[bottom]) == {1} and set(tags[~bottom]) == {2}
    root = ET.parse(tmp_path / "cube-1" / "solution.xdmf").getroot()
    named = {i.get("Name"): int(i.get("Value")) for i in root.iter("Information")}
    assert named == {"bottom": 1, "7": 2}
    with dio.XDMFFile(MPI.COMM_SELF, str(tmp_path / "cube-1" / "solution.xdmf"), "r") as f:
        msh = f.read_mesh(name="mesh")
        msh.topology.create_connectivity(2, 0)
        read = f.read_meshtags(msh, name="faces")
    assert sorted(np.unique(read.values)) == [1, 2] and len(read.values) == len(faces)
