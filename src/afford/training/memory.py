"""Keep freed memory in the process: a training step's large tensors come back every step.

glibc's malloc serves large blocks with mmap and hands them back to the system on free, so
each step's activations are page-faulted and zeroed afresh by the kernel: measured on our
2-core machines, about a fifth of a prediction training step went to system time this way.
With mmap off and a high trim threshold, freed blocks stay in the heap and are reused.
Elsewhere than glibc this does nothing.
"""

from __future__ import annotations

import ctypes
import ctypes.util

# mallopt parameters (glibc's malloc.h)
M_TRIM_THRESHOLD, M_TOP_PAD, M_MMAP_MAX = -1, -2, -4
TRIM_THRESHOLD = 2**31 - 1  # bytes: never give the heap's top back
TOP_PAD = 256 * 2**20  # bytes: grow the heap in large steps


def keep_freed_memory() -> bool:
    """Tune glibc's malloc for repeated large allocations; True where it applied."""
    name = ctypes.util.find_library("c")
    if name is None:
        return False
    try:
        libc = ctypes.CDLL(name)
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return False
    return all(
        mallopt(param, value) == 1
        for param, value in ((M_MMAP_MAX, 0), (M_TRIM_THRESHOLD, TRIM_THRESHOLD), (M_TOP_PAD, TOP_PAD))
    )
