"""`fembem ARGS...` whose solve never returns from native code (tests/test_user_defects_signals.py):
at the start of the solve every rank prints "stuck" and locks a mutex it holds already,
so only a helper outside the interpreter can end it."""
import ctypes
import sys

import coupling.app.run as run
from coupling.app.cli import main


def stuck(*args, **kwargs):
    libc = ctypes.CDLL(None)
    mutex = ctypes.create_string_buffer(64)  # a default (non-recursive) pthread mutex
    libc.pthread_mutex_lock(mutex)
    print("stuck", flush=True)
    libc.pthread_mutex_lock(mutex)  # never returns; signals do not interrupt it


run.run_solver = stuck
sys.exit(main(sys.argv[1:]))
