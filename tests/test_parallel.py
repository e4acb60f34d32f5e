"""fem_py.parallel helpers on one rank: the thread count of a rank respects the user's
OMP_NUM_THREADS, and gathering to rank 0 returns the object itself (no pickled copy)."""
from __future__ import annotations

import os

import numpy as np
import pytest
from mpi4py import MPI

from fem_py.parallel import gather_to_root, threads_per_rank


@pytest.mark.parametrize("value,expected", [("1", 1), ("", None), ("abc", None), ("0", None)])
def test_threads_per_rank_respects_omp_num_threads(value, expected, monkeypatch):
    cores = len(os.sched_getaffinity(0))  # one rank: all cores of the node
    monkeypatch.setenv("OMP_NUM_THREADS", value)
    assert threads_per_rank(MPI.COMM_WORLD) == (cores if expected is None else expected)
    monkeypatch.setenv("OMP_NUM_THREADS", str(10 * cores))  # never more than the cores
    assert threads_per_rank(MPI.COMM_WORLD) == cores


def test_gather_to_root_on_one_rank_is_the_object():
    a = np.arange(5.0)
    gathered = gather_to_root(MPI.COMM_SELF, a)
    assert len(gathered) == 1 and gathered[0] is a
