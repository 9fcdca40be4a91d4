"""Memory a process will need soon, made ready while it has nothing else to do.

A process touching fresh memory pays a page fault per 4 KiB page: ~10 ms for the ~35 MB a
picture is drawn in (plot/render.py). glibc makes it worse for a first picture: a block that
large is mapped anew for each allocation and returned when freed, until its threshold has
adapted, so the first two pictures of a process take ~1.6 times as long as the next ones.

``reserve`` fixes glibc's two thresholds so that freed memory stays in the process's heap, and
faults in ``size`` bytes of it now: what is allocated next reuses those pages. Elsewhere than
glibc (no ``mallopt``) it does nothing. It is meant for a short-lived process with idle time
ahead of known work (the run's helper, run/ahead.py), not for a long-lived one: memory it frees
is never given back to the system.
"""

from __future__ import annotations

M_TRIM_THRESHOLD = -1  # glibc's malloc.h: free memory at the heap's top above this is given back
M_MMAP_THRESHOLD = -3  # blocks of at least this size are mapped on their own
MAPPED_ABOVE = 32 << 20  # glibc's largest accepted everywhere on 64 bits; a picture's canvas is 17 MB
KEEP = 1 << 30  # free memory at the top up to 1 GiB stays in the heap
PIECE = 1 << 20


def reserve(size: int) -> bool:
    """Keep freed memory in the heap and touch ``size`` bytes of it now; False where it cannot."""
    try:
        import ctypes

        mallopt = ctypes.CDLL(None).mallopt
    except (ImportError, OSError, AttributeError):  # no ctypes, no C library, not glibc
        return False
    mallopt.argtypes = (ctypes.c_int, ctypes.c_int)
    if not (mallopt(M_MMAP_THRESHOLD, MAPPED_ABOVE) and mallopt(M_TRIM_THRESHOLD, KEEP)):
        return False
    # Zero-filled, so every page is faulted in; in pieces below the threshold, so they come from
    # the heap, and freed together they leave one free stretch there for the next allocations.
    touched = [bytearray(PIECE) for _ in range(-(-size // PIECE))]
    del touched
    return True
