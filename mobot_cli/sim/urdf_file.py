"""URDF text to a file PyBullet can load, and the few URDF facts the simulation needs."""

from __future__ import annotations

import contextlib
import hashlib
import os
import sys
import xml.etree.ElementTree as ET
from pathlib import Path


# Cache folders that grow with every distinct robot text (urdf/, spawned/, xacro/, robot/) keep
# at most this many files and bytes each; the least recently used go first (README, Security).
CACHE_MAX_FILES = 1024
CACHE_MAX_BYTES = 256 * 1024 * 1024


def cache_dir() -> Path:
    """mobot's cache folder: $MOBOT_CACHE_DIR, else $XDG_CACHE_HOME/mobot, else ~/.cache/mobot."""
    explicit = os.environ.get("MOBOT_CACHE_DIR")
    if explicit:
        return Path(explicit).expanduser()
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg).expanduser() if xdg else Path.home() / ".cache") / "mobot"


def urdf_path(text: str, folder: str = "urdf") -> Path:
    """A file holding ``text``, named by its content hash, written once and atomically.

    The folder is bounded (``prune``): every distinct text a live client sends makes a file.
    """
    digest = hashlib.sha256(text.encode("utf-8")).hexdigest()[:32]
    path = cache_dir() / folder / f"{digest}.urdf"
    if path.is_file():
        touch(path)
        return path
    path.parent.mkdir(parents=True, exist_ok=True)
    # Parallel sweep workers may write the same file: write aside, then rename.
    tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, path)
    prune(path.parent)
    return path


def touch(path: Path) -> None:
    """Mark a cache file as just used (pruning keeps the most recently used)."""
    try:
        os.utime(path)
    except OSError:
        pass


def prune(folder: Path, max_files: int | None = None, max_bytes: int | None = None) -> int:
    """Delete a cache folder's least recently used files beyond the limits; returns how many went.

    The newest file always stays (it was just written for use). Files being written (.tmp) are left alone.
    """
    max_files = CACHE_MAX_FILES if max_files is None else max_files
    max_bytes = CACHE_MAX_BYTES if max_bytes is None else max_bytes
    entries = []
    try:
        with os.scandir(folder) as scan:
            for entry in scan:
                if entry.name.endswith(".tmp") or not entry.is_file(follow_symlinks=False):
                    continue
                try:
                    info = entry.stat(follow_symlinks=False)
                except OSError:
                    continue
                entries.append((info.st_mtime_ns, info.st_size, entry.path))
    except OSError:
        return 0
    entries.sort(reverse=True)
    kept, removed = 0, 0
    for index, (_, size, name) in enumerate(entries):
        kept += size
        if index > 0 and (index >= max_files or kept > max_bytes):
            with contextlib.suppress(OSError):
                os.unlink(name)
                removed += 1
    return removed


def links_with_friction(text: str) -> frozenset[str]:
    """Names of links whose URDF sets ``<contact><lateral_friction>`` (their author chose it)."""
    root = ET.fromstring(text)
    return frozenset(
        link.get("name", "")
        for link in root.findall("link")
        if link.find("contact/lateral_friction") is not None
    )


@contextlib.contextmanager
def quiet_stdout():
    """Silence C-level prints (PyBullet's URDF importer writes to fd 1) for the duration."""
    try:
        sys.stdout.flush()
        saved = os.dup(1)
    except (OSError, ValueError):  # no real fd 1 (embedded interpreters): nothing to protect
        yield
        return
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)
