"""Nested iteration (coupling.solvers.nested): the coarse solution prolonged to the fine
mesh starts the fine solve; the answer is that of the cold solve to the tolerance and
the fine level takes fewer steps.

Measured (square, carstensen, 128 cells, d = 4h, one coarse level of 64 cells at the same
d): ssn 11 cold -> 4 Newton steps on the fine level (no PGPM warm steps), pgpm 182 ->
102, apgpm 56 -> 36; u differs from the cold solve by 6e-15 (ssn) and 4e-8, 5e-8
(pgpm, apgpm, whose stopping rule at tol = 1e-8 bounds the error by a multiple of tol).
"""
from __future__ import annotations

import json

import numpy as np
import pytest
from mpi4py import MPI

from conftest import run_cli, run_mpi
from coupling.app.config import parse_config
from coupling.app.from_config import coarser_configs
from coupling.manufactured import manufactured_problem, square_contact
from coupling.options import SolverOptions
from coupling.solvers import solve
from coupling.solvers.nested import prolong, solve_nested
from fem_py.forms import make_material

MATERIAL = make_material("carstensen")


def _levels(cells: int):
    fine = manufactured_problem(MPI.COMM_WORLD, square_contact(), MATERIAL, cells=cells)
    coarse = lambda: manufactured_problem(  # noqa: E731 - the same subdomains
        MPI.COMM_WORLD, square_contact(), MATERIAL, cells=cells // 2, d_over_h=2
    )
    return fine, coarse


@pytest.mark.parametrize("method,cold_bound", [("ssn", 6), ("pgpm", 0.7), ("apgpm", 0.8)])
def test_nested_solve_gives_the_cold_answer_in_fewer_fine_steps(method, cold_bound):
    fine, coarse = _levels(64)
    options = SolverOptions(method=method)
    cold = solve(fine, options)
    nested, levels = solve_nested(fine, [coarse], options)
    assert nested.converged and [lv.dofs for lv in levels] == [1089, 4225]
    scale = np.abs(cold.u.x.array).max()
    # both answers meet the stopping rule at tol = 1e-8; ssn's superlinear convergence puts
    # them closer (measured 3.4e-10 relative), pgpm's linear one within the condition
    # number times tol
    tol = 1e-8 if method == "ssn" else 1e-6
    assert np.abs(nested.u.x.array - cold.u.x.array).max() <= tol * scale
    assert np.abs(nested.phi - cold.phi).max() <= tol * scale
    if method == "ssn":  # Newton steps at once, no more than measured plus one
        assert all(r.line_search is not None for r in nested.history)
        assert nested.iterations <= cold_bound
    else:
        assert nested.iterations <= cold_bound * cold.iterations
    assert set(nested.timings) >= {"coarse_levels", "prolongation", "solve"}


def test_prolongation_is_exact_for_nested_meshes():
    """The meshes are nested (every coarse node is a fine node, the new nodes are edge
    midpoints), so P1 prolongation reproduces the coarse field at the coarse nodes and
    its average at the midpoints; the gap likewise along Gamma."""
    fine, coarse_builder = _levels(32)
    coarse = coarse_builder()
    solution = solve(coarse, SolverOptions())
    u, phi = prolong(coarse, solution, fine)
    xf = fine.V.tabulate_dof_coordinates()[: len(u), :2]
    xc = coarse.V.tabulate_dof_coordinates()[:, :2]
    key = lambda x: {tuple(np.round(p, 12)) for p in x}  # noqa: E731
    on_coarse = np.array([tuple(np.round(p, 12)) in key(xc) for p in xf])
    coarse_value = {tuple(np.round(p, 12)): v for p, v in zip(xc, solution.u.x.array)}
    got = np.array([coarse_value[tuple(np.round(p, 12))] for p in xf[on_coarse]])
    np.testing.assert_allclose(u[on_coarse], got, atol=1e-14)
    assert phi.shape == (fine.n_signorini,) and (phi >= 0).all()
    s_fine = fine.boundary.nodes[fine.boundary.signorini]
    s_coarse = {
        tuple(np.round(p, 12)): v
        for p, v in zip(coarse.boundary.nodes[coarse.boundary.signorini], solution.phi)
    }
    shared = [i for i, p in enumerate(s_fine) if tuple(np.round(p, 12)) in s_coarse]
    np.testing.assert_allclose(
        phi[shared], [s_coarse[tuple(np.round(s_fine[i], 12))] for i in shared], atol=1e-14
    )


def test_cli_nested_option(tmp_path):
    config = tmp_path / "c.toml"
    config.write_text(
        "[geometry]\nh = 0.00390625\nsubdomain_size = 0.015625\n"
        'signorini = ["bottom"]\n[material]\nrho = "carstensen"\n'
        '[data]\nf = "1 + x"\nt0 = "-1"\nu0 = "0.1"\n[output]\nplots = false\n'
    )
    runs = {}
    for nested in ("true", "false"):
        out = tmp_path / nested
        proc = run_cli(
            "solve", str(config), "--out", str(out), "--quiet", "--set", f"solver.nested={nested}"
        )
        assert proc.returncode == 0, proc.stderr
        runs[nested] = (json.loads((out / "summary.json").read_text()), np.load(out / "fields.npz"))
    (s_nested, f_nested), (s_cold, f_cold) = runs["true"], runs["false"]
    assert [lv["dofs"] for lv in s_nested["levels"]] == [1089, 16641]  # h x 4, d = 2h there
    assert "levels" not in s_cold
    assert s_nested["files"].count("levels.csv") == 1 and "levels.csv" not in s_cold["files"]
    assert not {"adapt.csv", "adapt.png"} & set(s_nested["files"])  # adaptive runs only
    assert s_nested["iterations"] < s_cold["iterations"]
    np.testing.assert_allclose(f_nested["u"], f_cold["u"], atol=1e-12)


