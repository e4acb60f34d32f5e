"""Files and folders that are never half-written: the output folder of a run, and
files renamed into place once complete.
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Callable

from mpi4py import MPI

from fem_py.parallel import run_on_root

__all__ = ["atomic_write", "prepare_output_dir"]


def prepare_output_dir(comm: MPI.Comm, out: Path, *, force: bool) -> None:
    """Create ``out``; refuse an existing non-empty folder unless ``force`` (collective).

    With ``force`` the files of the earlier run stay until :func:`write_outputs`
    replaces or removes them, so a run that fails on bad input destroys nothing.
    """
    out = Path(out)

    def create() -> None:
        if out.exists() and not out.is_dir():
            raise FileExistsError(
                f"output path {str(out)!r} exists and is not a folder; choose another --out"
            )
        if out.is_dir() and any(out.iterdir()) and not force:
            raise FileExistsError(
                f"output folder {str(out)!r} is not empty; pass --force to overwrite "
                "it or choose another --out"
            )
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            raise FileExistsError(
                f"cannot create output folder {str(out)!r} ({err.strerror}); "
                "choose another --out"
            ) from None

    run_on_root(comm, create)  # the error, if any, is raised on every rank


def atomic_write(path: Path, write: Callable[[Path], object]) -> None:
    """Call ``write(tmp_path)`` on a temporary file next to ``path``, then rename it to
    ``path`` (readers see the old file or the complete new one, never a partial one)."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=path.suffix)
    os.close(fd)
    try:
        write(Path(tmp))
        os.chmod(tmp, 0o644)  # mkstemp creates files readable by the owner only
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
