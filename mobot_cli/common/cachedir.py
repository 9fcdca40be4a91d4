"""Where mobot's cache folder is: a module of its own, light enough for the entry point to use
before anything else is imported (common/classcode.py)."""

from __future__ import annotations

import os
from pathlib import Path


def cache_dir() -> Path:
    """mobot's cache folder: $MOBOT_CACHE_DIR, else $XDG_CACHE_HOME/mobot, else ~/.cache/mobot."""
    explicit = os.environ.get("MOBOT_CACHE_DIR")
    if explicit:
        return Path(explicit).expanduser()
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg).expanduser() if xdg else Path.home() / ".cache") / "mobot"
