"""Freed memory given back to the operating system before a run's outputs.

glibc's allocator keeps the memory a process frees: small blocks, and since its mmap
threshold rises with every large block freed (up to 32 MB), most arrays of a large run
too, stay in the heap for reuse. When the solve ends, its preconditioner, Jacobian and
vectors (about a gigabyte at 4e6 dofs) are such free heap, which the outputs stage reuses
only in part: ``malloc_trim(0)`` there took the peak of a nested run at 4e6 dofs from 3.99
to 3.86 GiB (the peak is then the solve's).

Only there: trimming between the compute stages (after the mesh, a preconditioner's
set-up, a solve) lowered that peak further, to 3.78 GiB, but made the later stages
slower, the prolongation 3.2-4.4 s against 1.9 s and the finest preconditioner 9.0-11.3 s
against 7.5-7.7 s in interleaved runs (memory given back is faulted in again, and loses
its transparent huge pages): docs/design/speed.md.
"""
from __future__ import annotations

import ctypes
import ctypes.util
import functools

__all__ = ["release_free_memory"]


@functools.lru_cache(maxsize=1)
def _malloc_trim():
    """glibc's ``malloc_trim``, or None on a C library without it."""
    name = ctypes.util.find_library("c")
    try:
        return ctypes.CDLL(name).malloc_trim if name else None
    except (OSError, AttributeError):
        return None


def release_free_memory() -> None:
    """Return the free pages of every heap arena to the operating system (glibc's
    ``malloc_trim(0)``; nothing elsewhere). Rank-local; about 50 ms per GB given back."""
    trim = _malloc_trim()
    if trim is not None:
        trim(0)
