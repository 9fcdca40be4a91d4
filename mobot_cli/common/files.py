"""Atomic file writes: a reader (or a killed writer) never sees half a file.

Each write goes to a uniquely named temporary sibling, is flushed to disk and renamed over
the target, so parallel writers of the same file (sweep workers filling one cache) never
mix their bytes, and a file that exists is whole. A run folder's files other than
summary.json skip the flush to disk (``durable=False``): the rename alone keeps them whole
when a process is killed, and an fsync per file would slow every run.
"""

from __future__ import annotations

import errno
import math
import os
from pathlib import Path
from typing import Any

from mobot_cli.errors import OutputError, cannot_write


def write_bytes_atomic(path: Path, data: bytes, durable: bool = True) -> None:
    """Write bytes to a temporary sibling, flush it to disk (``durable``) and rename it into place."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{os.urandom(4).hex()}.tmp")
    # os.open with 0o666 (not mkstemp's 0o600): the file gets the permissions the umask gives.
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o666)
    try:
        with os.fdopen(fd, "wb") as out:
            out.write(data)
            if durable:
                out.flush()
                os.fsync(out.fileno())
        os.replace(tmp, path)
    except OSError as exc:
        try:
            tmp.unlink(missing_ok=True)  # never leave half a file behind (a full disk)
        except OSError:
            pass
        exc.filename = str(path)  # the file the user knows, not its temporary sibling
        raise
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_text_atomic(path: Path, text: str, durable: bool = True) -> None:
    """Write UTF-8 text atomically (newlines as given: files compare byte for byte)."""
    write_bytes_atomic(path, text.encode("utf-8"), durable)


def write_json_atomic(path: Path, data: Any) -> None:
    """Write JSON atomically: indented by 2, a trailing newline, NaN and infinity refused."""
    import json  # not before a run's loop, which writes none

    write_text_atomic(path, json.dumps(data, indent=2, allow_nan=False, default=json_default) + "\n")


def json_default(value: Any) -> Any:
    """The JSON form of what json cannot write itself (paths, enums...): its str()."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return str(value)


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
