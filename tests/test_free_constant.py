"""A scalar problem whose gap lives on the whole boundary (``signorini = "all"``): the
constant mode (u + c, phi - c) changes only the body load's energy, -c int f dx, so the
problem has a unique solution only for int f dx > 0 (coupling/problem.py,
``_check_free_constant``); otherwise it is refused in one line (exit 2, nothing written,
on 1 and 2 ranks) instead of a gap of 1e13 reported as converged."""
from __future__ import annotations

import numpy as np
import pytest
from mpi4py import MPI

from conftest import ROOT, run_cli, run_mpi
from coupling.options import SolverOptions
from coupling.problem import SignoriniProblem
from coupling.solvers import solve
from fem_py.forms import make_material
from fem_py.mesh import GeometrySpec, build_domain

COMM = MPI.COMM_WORLD


@pytest.fixture(scope="module")
def disk():
    return build_domain(
        COMM, GeometrySpec("disk", radius=0.25, h=0.05, subdomain_size=0.125, signorini="all")
    )


@pytest.mark.parametrize(
    "f,text", [("-1", "without bound (no solution)"), ("0", "no unique solution")]
)
def test_a_load_that_pulls_the_body_off_is_refused(disk, f, text):
    with pytest.raises(ValueError, match="whole boundary") as error:
        SignoriniProblem(disk, make_material("linear"), f=f)
    assert text in str(error.value) and "\n" not in str(error.value)


def test_a_load_that_presses_it_on_has_a_solution_touching_somewhere(disk):
    """int f > 0: the minimiser has min phi = 0, and moving along the constant mode into the
    admissible set, (u - c, phi + c) with c > 0, raises the energy by c int f."""
    problem = SignoriniProblem(disk, make_material("linear"), f="1", t0="x")
    result = solve(problem, SolverOptions(method="ssn", tol=1e-10))
    assert result.converged and result.phi.min() == pytest.approx(0.0, abs=1e-10)
    value = problem.functional.value
    base = value(result.u, result.phi)
    c = 1e-3
    result.u.x.array[:] -= c
    area = np.pi * 0.25**2  # int f over the polygon inscribed in the circle, to O(h^2)
    assert value(result.u, result.phi + c) - base == pytest.approx(c * area, rel=0.05)


def test_the_command_refuses_it_in_one_line_on_two_ranks(tmp_path):
    (tmp_path / "c.toml").write_text(
        '[geometry]\nshape = "disk"\nradius = 0.25\nh = 0.05\nsubdomain_size = 0.125\n'
        'signorini = "all"\n[data]\nf = "-1"\n'
    )
    out = tmp_path / "out"
    proc = run_cli("solve", str(tmp_path / "c.toml"), "--out", str(out), cwd=tmp_path)
    assert proc.returncode == 2 and not out.exists()
    assert proc.stderr.count("\n") == 1 and "no solution" in proc.stderr
    cli = str(ROOT / "coupling" / "app" / "cli.py")
    proc = run_mpi(2, cli, "solve", "c.toml", "--out", "out", cwd=tmp_path, check=False)
    assert proc.returncode == 2 and not out.exists()
    assert proc.stderr.count("whole boundary") == 1
