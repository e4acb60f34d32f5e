"""Files and folders that are never half-written: the output folder of a run, and
files renamed into place once complete.

A run writes into a hidden sibling of its output folder (:func:`staged_output_dir`)
and swaps it into place when every file is written, so the folder holds either a
complete run or what it held before; an interrupted or failed run leaves nothing.
A run that is killed (SIGKILL, the kernel's out-of-memory killer, a power cut) cannot
clean up: its staging folder holds a lock file that the run keeps locked (``flock``)
while it lives, the kernel drops the lock when the process dies, and the next run into
the same place removes every staging folder whose lock it can take
(:func:`remove_stale_staging`).
"""
from __future__ import annotations

import contextlib
import ctypes
import fcntl
import os
import shutil
import tempfile
from pathlib import Path
from typing import Callable, Iterator

from mpi4py import MPI

from fem_py.parallel import broadcast_from_root, run_on_root

__all__ = [
    "atomic_write",
    "prepare_output_dir",
    "staged_output_dir",
    "claim",
    "remove_stale_staging",
]

#: the lock file of a live run inside its staging folder
_LOCK = ".lock"


def _check_output_dir(out: Path, force: bool) -> None:
    """Refuse a path that is not a folder, or a non-empty folder unless ``force``."""
    if out.exists() and not out.is_dir():
        raise FileExistsError(
            f"output path {str(out)!r} exists and is not a folder; choose another --out"
        )
    if out.is_dir() and any(out.iterdir()) and not force:
        raise FileExistsError(
            f"output folder {str(out)!r} is not empty; pass --force to overwrite "
            "it or choose another --out"
        )


def _mkdir(path: Path, out: Path) -> None:
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise FileExistsError(
            f"cannot create output folder {str(out)!r} ({err.strerror}); choose another --out"
        ) from None


def prepare_output_dir(comm: MPI.Comm, out: Path, *, force: bool) -> None:
    """Create ``out``; refuse an existing non-empty folder unless ``force`` (collective).

    With ``force`` the files of the earlier run stay until
    :func:`coupling.io.outputs.write_outputs` replaces or removes them, so a run that
    fails on bad input destroys nothing.
    """
    out = Path(out)

    def create() -> None:
        _check_output_dir(out, force)
        _mkdir(out, out)

    run_on_root(comm, create)  # the error, if any, is raised on every rank


def _exchange(a: Path, b: Path) -> bool:
    """Swap two paths atomically (Linux renameat2 RENAME_EXCHANGE); False if unsupported."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):
        return False
    at_fdcwd, rename_exchange = -100, 2
    done = renameat2(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange)
    return done == 0


def _move_into_place(staging: Path, out: Path) -> None:
    """Put the complete folder ``staging`` at ``out``; the earlier ``out`` is removed after."""
    if not out.exists() or (out.is_dir() and not any(out.iterdir())):
        os.replace(staging, out)  # rename onto an empty folder replaces it
        return
    if _exchange(staging, out):
        shutil.rmtree(staging)  # now the earlier run
        return
    old = Path(tempfile.mkdtemp(dir=out.parent, prefix=f".{out.name}.old-"))
    os.replace(out, old / out.name)
    os.replace(staging, out)
    shutil.rmtree(old)


def claim(staging: Path) -> bool:
    """True for exactly one of the ranks (processes) that call this while ``staging``
    exists: an exclusive create of a marker file inside it. Which rank reports an
    interrupt, when any rank may be stuck in a collective call."""
    try:
        os.close(os.open(staging / ".claimed", os.O_CREAT | os.O_EXCL | os.O_WRONLY))
        return True
    except OSError:
        return False


def _staging_glob(out: Path) -> str:
    return f".{out.name}.partial-*"


def remove_stale_staging(out: Path) -> list[Path]:
    """Remove the staging folders of ``out`` left by dead runs: those whose lock file is
    not locked by a live process (a folder without one, being created or being moved
    into place, is kept). Returns the folders removed."""
    removed = []
    for folder in sorted(Path(out).parent.glob(_staging_glob(Path(out)))):
        try:
            fd = os.open(folder / _LOCK, os.O_RDWR)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:  # a live run holds it
            continue
        finally:
            os.close(fd)  # releases the lock if we took it
        shutil.rmtree(folder, ignore_errors=True)
        removed.append(folder)
    return removed


def _locked_staging(out: Path) -> tuple[str, int]:
    """A new staging folder of ``out`` and the descriptor of its lock file, locked for
    as long as this process lives or until it is closed."""
    path = tempfile.mkdtemp(dir=out.parent, prefix=f".{out.name}.partial-")
    fd = os.open(Path(path) / _LOCK, os.O_CREAT | os.O_RDWR, 0o600)
    fcntl.flock(fd, fcntl.LOCK_EX)
    return path, fd


@contextlib.contextmanager
def staged_output_dir(comm: MPI.Comm, out: Path, *, force: bool) -> Iterator[Path]:
    """A hidden sibling folder of ``out`` to write a run into (collective).

    ``out`` is checked as by :func:`prepare_output_dir` first. When the block ends
    normally the staging folder replaces ``out`` (collective); when it ends by an
    exception (an interrupt included) every rank removes it and ``out`` is untouched,
    which needs no collective call. Yields the staging folder on every rank.
    """
    out = Path(out)
    lock: list[int] = []  # rank 0: the descriptor of the staging folder's lock file

    def create() -> str:
        _check_output_dir(out, force)
        _mkdir(out.parent, out)
        remove_stale_staging(out)
        path, fd = _locked_staging(out)
        lock.append(fd)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(path, 0o777 & ~umask)  # mkdtemp makes it private; a folder of results is not
        return path

    staging = Path(broadcast_from_root(comm, create))

    def unlock() -> None:
        for fd in lock:
            os.close(fd)

    try:
        yield staging
    except BaseException:
        # every rank removes it: after an interrupt a rank may be stuck in a collective
        # call with a peer that has gone, and mpirun then kills it
        shutil.rmtree(staging, ignore_errors=True)
        unlock()
        raise

    def move() -> None:
        (staging / _LOCK).unlink()  # not part of the run's files; the lock stays held
        _move_into_place(staging, out)

    try:
        run_on_root(comm, move)
    except BaseException:
        if comm.rank == 0:
            shutil.rmtree(staging, ignore_errors=True)
        raise
    finally:
        unlock()


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
