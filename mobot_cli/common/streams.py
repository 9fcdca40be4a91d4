"""C code that writes to file descriptor 1 or 2 itself (PyBullet's banner and URDF importer, Ray's
core logging), silenced for a block: Python's own streams never see those writes."""

from __future__ import annotations

import contextlib
import os
import sys
from typing import Iterator


@contextlib.contextmanager
def silenced(fd: int) -> Iterator[None]:
    """Point ``fd`` (1 or 2) at /dev/null for the block, then back where it was."""
    stream = sys.stdout if fd == 1 else sys.stderr
    try:
        if stream is not None:
            stream.flush()  # what Python wrote before the block still goes out
        saved = os.dup(fd)
    except (OSError, ValueError):  # no real descriptor (an embedded interpreter): nothing to protect
        yield
        return
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), fd)
        yield
    finally:
        os.dup2(saved, fd)
        os.close(saved)
