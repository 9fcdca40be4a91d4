"""Where mobot's cache folder is, and how a file in it that holds code is read: a module of its
own, light enough for the entry point to use before anything else is imported
(common/classcode.py)."""

from __future__ import annotations

import os
import stat
from pathlib import Path


def cache_dir() -> Path:
    """mobot's cache folder: $MOBOT_CACHE_DIR, else $XDG_CACHE_HOME/mobot, else ~/.cache/mobot."""
    explicit = os.environ.get("MOBOT_CACHE_DIR")
    if explicit:
        return Path(explicit).expanduser()
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg).expanduser() if xdg else Path.home() / ".cache") / "mobot"


def read_own(path: Path) -> bytes | None:
    """The bytes of a cache file as one another program could have written: only a regular file
    (not a link) owned by this user and writable by no one else is read; None for anything else,
    or no file."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
    except OSError:  # none yet, a link
        return None
    with os.fdopen(fd, "rb") as handle:
        info = os.fstat(handle.fileno())
        if (not stat.S_ISREG(info.st_mode) or info.st_mode & (stat.S_IWGRP | stat.S_IWOTH)
                or (hasattr(os, "getuid") and info.st_uid != os.getuid())):
            return None
        return handle.read()
