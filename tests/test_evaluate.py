"""`fembem evaluate` and coupling.io.evaluation: u_h inside, both traces on Gamma, u_e
outside, from the fields of a finished run.

Accuracy against the manufactured square (docs/method.md section 8): at random points inside,
u_h interpolated in its triangle converges like h^2 (P1; measured orders 2.15 and 1.72
over 16 -> 32 -> 64 cells, the second lowered by where the points fall), so the test
asks for 1.6; u_e by the representation formula converges like h^2 (measured 1.99,
2.00), asked for 1.8.
"""
from __future__ import annotations

import io

import numpy as np
import pytest
from mpi4py import MPI

from conftest import load_config, run_cli, run_mpi
from coupling.io.evaluation import evaluate
from coupling.io.outputs import boundary_fields, gather_p1
from coupling.io.quantities import boundary_flux
from coupling.manufactured import square_contact, manufactured_problem
from coupling.options import SolverOptions
from coupling.solvers import solve
from fem_py.forms import make_material

CONFIG = load_config(
    'shape = "lshape"\nh = 0.03125\nsubdomain_size = 0.125\nsignorini = ["bottom"]'
)


def test_manufactured_values_converge():
    solution = square_contact()
    rng = np.random.default_rng(1)
    inside = rng.uniform(-0.24, 0.24, (50, 2))
    theta = rng.uniform(0, 2 * np.pi, 50)
    outside = 0.5 * np.column_stack([np.cos(theta), np.sin(theta)])
    errors = []
    for cells in (16, 32, 64):
        problem = manufactured_problem(
            MPI.COMM_WORLD, solution, make_material("carstensen"), cells=cells
        )
        result = solve(problem, SolverOptions(tol=1e-10))
        x, u, triangles = gather_p1(result.u)
        fields = dict(
            x=x,
            u=u,
            triangles=triangles,
            a=np.array(problem.a),
            flux_space=np.array(problem.flux_space),
            **boundary_fields(problem, result, boundary_flux(problem, result)),
        )
        values = evaluate(fields, np.vstack([inside, outside]))
        assert list(values["where"]) == ["inside"] * 50 + ["outside"] * 50
        assert np.isnan(values["ue"][:50]).all() and np.isnan(values["u"][50:]).all()
        errors.append(
            (
                np.abs(values["u"][:50] - solution.exact_u()(*inside.T)).max(),
                np.abs(values["ue"][50:] - solution.exact_ue()(*outside.T)).max(),
            )
        )
    e = np.array(errors)
    orders = np.log2(e[:-1] / e[1:])
    assert orders[:, 0].min() >= 1.6 and orders[:, 1].min() >= 1.8, (e, orders)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("evaluate")
    config = tmp / "c.toml"
    config.write_text(CONFIG)
    out = tmp / "out"
    proc = run_cli("solve", str(config), "--out", str(out), "--quiet")
    assert proc.returncode == 0, proc.stderr
    return out, dict(np.load(out / "fields.npz"))


def _table(text: str) -> list[list[str]]:
    return [line.split(",") for line in io.StringIO(text).read().splitlines()]


def test_cli_table_nodes_boundary_and_outside(run, tmp_path):
    out, f = run
    nodes, boundary = f["x"][::7], f["boundary_x"][::5]
    far = np.array([[0.6, 0.0], [1.0, 1.0], [0.2, 0.2]])  # (0.2, 0.2): the cut-out corner
    points = np.vstack([nodes, boundary, far])
    csv = tmp_path / "p.csv"
    csv.write_text("x,y\n" + "".join(f"{x!r},{y!r}\n" for x, y in points))
    proc = run_cli("evaluate", str(out), "--points", str(csv))
    assert proc.returncode == 0, proc.stderr
    rows = _table(proc.stdout)
    assert rows[0] == ["x", "y", "where", "u", "ue"] and len(rows) == len(points) + 1
    rows = rows[1:]
    for i, (row, p) in enumerate(zip(rows, points)):
        assert np.allclose([float(row[0]), float(row[1])], p, rtol=0, atol=0)
        if i < len(nodes):
            assert row[2] in ("inside", "boundary")
            assert float(row[3]) == pytest.approx(f["u"][i * 7], rel=1e-12, abs=1e-14)
        elif i < len(nodes) + len(boundary):
            j = (i - len(nodes)) * 5
            assert row[2] == "boundary"
            assert float(row[3]) == pytest.approx(f["boundary_u"][j], rel=1e-12, abs=1e-14)
            assert float(row[4]) == pytest.approx(f["ue"][j], rel=1e-12, abs=1e-14)
        else:
            assert row[2] == "outside" and row[3] == ""
    inside = [r for r in rows[: len(nodes)] if r[2] == "inside"]
    assert inside and all(r[4] == "" for r in inside)
    # outside values are those of `fembem exterior`
    ext_csv = tmp_path / "far.csv"
    ext_csv.write_text("".join(f"{x!r},{y!r}\n" for x, y in far))
    ext = _table(run_cli("exterior", str(out), "--points", str(ext_csv)).stdout)[1:]
    assert [r[2] for r in ext] == [r[4] for r in rows[-3:]]


@pytest.mark.mpi
def test_cli_table_is_the_same_under_mpirun(run, tmp_path):
    out, f = run
    csv = tmp_path / "p.csv"
    csv.write_text("0.1,-0.1\n0.0,-0.25\n0.6,0.0\n")
    serial = run_cli("evaluate", str(out), "--points", str(csv)).stdout
    par = run_mpi(2, "-m", "coupling.app.cli", "evaluate", str(out), "--points", str(csv))
    assert par.stdout == serial
