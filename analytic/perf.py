"""Process-level performance settings (opt-in).

The solver works on arrays of a few hundred kB per quantity (3600 inputs x bodies,
complex).  glibc serves allocations above its mmap threshold (128 kB by default,
adapted upwards only after a free) with fresh ``mmap`` pages and returns them on
free, so every call pays page faults to zero them again.  Measured on the
3600-point four-bar sweep with forces: 0.62-0.80 M/s with the default allocator,
1.1 M/s with the thresholds raised (``benchmarks/bench_solver.py`` prints both).
"""

from __future__ import annotations

import ctypes

# glibc mallopt parameters (malloc.h)
_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3


def tune_allocator(mmap_threshold: int = 64 << 20, trim_threshold: int = 128 << 20) -> bool:
    """Raise glibc's mmap and trim thresholds for this process so large temporary
    arrays are recycled from the heap instead of being mapped and unmapped.

    Affects the whole process (every library in it); the ``xval`` command and the
    benchmark call it, library users may.  Returns False where the C library has no
    ``mallopt`` (not glibc): nothing is changed there.
    """
    try:
        # the process's own symbols (the C library it runs on): find_library("c") would
        # run ldconfig or a compiler, 50-100 ms
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError, TypeError):
        return False
    mallopt.argtypes = [ctypes.c_int, ctypes.c_int]
    ok = mallopt(_M_MMAP_THRESHOLD, int(mmap_threshold)) == 1
    ok &= mallopt(_M_TRIM_THRESHOLD, int(trim_threshold)) == 1
    return bool(ok)
