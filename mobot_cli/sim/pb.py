"""The one place pybullet is imported: its C module writes a build-time banner to stderr on
import, which would land in front of every error message and in scripts' logs."""

from __future__ import annotations

import os
import sys


def _import_quietly():
    sys.stderr.flush()
    saved, devnull = os.dup(2), os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, 2)
        import pybullet
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        os.close(devnull)
    return pybullet


p = _import_quietly()
