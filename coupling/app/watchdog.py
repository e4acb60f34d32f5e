"""A run ends on SIGINT or SIGTERM within seconds, wherever it is.

Python runs a signal handler only when the interpreter regains control, so a run inside
native code (an OpenBLAS allocation loop, a long PETSc or C++ call) ignores the
interrupt. :class:`SignalWatchdog` starts a small helper process before the run. The
C-level handler Python installs writes the signal number into a pipe
(``signal.set_wakeup_fd``) even while the interpreter is stuck; the helper reads it,
and when the run has not ended ``grace`` seconds later it does what the run's own
handler would have done: prints the interrupt line (unless the run printed it, or
another rank claimed the staging folder), removes the staging folder, and sends the
signal again. The run's handlers are installed with SA_RESETHAND, so that second
signal meets the default action and the process ends with the shell's usual code
(128 + the signal number); if the run ignores it (its own handler ran and is cleaning
up, but stalls) it is killed after one more ``grace``.

The run tells the helper its staging folder and that it has reported the interrupt
over a second pipe; the helper ends when that pipe closes (the run has ended).
"""
from __future__ import annotations

import os
import select
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

from fem_py.signals import sigaction

__all__ = ["SignalWatchdog", "WATCHDOG_GRACE_SECONDS"]

#: seconds a run has to end by itself after SIGINT/SIGTERM before the helper ends it
WATCHDOG_GRACE_SECONDS = 3.0
_SA_RESETHAND = 0x80000000


def _reset_after_first(signums: tuple[int, ...]) -> bool:
    """Add SA_RESETHAND to the installed action of each signal (the kernel restores the
    default action once the handler has been entered); False where libc does not allow
    it (the helper then kills with SIGKILL)."""
    for s in signums:
        act = sigaction(s)
        if act is None:
            return False
        act.flags |= _SA_RESETHAND
        if sigaction(s, act) is None:
            return False
    return True


class SignalWatchdog:
    """The helper of one command (a context manager, entered after the signal handlers
    are installed). ``lines``: the interrupt line for each signal; ``rank``: the MPI rank
    (the helper of rank 0 reports an interrupt before a staging folder exists)."""

    def __init__(
        self, lines: dict[int, str], rank: int, grace: float = WATCHDOG_GRACE_SECONDS
    ) -> None:
        self.lines, self.rank, self.grace = lines, rank, grace
        self._proc: subprocess.Popen | None = None
        self._control = -1
        self._wake_w = -1
        self._previous_wakeup = -1

    def __enter__(self) -> SignalWatchdog:
        wake_r, self._wake_w = os.pipe()
        control_r, self._control = os.pipe()
        os.set_blocking(self._wake_w, False)
        resets = _reset_after_first(tuple(self.lines))
        args = [str(os.getpid()), str(self.grace), str(self.rank), str(int(resets))]
        for s, line in self.lines.items():
            args += [str(int(s)), line]
        self._proc = subprocess.Popen(
            [sys.executable, "-c", "from coupling.app.watchdog import _helper; _helper()", *args],
            stdin=wake_r,
            stdout=subprocess.DEVNULL,
            pass_fds=(control_r,),
            env={**os.environ, "FEMBEM_WATCHDOG_CONTROL": str(control_r)},
            start_new_session=True,  # a Ctrl-C to the terminal's group is not for it
        )
        os.close(wake_r)
        os.close(control_r)
        self._previous_wakeup = signal.set_wakeup_fd(self._wake_w, warn_on_full_buffer=False)
        return self

    def _tell(self, message: str) -> None:
        try:
            os.write(self._control, message.encode() + b"\n")
        except OSError:
            pass

    def staging(self, path: Path) -> None:
        """The run's staging folder: removed by the helper if it has to end the run."""
        self._tell(f"S{path}")

    def reported(self) -> None:
        """The run has printed its interrupt line."""
        self._tell("R")

    def __exit__(self, *exc) -> None:
        signal.set_wakeup_fd(self._previous_wakeup)
        for fd in (self._control, self._wake_w):
            os.close(fd)
        if self._proc is not None:
            self._proc.wait()


class _Control:
    """The helper's end of the control pipe: the staging folder, whether the run has
    reported, and whether the pipe is still open (the run alive)."""

    def __init__(self, fd: int) -> None:
        self.fd, self.staging, self.reported, self.open, self._pending = fd, None, False, True, b""

    def read(self) -> None:
        data = os.read(self.fd, 4096)
        self.open = bool(data)
        *messages, self._pending = (self._pending + data).split(b"\n")
        for m in messages:
            if m.startswith(b"S"):
                self.staging = Path(m[1:].decode())
            elif m == b"R":
                self.reported = True

    def wait(self, seconds: float) -> None:
        """Read messages for up to ``seconds``, or until the pipe closes."""
        deadline = time.monotonic() + seconds
        while self.open and (left := deadline - time.monotonic()) > 0:
            if select.select([self.fd], [], [], left)[0]:
                self.read()


def _helper() -> None:
    """The helper process: argv = pid, grace, rank, resets, then (signal, line) pairs;
    stdin the wakeup pipe, FEMBEM_WATCHDOG_CONTROL the control pipe."""
    pid, grace, rank, resets = sys.argv[1:5]
    pid, grace, rank, resets = int(pid), float(grace), int(rank), resets == "1"
    rest = sys.argv[5:]
    lines = {int(rest[i]): rest[i + 1] for i in range(0, len(rest), 2)}
    wake = sys.stdin.fileno()
    control = _Control(int(os.environ["FEMBEM_WATCHDOG_CONTROL"]))
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    while control.open:
        ready, _, _ = select.select([wake, control.fd], [], [])
        if control.fd in ready:
            control.read()
        if wake in ready:
            got = [s for s in os.read(wake, 64) if s in lines]
            if not got:
                continue
            control.wait(grace)
            if control.open:  # the run is stuck: end it
                _end_run(pid, got[0], lines[got[0]], control, rank, resets, grace)
            return


def _claim(staging: Path) -> bool:
    """``coupling.io.atomic.claim`` without starting MPI in this process."""
    import mpi4py

    mpi4py.rc.initialize = mpi4py.rc.finalize = False
    from coupling.io.atomic import claim

    return claim(staging)


def _end_run(
    pid: int, signum: int, line: str, control: _Control, rank: int, resets: bool, grace: float
) -> None:
    """Do what a stuck run's handler cannot: report once, remove the staging folder,
    end the process (the signal again, then SIGKILL)."""
    staging = control.staging
    if not control.reported and (_claim(staging) if staging is not None else rank == 0):
        print(f"fembem: {line}", file=sys.stderr, flush=True)
    if staging is not None:
        shutil.rmtree(staging, ignore_errors=True)
    try:
        if resets:
            os.kill(pid, signum)
            control.wait(grace)
            if not control.open:
                return
        os.kill(pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
