"""The unit of a COLLADA mesh, which trimesh ignores and PyBullet applies.

A wheel exported in millimetres (Rover Robotics' ``pro_tire.dae``: ``<unit meter="0.001"/>``)
collides in PyBullet at its true size, but trimesh reads its vertices as metres: a tyre of
radius 127 m. Measurements mobot takes from a mesh (a wheel's radius, the footprint) scale by
this unit.
"""

from __future__ import annotations

import re

# <asset> comes first in a COLLADA file: its <unit> is within the first few kB.
_HEAD_BYTES = 65536
_UNIT = re.compile(rb"<unit\b[^>]*\bmeter\s*=\s*[\"']([^\"']+)[\"']")


def metres_per_unit(path: str) -> float:
    """The metres per unit of a .dae file's <unit meter=...>; 1 for other files, or when absent
    or unreadable."""
    if not path.lower().endswith(".dae"):
        return 1.0
    try:
        with open(path, "rb") as handle:
            head = handle.read(_HEAD_BYTES)
    except OSError:
        return 1.0
    found = _UNIT.search(head)
    try:
        meter = float(found.group(1)) if found else 1.0
    except ValueError:
        return 1.0
    return meter if 0.0 < meter < float("inf") else 1.0
