"""`fembem` with an exception injected on one rank (tests/test_user_defects_errors.py):
argv[1] the rank that fails, argv[2] where ("solve": at the start of the solve, when
the other ranks go on into collective calls; "setup": before the mesh is built) and
argv[3] the exception ("runtime" or "value"); argv[4:] the command line."""
import sys

from mpi4py import MPI

import coupling.app.from_config as from_config
import coupling.app.run as run
from coupling.app.cli import main

rank, where, kind = int(sys.argv[1]), sys.argv[2], sys.argv[3]
module, name = (run, "run_solver") if where == "solve" else (from_config, "domain_from_config")
original = getattr(module, name)


def failing(*args, **kwargs):
    if MPI.COMM_WORLD.rank == rank:
        raise {"runtime": RuntimeError, "value": ValueError}[kind](f"injected on rank {rank}")
    return original(*args, **kwargs)


setattr(module, name, failing)
sys.exit(main(sys.argv[4:]))
