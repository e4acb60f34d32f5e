"""fem_py.memory: freed heap memory goes back to the operating system."""
from __future__ import annotations

from fem_py.memory import release_free_memory


def _resident_mib() -> float:
    with open("/proc/self/status") as status:
        line = next(line for line in status if line.startswith("VmRSS:"))
    return int(line.split()[1]) / 1024


def test_freed_heap_blocks_are_returned():
    # 256 MiB in blocks below glibc's mmap threshold (from the heap), the last one kept so
    # that the free space is not at the heap's top (which glibc trims by itself)
    blocks = [bytearray(64 * 1024) for _ in range(4096)]
    keep = blocks.pop()
    del blocks
    before = _resident_mib()
    release_free_memory()
    after = _resident_mib()
    assert before - after > 128, (before, after)  # most of the 256 MiB
    assert len(keep) == 64 * 1024
