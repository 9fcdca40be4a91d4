"""What a process forked from mobot (not a new program) does first."""

from __future__ import annotations

import os


def close_fds_but(keep: set[int]) -> None:
    """Close every file descriptor but ``keep``, as spawning a new program with those passed would."""
    low = 0
    for fd in sorted(keep) + [os.sysconf("SC_OPEN_MAX")]:
        if low < fd:  # an empty range is skipped: closerange(0, 0) closes them all (0 - 1 wraps around)
            os.closerange(low, fd)
        low = fd + 1
