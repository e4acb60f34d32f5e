"""Output helpers without a solve: atomic writes, the output folder, the plots.

The figures are drawn from synthetic fields of the square [-1/4, 1/4]^2 (u = x + y,
u_e the field of a point source); what is checked is that every figure is written for
the cases the drawing code distinguishes (P1 and P0 flux, no Signorini arc, an arc
that wraps past the first boundary node, Gamma_s = Gamma), not how they look.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from mpi4py import MPI

from coupling.io.atomic import atomic_write, prepare_output_dir
from coupling.io.gamma_drawing import true_runs
from coupling.io.plots import PLOT_FILES, write_plots
from fem_py.polyline import arc_length

PNG = b"\x89PNG\r\n\x1a\n"


def test_atomic_write_replaces_or_keeps_the_old_file(tmp_path):
    path = tmp_path / "a.txt"
    atomic_write(path, lambda p: p.write_text("one"))
    assert path.read_text() == "one"

    def fail(p):
        p.write_text("half")
        raise RuntimeError("disk full")

    with pytest.raises(RuntimeError):
        atomic_write(path, fail)
    assert path.read_text() == "one"
    assert [p.name for p in tmp_path.iterdir()] == ["a.txt"]  # no temporary left


def test_prepare_output_dir(tmp_path):
    comm = MPI.COMM_SELF
    out = tmp_path / "new" / "deeper"
    prepare_output_dir(comm, out, force=False)
    assert out.is_dir()
    (out / "x").write_text("")
    with pytest.raises(FileExistsError, match="not empty; pass --force"):
        prepare_output_dir(comm, out, force=False)
    prepare_output_dir(comm, out, force=True)
    assert (out / "x").exists()  # kept until write_outputs replaces the run's files
    with pytest.raises(FileExistsError, match="is not a folder"):
        prepare_output_dir(comm, out / "x", force=True)


@pytest.mark.parametrize(
    "mask, runs",
    [
        ([0, 1, 1, 0, 0], [(1, 3)]),
        ([1, 1, 0, 0, 1], [(4, 7)]),  # wraps past panel 0: panels 4, 0, 1
        ([1, 0, 1, 0, 1], [(2, 3), (4, 6)]),  # panels 4 and 0 form one run
        ([0, 0, 0], []),
        ([1, 1, 1], [(0, 3)]),
    ],
)
def test_runs_of_a_cyclic_mask(mask, runs):
    assert true_runs(np.array(mask, dtype=bool)) == runs


def square_fields(n: int, signorini: np.ndarray, flux_space: str) -> dict:
    """Fields.npz-like arrays on the square [-1/4, 1/4]^2 with n cells per side."""
    g = np.linspace(-0.25, 0.25, n + 1)
    X, Y = np.meshgrid(g, g)
    x = np.column_stack([X.ravel(), Y.ravel()])
    k = np.arange(n * (n + 1)).reshape(n, n + 1)[:, :n].ravel()  # lower-left corners
    triangles = np.concatenate(
        [np.column_stack([k, k + 1, k + n + 2]), np.column_stack([k, k + n + 2, k + n + 1])]
    )
    side = g[:-1]
    nodes = np.concatenate(
        [
            np.column_stack([side, np.full(n, -0.25)]),
            np.column_stack([np.full(n, 0.25), side]),
            np.column_stack([-side, np.full(n, 0.25)]),
            np.column_stack([np.full(n, -0.25), -side]),
        ]
    )
    r2 = (nodes**2).sum(axis=1)
    phi = np.where(signorini, 0.01 * np.sin(np.arange(len(nodes))) ** 2, 0.0)
    active = signorini & (phi == 0)
    return dict(
        x=x,
        u=x.sum(axis=1),
        triangles=triangles,
        boundary_x=nodes,
        boundary_u=nodes.sum(axis=1),
        phi=phi,
        # du/dn of u = x + y on the bottom, right, top and left sides (n nodes each)
        pressure=np.repeat([-1.0, 1.0, 1.0, -1.0], n),
        ue=0.5 + 0.1 * np.log(r2),
        dn_ue=0.2 / np.sqrt(r2) if flux_space == "p1" else np.full(len(nodes), 0.8),
        active=active,
        signorini=signorini,
        a=np.array(0.5),
        flux_space=np.array(flux_space),
    )


@pytest.mark.parametrize("case", ["none", "wrapping arc, p0 flux", "all"])
def test_every_figure_is_written(tmp_path, case):
    n = 8
    signorini = np.zeros(4 * n, dtype=bool)
    if case == "wrapping arc, p0 flux":
        # an arc from node 4n - 4 on the left side round the corner node 0 to node 3
        signorini[np.r_[4 * n - 3 : 4 * n, 0:3]] = True
    elif case == "all":
        signorini[:] = True
    fields = square_fields(n, signorini, "p0" if "p0" in case else "p1")
    history = [
        SimpleNamespace(iteration=k, energy=-1 + 2.0**-k, step_norm=2.0**-k, contact=3)
        for k in range(1, 30)
    ]
    if case == "none":  # no history (no iteration): no history.png
        history = []
    written = write_plots(tmp_path, fields, history, tol=1e-8)
    assert written == [n for n in PLOT_FILES if history or n != "history.png"]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(written)
    for name in written:
        assert (tmp_path / name).read_bytes()[:8] == PNG


def test_arc_length():
    nodes = np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 4.0], [0.0, 0.0]])
    np.testing.assert_allclose(arc_length(nodes), [0.0, 3.0, 7.0, 12.0])


@pytest.mark.parametrize("shape", ["square", "box"])
def test_a_figure_process_that_died_leaves_the_figures_to_the_run(
    tmp_path, monkeypatch, capsys, shape
):
    """The figure process ended before the run sent it anything (killed, out of memory):
    the sends do not fail, its answer does, and the run draws every figure itself with a
    one-line warning."""
    import coupling.app.cli as cli
    import coupling.io.figure_worker as figure_worker
    from coupling.io.body_figure_data import BODY_PLOT_FILES

    class Dead(figure_worker.FigureWorker):
        def __init__(self, body=False):
            super().__init__(body)
            self._process.kill()
            self._process.wait()

    monkeypatch.setattr(figure_worker, "FigureWorker", Dead)
    geometry = (
        'shape = "square"\nh = 0.0625\nsubdomain_size = 0.125\n'
        if shape == "square"
        else 'shape = "box"\ncenter = [0.0, 0.0, 0.0]\nwidth = 0.5\nh = 0.125\n'
    )
    config = tmp_path / "c.toml"
    config.write_text(
        f'[geometry]\n{geometry}signorini = ["bottom"]\n[data]\nt0 = "-1"\n'
        "[output]\nxdmf = false\nplots = true\n"
    )
    out = tmp_path / "out"
    assert cli.main(["solve", str(config), "--out", str(out), "--quiet"]) == 0
    expected = PLOT_FILES if shape == "square" else BODY_PLOT_FILES
    assert all((out / name).read_bytes()[:8] == PNG for name in expected)
    assert "warning: the figure process failed" in capsys.readouterr().err


def test_a_dead_figure_process_ends_quietly_in_a_process_with_petsc_s_handlers():
    """In a process whose PETSc keeps its signal handlers (a user's script), a figure
    process that has died is sent inputs, then ended without an answer (the run failed)
    or asked for one: no write to its pipe raises SIGPIPE, which PETSc's handler would
    turn into MPI_Abort; the answer is FigureWorkerError."""
    import subprocess
    import sys

    from conftest import ROOT

    code = """
from petsc4py import PETSc  # its signal handlers on
from coupling.io.figure_worker import FigureWorker, FigureWorkerError
for ask in (False, True):
    with FigureWorker() as worker:
        worker._process.kill()
        worker._process.wait()
        worker.send(list(range(1000)))  # stays in the pipe's buffer
        if ask:
            try:
                worker.answer()
            except FigureWorkerError:
                print("answer failed", flush=True)
print("ended", flush=True)
"""
    proc = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.split() == ["answer", "failed", "ended"]
