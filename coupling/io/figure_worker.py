"""A process that draws the figures while the run goes on computing.

matplotlib holds the GIL while it draws, and the figures take one to two seconds
whatever the mesh size (imports and first draw included), so a thread would not run them beside
the run's own Python work. :class:`FigureWorker` starts ``python -m
coupling.io.figure_worker`` when the run starts: it imports matplotlib and draws the
figures of a small square (:func:`coupling.io.figures.warm_up`; for a body it imports
the body's figure modules too) while the mesh is built, then waits for
:class:`coupling.io.figure_data.FigureInputs` on its standard input (a few MB, pickled,
each preceded by its length) and answers with the PNG bytes of
:func:`coupling.io.figures.render` on its standard output. The inputs come in parts, the
first right after the solve, and the worker draws each figure as soon as its inputs are
in: planar, boundary.png and history.png from the boundary arrays while the run gathers
and rasterises u_h, then u.png and whole_plane.png (u_e's samples); a body, the figures
on Gamma and the history while the run computes the section of slice.png (point
location and the representation formula, seconds at 64^3 cubes); an elastic run,
deformed.png, signorini.png and history.png while the run computes the samples of u_e
of exterior.png (:mod:`coupling.io.elastic_figures`). The run writes
the files itself (atomically, into its staged output folder). For planar figures the
worker imports neither MPI nor the mesh libraries; a body's figure modules import the
mesh libraries, and with them MPI: the worker starts without the variables of the run's
MPI job (:func:`outside_the_mpi_job`), so that under mpirun it is an MPI process of its
own, never a rank that fails to join the job. It runs in a session of its own (Ctrl-C
reaches the run, which ends the worker) and exits when its standard input closes.
"""
from __future__ import annotations

import contextlib
import os
import pickle
import select
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any, Callable

__all__ = ["FigureWorker", "FigureWorkerError", "outside_the_mpi_job"]


#: What mpirun adds to a rank's environment (Open MPI 4 and PMIx: the job, the rank, the
#: daemon's address); a process started with them and initialising MPI tries to join the
#: job as one of its ranks, and fails (orte_init). The Open MPI settings (OMPI_MCA_pmix,
#: OMPI_ALLOW_RUN_AS_ROOT, PMIX_MCA_*) stay.
MPI_JOB_VARIABLES = (
    "OMPI_COMM_WORLD_",
    "OMPI_MCA_orte_",
    "OMPI_MCA_ess",
    "OMPI_UNIVERSE_SIZE",
    "OMPI_FIRST_RANKS",
    "OMPI_APP_CTX_NUM_PROCS",
    "OMPI_NUM_APP_CTX",
    "OMPI_FILE_LOCATION",
    "OMPI_COMMAND",
    "OMPI_MCA_initial_wdir",
    "PMI_",
    "PMIX_",
)


def outside_the_mpi_job(environ: dict[str, str]) -> dict[str, str]:
    """``environ`` without the variables of an MPI job (:data:`MPI_JOB_VARIABLES`, but the
    PMIx settings ``PMIX_MCA_*``): the environment of a helper process of one rank (the
    figure process of a 3D run imports the mesh libraries, and with them MPI, which then
    starts as a process of its own)."""
    return {
        k: v
        for k, v in environ.items()
        if k.startswith("PMIX_MCA_") or not k.startswith(MPI_JOB_VARIABLES)
    }


#: The bytes of the length that precedes each pickled message to the worker.
_LENGTH_BYTES = 8


@contextlib.contextmanager
def _sigpipe_blocked():
    """Writes to a pipe whose reader has ended raise BrokenPipeError inside, whatever
    handles SIGPIPE in this process (PETSc initialised with its signal handlers, as in a
    script or a test, aborts the process on it; ``fembem`` turns them off): the signal is
    blocked in this thread, and one that a write raised is taken before it is unblocked."""
    blocked = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGPIPE})
    try:
        yield
    finally:
        if signal.SIGPIPE not in blocked:
            if signal.SIGPIPE in signal.sigpending():
                signal.sigwait({signal.SIGPIPE})
            signal.pthread_sigmask(signal.SIG_SETMASK, blocked)


def _close(stream) -> None:
    """Close a pipe of the worker: what a failed write left in its buffer is dropped."""
    with _sigpipe_blocked():
        try:
            stream.close()
        except BrokenPipeError:
            pass


class FigureWorkerError(RuntimeError):
    """The figure process failed (its last line of error output, or how it ended)."""


