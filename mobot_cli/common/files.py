"""Writing files so that a reader never sees half of one."""

from __future__ import annotations

import errno
import os
from pathlib import Path

from mobot_cli.errors import OutputError, cannot_write


def write_text_atomic(path: Path, text: str) -> None:
    """Write text to a temporary sibling, flush it to disk and rename it into place."""
    tmp = path.with_name(path.name + ".tmp")
    try:
        with tmp.open("w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except OSError as exc:
        try:
            tmp.unlink(missing_ok=True)  # never leave half a file behind (a full disk)
        except OSError:
            pass
        exc.filename = str(path)  # the file the user knows, not its temporary sibling
        raise


def check_out_folder(path: Path, flag: str = "--out") -> None:
    """Refuse an output folder that cannot be made or written, before any work starts.

    Nothing is created: a folder that does not exist yet is judged by its nearest existing
    parent. (Root may write where the mode bits say no; only a read-only mount stops it.)
    """
    try:
        if path.exists() and not path.is_dir():
            raise OutputError(f"{flag} {path} is a file", hint=f"Give {flag} a folder, new or existing.")
        existing = path
        while not existing.exists() and not existing.is_symlink() and existing != existing.parent:
            existing = existing.parent
    except OSError as exc:  # a name too long, a loop of links
        raise cannot_write(path, exc) from None
    if not existing.is_dir():
        raise OutputError(f"{flag} {path} cannot be made: {existing} is a file",
                          hint=f"Give {flag} a folder, new or existing.")
    if os.statvfs(existing).f_flag & os.ST_RDONLY:
        raise cannot_write(path, OSError(errno.EROFS, os.strerror(errno.EROFS)))
    if not os.access(existing, os.W_OK | os.X_OK):
        raise cannot_write(path, OSError(errno.EACCES, os.strerror(errno.EACCES)))
