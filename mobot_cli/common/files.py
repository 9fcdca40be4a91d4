"""Atomic file writes: a reader (or a killed writer) never sees half a file.

Each write goes to a uniquely named temporary sibling, is flushed to disk and renamed over
the target, so parallel writers of the same file (sweep workers filling one cache) never
mix their bytes, and a file that exists is whole.
"""

from __future__ import annotations

import json
import math
import os
import secrets
from pathlib import Path
from typing import Any


def write_bytes_atomic(path: Path, data: bytes) -> None:
    """Write bytes to a temporary sibling, flush it to disk and rename it into place."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp")
    # os.open with 0o666 (not mkstemp's 0o600): the file gets the permissions the umask gives.
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o666)
    try:
        with os.fdopen(fd, "wb") as out:
            out.write(data)
            out.flush()
            os.fsync(out.fileno())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_text_atomic(path: Path, text: str) -> None:
    """Write UTF-8 text atomically (newlines as given: files compare byte for byte)."""
    write_bytes_atomic(path, text.encode("utf-8"))


def write_json_atomic(path: Path, data: Any) -> None:
    """Write JSON atomically: indented by 2, a trailing newline, NaN and infinity refused."""
    write_text_atomic(path, json.dumps(data, indent=2, allow_nan=False, default=json_default) + "\n")


def json_default(value: Any) -> Any:
    """The JSON form of what json cannot write itself (paths, enums...): its str()."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return str(value)
