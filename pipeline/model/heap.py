"""The process's heap: freed pages handed back to the operating system where large frames were let go."""

from __future__ import annotations

import ctypes


def release_free_memory() -> None:
    """Give the heap pages freed so far back to the operating system (glibc's malloc_trim; nothing on
    other C libraries): the chunks' freed columns would otherwise stay counted in the process's memory."""
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        pass
