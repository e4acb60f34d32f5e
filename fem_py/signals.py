"""The process's signal actions kept across a library that changes them.

gmsh's Python module sets SIGINT to the default action when it is imported (a Ctrl-C
then kills the process at once, with no message and no clean-up) and puts back, in
``gmsh.finalize``, the handler it found at import. :func:`kept_signal_actions` restores
both tables a signal's action lives in: Python's (``signal.signal``) and the kernel's
``sigaction``, whose flags the caller may have set (``coupling.app.watchdog`` adds
SA_RESETHAND, which ``signal.signal`` alone would drop).
"""
from __future__ import annotations

import ctypes
import signal
from contextlib import contextmanager
from typing import Iterator

__all__ = ["SigAction", "kept_signal_actions", "sigaction"]


class SigAction(ctypes.Structure):
    """glibc's struct sigaction (Linux): handler, mask (1024 bits), flags, restorer."""

    _fields_ = [
        ("handler", ctypes.c_void_p),
        ("mask", ctypes.c_ulong * 16),
        ("flags", ctypes.c_int),
        ("restorer", ctypes.c_void_p),
    ]


def sigaction(signum: int, new: SigAction | None = None) -> SigAction | None:
    """The installed action of ``signum`` (after installing ``new``, if given), or None
    where libc does not tell."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        old = SigAction()
        pointer = ctypes.byref(new) if new is not None else None
        if libc.sigaction(int(signum), pointer, ctypes.byref(old)) != 0:
            return None
        return old if new is None else new
    except (OSError, AttributeError):
        return None


@contextmanager
def kept_signal_actions(signums: tuple[int, ...] = (signal.SIGINT,)) -> Iterator[None]:
    """``with kept_signal_actions():`` the actions of ``signums`` on leaving are those on
    entering (Python's handler and the kernel's action with its flags)."""
    saved = [(s, signal.getsignal(s), sigaction(s)) for s in signums]
    try:
        yield
    finally:
        for s, handler, action in saved:
            if handler is not None:
                signal.signal(s, handler)
            if action is not None:
                sigaction(s, action)
