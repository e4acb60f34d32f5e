"""``[solver] boundary_operator``: the solver with the H-matrix S_h (bem_cpp, applied and
never formed) gives the dense answer, serially and on two ranks; the choice is validated;
what needs the dense S_h refuses the H-matrix in one line (docs/design/hmatrix.md)."""
from __future__ import annotations

import numpy as np
import pytest
from mpi4py import MPI

from conftest import ROOT, run_mpi
from coupling.app.config import ConfigError, parse_config
from coupling.distributed import boundary_operator_kind, dense_matrix
from coupling.manufactured import MANUFACTURED, manufactured_problem
from coupling.options import HMATRIX_CROSSOVER, HMATRIX_CROSSOVER_3D, SolverOptions
from coupling.preconditioners import build_preconditioner
from coupling.solvers import solve
from fem_py.forms import make_material

SCRIPT = str(ROOT / "tests" / "mpi" / "boundary_operator_check.py")
#: 128 cells per side: 512 boundary dofs on the square and on the L-shape, eight
#: H-matrix leaves of 64 dofs, so that S_h has low-rank blocks (not at 64 cells)
CELLS = 128


@pytest.fixture(scope="module", autouse=True)
def one_thread():
    """One OpenMP / BLAS thread, as each rank under mpirun: on the shared 2-core machine
    two threads made the small (n = 512) H-matrix products about 10 times slower
    (docs/design/hmatrix.md, "The solver's S_h"); the results do not depend on it."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1):
        yield


def _problem(shape: str, kind: str):
    return manufactured_problem(
        MPI.COMM_WORLD,
        MANUFACTURED[shape](),
        make_material("carstensen"),
        cells=CELLS,
        boundary_operator=kind,
    )


@pytest.fixture(scope="module")
def problems():
    return {
        (shape, kind): _problem(shape, kind)
        for shape in ("square", "lshape")
        for kind in ("dense", "hmatrix")
    }


#: the solver tolerance (relative step) of each method in these tests
METHOD_TOL = {"ssn": 1e-10, "pgpm": 1e-8}


@pytest.fixture(scope="module")
def solutions(problems):
    """solutions(shape, kind, method), each solved once per module."""
    cache: dict = {}

    def get(shape: str, kind: str, method: str):
        if (shape, kind, method) not in cache:
            options = SolverOptions(method=method, tol=METHOD_TOL[method], max_iterations=5000)
            cache[shape, kind, method] = solve(problems[shape, kind], options)
        return cache[shape, kind, method]

    return get


def _relative(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def test_the_hmatrix_operator_is_not_formed_and_has_low_rank_blocks(problems):
    dense, hmatrix = problems["square", "dense"], problems["square", "hmatrix"]
    assert isinstance(dense.S, np.ndarray) and dense.boundary_operator == "dense"
    assert hmatrix.boundary_operator == "hmatrix" and not isinstance(hmatrix.S, np.ndarray)
    assert hmatrix.S.shape == dense.S.shape == (512, 512)
    assert hmatrix.S.info.max_rank > 0  # compressed blocks, not only the near field
    z = np.random.default_rng(1).standard_normal(512)
    # products to the H-matrix accuracy (tol 1e-10, docs/design/hmatrix.md)
    assert _relative(hmatrix.S @ z, dense.S @ z) <= 1e-9


@pytest.mark.parametrize("shape,method", [("square", "ssn"), ("square", "pgpm"), ("lshape", "ssn")])
def test_hmatrix_solve_gives_the_dense_answer(solutions, shape, method):
    dense, hmatrix = solutions(shape, "dense", method), solutions(shape, "hmatrix", method)
    assert dense.converged and hmatrix.converged
    assert hmatrix.iterations == dense.iterations
    np.testing.assert_array_equal(hmatrix.contact, dense.contact)
    # The two discrete problems differ by the product error of S_h (the H-matrix blocks
    # to relative 1e-10: 5e-11 measured at n = 512) and the two runs take the same
    # steps, so the iterates differ by the same order; 10 times the block tolerance
    # bounds it (measured: u 6e-14 ... 9e-14, phi 5e-12 ... 3e-11, energy 3e-13,
    # flux 6e-11 ... 1.2e-10).
    assert _relative(hmatrix.u.x.array, dense.u.x.array) <= 1e-9
    assert _relative(hmatrix.phi, dense.phi) <= 1e-9
    assert abs(hmatrix.energy - dense.energy) <= 1e-11 * abs(dense.energy)
    # the exterior flux by the operator's CG solve with V_h against the Cholesky solve
    assert _relative(hmatrix.flux, dense.flux) <= 1e-9


@pytest.mark.mpi
def test_hmatrix_solve_is_the_same_on_two_ranks(tmp_path, solutions):
    serial = solutions("square", "hmatrix", "ssn")
    out = tmp_path / "p2.npz"
    run_mpi(2, SCRIPT, str(out), str(CELLS), "ssn", "hmatrix", str(METHOD_TOL["ssn"]))
    par = np.load(out)
    # distributed by rows (bem_cpp.steklov_poincare(..., comm=...)), not replicated: rank 0
    # holds about half the serial bytes (measured 0.51; tests/test_mpi_steklov_operator.py)
    assert str(par["operator_class"]) == "SteklovPoincareOperator"
    assert par["distributed_bytes"] < 0.65 * par["serial_bytes"]
    assert par["converged"] and par["iterations"] == serial.iterations
    assert abs(par["energy"] - serial.energy) <= 1e-12 * abs(serial.energy)
    np.testing.assert_allclose(par["phi"], serial.phi, rtol=0, atol=1e-9 * abs(serial.phi).max())
    np.testing.assert_allclose(par["flux"], serial.flux, rtol=0, atol=1e-9 * abs(serial.flux).max())
    # u: compared as a set of nodal values sorted by coordinates (the rank-independent
    # order of tests/mpi/boundary_operator_check.py)
    from coupling.io.outputs import gather_p1

    x, u, _ = gather_p1(serial.u)
    key = np.round(x, 12)
    order = np.lexsort((key[:, 1], key[:, 0]))
    np.testing.assert_allclose(par["x"], x[order], atol=1e-15)
    assert _relative(par["u"], u[order]) <= 1e-9


def test_auto_chooses_by_the_crossover():
    assert boundary_operator_kind("auto", HMATRIX_CROSSOVER) == "hmatrix"
    assert boundary_operator_kind("auto", HMATRIX_CROSSOVER - 1) == "dense"
    # a surface in R^3 has its own crossover
    assert boundary_operator_kind("auto", HMATRIX_CROSSOVER_3D, 3) == "hmatrix"
    assert boundary_operator_kind("auto", HMATRIX_CROSSOVER_3D - 1, 3) == "dense"
    for kind in ("dense", "hmatrix"):
        assert boundary_operator_kind(kind, 10) == boundary_operator_kind(kind, 10**6) == kind
    with pytest.raises(ValueError, match="boundary_operator must be one of"):
        boundary_operator_kind("h-matrix", 100)
    with pytest.raises(ValueError, match="boundary_operator must be one of"):
        SolverOptions(boundary_operator="sparse")


def test_config_validates_the_choice():
    assert parse_config({}).solver.boundary_operator == "auto"
    assert (
        parse_config({"solver": {"boundary_operator": "hmatrix"}}).solver.boundary_operator
        == "hmatrix"
    )
    with pytest.raises(ConfigError, match='solver.boundary_operator must be one of "auto"'):
        parse_config({"solver": {"boundary_operator": "fast"}})
    with pytest.raises(ConfigError, match='set solver.boundary_operator = "dense"'):
        parse_config({"solver": {"boundary_operator": "hmatrix", "preconditioner": "exact"}})


@pytest.mark.parametrize(
    "setting,message",
    [
        ("solver.boundary_operator=fast", "solver.boundary_operator must be one of"),
        ("solver.preconditioner=exact", "factors the dense S_h; set solver.boundary_operator"),
    ],
)
def test_cli_refuses_bad_settings_in_one_line(tmp_path, capsys, setting, message):
    import coupling.app.cli as cli

    config = tmp_path / "c.toml"
    config.write_text('[solver]\nboundary_operator = "hmatrix"\n')
    assert cli.main(["info", str(config), "--set", setting]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("fembem: error: ") and message in lines[0]


def test_dense_only_paths_refuse_the_hmatrix_in_one_line(problems):
    hmatrix = problems["square", "hmatrix"]
    with pytest.raises(ValueError, match='set \\[solver\\] boundary_operator = "dense"') as err:
        build_preconditioner(hmatrix, SolverOptions(preconditioner="exact"))
    assert "the exact preconditioner needs the dense S_h" in str(err.value)
    assert "\n" not in str(err.value)
    from bench.peers.baselines import CoupledHessian

    with pytest.raises(ValueError, match="SNES VI / TAO Newton peers needs the dense S_h"):
        CoupledHessian(hmatrix)
    dense = problems["square", "dense"]
    assert dense_matrix(dense.S, "x") is dense.S
