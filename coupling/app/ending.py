"""How a command ends: its exit codes, and the one line and the exit of an error on
some or all MPI ranks (``fembem``, :mod:`coupling.app.cli`)."""
from __future__ import annotations

import os
import signal
import sys
import time
from typing import Any

__all__ = [
    "EXIT_OK",
    "EXIT_CHECK_FAILED",
    "EXIT_BAD_INPUT",
    "EXIT_NOT_CONVERGED",
    "EXIT_INTERNAL_ERROR",
    "EXIT_INTERRUPTED",
    "ERROR_GRACE_SECONDS",
    "error_line",
    "end_with_error",
]

EXIT_OK, EXIT_CHECK_FAILED, EXIT_BAD_INPUT, EXIT_NOT_CONVERGED = 0, 1, 2, 3
#: 128 + the signal number, as a shell reports a process ended by that signal
EXIT_INTERRUPTED = {signal.SIGINT: 130, signal.SIGTERM: 143}
#: exit code of an unexpected exception (a bug), as Python's for an uncaught one
EXIT_INTERNAL_ERROR = 1
#: seconds a failing rank waits for all ranks to fail alike before it ends the run alone
ERROR_GRACE_SECONDS = 2.0


def error_line(err: Exception) -> tuple[int, str]:
    """(exit code, the line after "error: ") for an exception of a command: bad input
    (a configuration, a file, a folder: ValueError, OSError), memory running out, or
    anything else (a bug)."""
    first = str(err).splitlines()[0] if str(err) else ""
    if isinstance(err, (ValueError, OSError)):
        return EXIT_BAD_INPUT, first or type(err).__name__
    if isinstance(err, MemoryError):
        detail = f" ({first})" if first else ""
        return EXIT_BAD_INPUT, (
            f"out of memory{detail}; use a coarser mesh (geometry.h, "
            "geometry.subdomain_size) or a machine with more memory"
        )
    return EXIT_INTERNAL_ERROR, (
        f"internal error ({type(err).__name__}: {first}); this is a bug of fembem: "
        "please report it with the output of --debug"
    )


def end_with_error(errors: Any, code: int, message: str) -> int:
    """End the command with ``message`` and exit code ``code`` on this rank.

    Serial (``errors`` None): print the line, return the code. Under MPI, ``errors`` is a
    communicator only failing ranks use: when every rank reaches it within
    ``ERROR_GRACE_SECONDS`` (an error raised alike on every rank, such as bad input),
    rank 0 prints and every rank returns the code; otherwise this rank prints the line,
    naming itself, and exits at once without MPI's finalisation (which would wait for the
    other ranks), and mpirun then ends every other rank with the same exit code.
    """
    if errors is None:
        print(f"fembem: error: {message}", file=sys.stderr, flush=True)
        return code
    barrier = errors.Ibarrier()
    deadline = time.monotonic() + ERROR_GRACE_SECONDS
    while not barrier.Test():
        if time.monotonic() > deadline:
            print(f"fembem: error on rank {errors.rank}: {message}", file=sys.stderr, flush=True)
            sys.stdout.flush()
            os._exit(code)
        time.sleep(0.005)
    if errors.rank == 0:
        print(f"fembem: error: {message}", file=sys.stderr, flush=True)
    return code
