"""Freed memory given back to the operating system before a run's outputs.

glibc's allocator keeps the memory a process frees (small blocks, and, since its mmap
threshold rises with every large block freed, most arrays of a large run too) for reuse.
When the solve ends, its preconditioner, Jacobian and vectors are such free heap, which
the outputs stage reuses only in part; trimming the heap there lowers a large run's
peak. Only there: trimmed between the compute stages, the memory given back is faulted
in again and loses its transparent huge pages, and the later stages ran measurably
slower (docs/design/speed.md, "Issue 33, continued").
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