@pytest.mark.mpi
def test_nested_run_is_the_same_on_two_ranks(tmp_path):
    """The default nested solve (levels of 1,089 and 16,641 dofs) on 1 and 2 ranks: the
    same levels, steps and CG iterations, and u_h to round-off (the runs differ only in
    the order of reductions; 1e-12 as in tests/test_rank_independence.py)."""
    config = tmp_path / "c.toml"
    config.write_text(
        "[geometry]\nh = 0.00390625\nsubdomain_size = 0.015625\n"
        'signorini = ["bottom"]\n[material]\nrho = "carstensen"\n'
        '[data]\nf = "1 + x"\nt0 = "-1"\nu0 = "0.1"\n[output]\nplots = false\nxdmf = false\n'
    )
    runs = []
    for nprocs, out in ((1, tmp_path / "p1"), (2, tmp_path / "p2")):
        args = ("solve", str(config), "--out", str(out), "--quiet")
        if nprocs == 1:
            proc = run_cli(*args)
            assert proc.returncode == 0, proc.stderr
        else:
            run_mpi(nprocs, "-m", "coupling.app.cli", *args)
        runs.append((json.loads((out / "summary.json").read_text()), np.load(out / "fields.npz")))
    (s1, f1), (s2, f2) = runs
    assert s2["mpi_ranks"] == 2
    key = lambda s: [
        (lv["dofs"], lv["iterations"], lv["cg_iterations"]) for lv in s["levels"]
    ]  # noqa: E731
    assert key(s1) == key(s2) and len(s1["levels"]) == 2
    assert [h["cg_iterations"] for h in s1["history"]] == [
        h["cg_iterations"] for h in s2["history"]
    ]
    np.testing.assert_allclose(f2["u"], f1["u"], atol=1e-12 * np.abs(f1["u"]).max())


@pytest.mark.parametrize("subdomains_on_arc,levels", [(2, 1), (3, 0)])
def test_coarser_levels_stop_where_their_geometry_is_invalid(subdomains_on_arc, levels):
    """The 4h level raises d = 4h to 8h: a Signorini arc over an odd number of the given
    subdomains ends between the coarse level's grid vertices, so that level is dropped
    (the solve is cold) instead of failing a run the fine mesh allows."""
    h = 0.5 / 128
    d = 4 * h
    end = -0.25 + subdomains_on_arc * d
    config = parse_config(
        {
            "geometry": {
                "h": h,
                "subdomain_size": d,
                "signorini": [[[-0.25, -0.25], [end, -0.25]]],
            }
        }
    )
    coarser = coarser_configs(config, 129**2)
    assert len(coarser) == levels
    for level in coarser:
        assert level.geometry.subdomain_size == 2 * level.geometry.h == 8 * h


def test_nested_solve_of_a_body():
    # the box (docs/design/three_dimensions.md, "Nested"): 16 cubes per side started from
    # the solution on 8; the coarse u by P1 interpolation in the tetrahedra, the gap on the
    # coarse surface triangles (the fine nodes lie on the flat faces)
    from coupling.manufactured import box_contact

    build = lambda cells: manufactured_problem(  # noqa: E731
        MPI.COMM_WORLD, box_contact(), MATERIAL, cells=cells
    )
    fine = build(16)
    options = SolverOptions()
    cold = solve(fine, options)
    nested, levels = solve_nested(fine, [lambda: build(8)], options)
    assert nested.converged and [lv.dofs for lv in levels] == [729, 4913]
    # both meet the stopping rule at tol = 1e-8: within C0/c0 (8.8 here) times tol
    # (measured 1.0e-8 relative)
    scale = np.abs(cold.u.x.array).max()
    assert np.abs(nested.u.x.array - cold.u.x.array).max() <= 1e-7 * scale
    assert np.abs(nested.phi - cold.phi).max() <= 1e-7 * scale
    assert np.array_equal(nested.contact, cold.contact)
    assert nested.iterations < cold.iterations  # measured 3 against 10

    # the configuration's levels (NESTED_COARSENING_3D): h times 4 per level while a level
    # keeps NESTED_MIN_DOFS = 1000 dofs and a whole number of cubes, then once times 2
    # where that still does
    def levels(cubes: int) -> list[float]:
        config = parse_config({"geometry": {"shape": "box", "width": 0.5, "h": 0.5 / cubes}})
        return [0.5 / c.geometry.h for c in coarser_configs(config, (cubes + 1) ** 3)]

    assert levels(128) == pytest.approx([16, 32], rel=1e-12)  # 8 cubes: 729 dofs
    assert levels(64) == pytest.approx([16], rel=1e-12)  # 8 cubes: 729 dofs
    assert levels(48) == pytest.approx([12], rel=1e-12)  # 3 or 6 cubes: too few dofs
    assert levels(32) == pytest.approx([16], rel=1e-12)  # 8 cubes: too few
    assert levels(30) == pytest.approx([15], rel=1e-12)  # 7.5 cubes: no level at 4h
    assert levels(14) == []  # 7 cubes: 512 dofs