class FigureWorker:
    """The figure process of one run (rank 0 of a run with plots), used once.

    Use as a context manager: leaving it ends the process if it still runs.
    """

    def __init__(self, body: bool = False) -> None:
        """Start the worker; ``body``: the run's Omega is a body in R^3, whose figure
        modules the worker imports while it warms up (about a second)."""
        root = str(Path(__file__).resolve().parents[2])  # the folder holding ``coupling``
        path = os.environ.get("PYTHONPATH")
        env = dict(
            outside_the_mpi_job(os.environ),
            PYTHONPATH=root if not path else os.pathsep.join([root, path]),
            MPLBACKEND="Agg",
            OMP_NUM_THREADS="1",
            OPENBLAS_NUM_THREADS="1",
        )
        self._process = subprocess.Popen(
            [sys.executable, "-m", __name__, *(["--body"] if body else [])],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            env=env,
            start_new_session=True,
        )

    def send(self, inputs) -> None:
        """Hand the worker ``inputs`` (pickled into its standard input): it draws the
        figures of :func:`coupling.io.figures.render` it has not drawn from earlier
        inputs. Returns once the pipe has taken them (at once, unless the worker is still
        drawing or warming up and they exceed the pipe's 64 KB);
        if it has ended, :meth:`answer` raises its error."""
        data = pickle.dumps(inputs, protocol=5)
        try:  # its length first: the worker reads the whole message before unpickling it,
            # which may import modules for a second (the pipe would wait for that)
            with _sigpipe_blocked():
                self._process.stdin.write(len(data).to_bytes(_LENGTH_BYTES, "little") + data)
                self._process.stdin.flush()
        except (BrokenPipeError, ValueError):  # it ended before reading, or was ended
            pass

    def answer(self) -> dict[str, bytes]:
        """The PNG bytes of all the figures drawn from the inputs sent; waits for the
        worker to finish.

        Raises
        ------
        FigureWorkerError
            The worker ended without an answer (its error, or its exit status).
        """
        stdin, self._process.stdin = self._process.stdin, None
        if stdin is not None:  # the end of the inputs (and a flush of what a write to an
            _close(stdin)  # ended worker left in the buffer)
        try:
            out, err = self._process.communicate()
        except ValueError:  # its output was closed: it was ended
            out, err = b"", b""
            self.close()
        status = self._process.returncode
        if status == 0 and out:
            return pickle.loads(out)
        lines = err.decode(errors="replace").strip().splitlines()
        raise FigureWorkerError(lines[-1] if lines else f"the figure process exited with {status}")

    def render(self, inputs, *later: Callable[[], Any]) -> dict[str, bytes]:
        """The PNG bytes of the figures of ``inputs`` (:func:`coupling.io.figures.render`),
        drawn in the worker; waits for it to finish.

        ``later``: functions returning more complete inputs (a body's section, which takes
        seconds to compute), each called here while the worker draws what it was sent
        before; the worker then draws the figures it has not drawn yet. An error of one
        of them ends the worker and is raised.

        Raises
        ------
        FigureWorkerError
            The worker ended without an answer (its error, or its exit status).
        """
        self.send(inputs)
        return self.render_rest(*later)

    def render_rest(self, *later: Callable[[], Any]) -> dict[str, bytes]:
        """:meth:`render` for a worker that was sent its first inputs already (:meth:`send`)."""
        for more in later:
            try:
                inputs = more()
            except BaseException:
                self.close()
                raise
            self.send(inputs)
        return self.answer()

    def close(self) -> None:
        """End the worker if it still runs."""
        if self._process.poll() is None:
            self._process.kill()
        self._process.wait()
        for stream in (self._process.stdin, self._process.stdout, self._process.stderr):
            if stream is not None:  # the input may hold what a failed send left
                _close(stream)

    def __enter__(self) -> FigureWorker:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def main(argv: list[str]) -> int:
    """The worker: warm up (``--body``: import a body's figure modules too), draw the
    figures of each inputs read (those not drawn from the inputs before), and when the
    input ends answer with all the PNG bytes."""
    from coupling.io import figures

    if "--body" in argv:
        import coupling.io.body_figures  # noqa: F401
    figures.warm_up(stop=lambda: bool(select.select([sys.stdin], [], [], 0)[0]))
    pngs: dict[str, bytes] | None = None
    while True:
        length = sys.stdin.buffer.read(_LENGTH_BYTES)
        if len(length) < _LENGTH_BYTES:  # after the last inputs, or the run ended
            break  # without figures
        inputs = pickle.loads(sys.stdin.buffer.read(int.from_bytes(length, "little")))
        pngs = (pngs or {}) | figures.render(inputs, skip=pngs or ())
    if pngs is not None:
        pickle.dump(pngs, sys.stdout.buffer, protocol=5)
        sys.stdout.buffer.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
