"""Run under mpirun: the tags of every local cell and facet (ghosts included) of the
parallel structured meshes, checked against geometry, and the coarse structure written
down from the generator against the one recovered from the distributed mesh. Writes one
JSON line per rank."""
import json
import sys

import numpy as np
from dolfinx.mesh import compute_midpoints
from mpi4py import MPI

from fem_py.mesh import GeometrySpec, build_domain
from fem_py.partition import compute_coarse_structure
from fem_py.tags import GAMMA_T_TAG, SIGNORINI_TAG0

CASES = {
    "square": dict(shape="square", h=1 / 40, subdomain_size=1 / 10, signorini=["bottom"]),
    "lshape": dict(
        shape="lshape", h=1 / 48, subdomain_size=1 / 12, signorini=["notch_bottom", "left"]
    ),
}


def differing_fields(written, recovered) -> list[str]:
    """The fields of two CoarseStructures that differ: all equal exactly but the
    coordinates, which the recovery reads from the dof coordinates (the P1 push-forward:
    round-off, 1e-15 of the domain's size) where the generator has them exact."""
    bad = []
    for name in written.__dataclass_fields__:
        a, b = getattr(written, name), getattr(recovered, name)
        if hasattr(a, "offsets"):  # a Ragged
            if not np.array_equal(a.offsets, b.offsets):
                bad.append(name)
                continue
            a, b = a.flat, b.flat
        a, b = np.asarray(a), np.asarray(b)
        if name.endswith("coords"):
            scale = np.abs(b).max()
            equal = a.shape == b.shape and np.allclose(a, b, rtol=0, atol=1e-15 * scale)
        else:
            equal = a.dtype == b.dtype and np.array_equal(a, b)
        if not equal:
            bad.append(name)
    return bad


def check(comm, case):
    d = build_domain(comm, GeometrySpec(center=(0.5, 0.5), width=0.5, structured=True, **case))
    m = d.mesh
    n_cells = m.topology.index_map(2).size_local + m.topology.index_map(2).num_ghosts
    n_facets = m.topology.index_map(1).size_local + m.topology.index_map(1).num_ghosts
    # cells: one tag per coarse square (the square holding the cell midpoint), all tagged
    mid = compute_midpoints(m, 2, np.arange(n_cells, dtype=np.int32))[:, :2]
    tag = np.full(n_cells, -1)
    tag[d.cell_tags.indices] = d.cell_tags.values
    first = {}
    square = np.floor((mid - d.vertices.min(0)) / d.coarse_size).astype(int)
    for c, t in zip(square.tolist(), tag.tolist()):
        first.setdefault(tuple(c), set()).add(t)
    cells_ok = bool(
        tag.min() >= 0
        and all(len(t) == 1 for t in first.values())
        and len(set().union(*first.values())) == len(first)
    )  # one square per tag
    # facets: exactly those on the polygon boundary are tagged, with the arc they lie in
    fmid = compute_midpoints(m, 1, np.arange(n_facets, dtype=np.int32))[:, :2]
    P = d.vertices
    side = np.full(n_facets, -1)
    for i, (a, b) in enumerate(zip(P, np.roll(P, -1, 0))):
        t, r = b - a, fmid - a
        on = (np.abs(t[0] * r[:, 1] - t[1] * r[:, 0]) < 1e-12) & ((r @ t) > 0) & ((r @ t) < t @ t)
        side[on] = i
    ftag = np.full(n_facets, -1)
    ftag[d.facet_tags.indices] = d.facet_tags.values
    names = {
        "square": ["bottom", "right", "top", "left"],
        "lshape": ["bottom", "right", "notch_bottom", "notch_left", "top", "left"],
    }[case["shape"]]
    want = np.array(
        [
            SIGNORINI_TAG0 + case["signorini"].index(names[s])
            if names[s] in case["signorini"]
            else GAMMA_T_TAG
            for s in side[side >= 0]
        ]
    )
    facets_ok = bool(
        np.array_equal(np.flatnonzero(ftag >= 0), np.flatnonzero(side >= 0))
        and np.array_equal(ftag[side >= 0], want)
    )
    recovered = compute_coarse_structure(m, d.cell_tags, d.facet_tags)
    return {
        "cells_ok": cells_ok,
        "facets_ok": facets_ok,
        "coarse_differs": differing_fields(d.coarse, recovered),
        "ghost_cells": m.topology.index_map(2).num_ghosts,
    }


if __name__ == "__main__":
    comm = MPI.COMM_WORLD
    result = {name: check(comm, case) for name, case in CASES.items()}
    with open(f"{sys.argv[1]}.{comm.rank}", "w") as f:
        json.dump(result, f)
