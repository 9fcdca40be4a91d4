"""mobot's cache folder, and a small on-disk cache of JSON documents keyed by content hashes."""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import os
from pathlib import Path
from typing import Any

from mobot_cli.common.files import write_text_atomic

# Bump when the layout of a cached document changes, so old entries are simply missed.
CACHE_FORMAT = 2
_PACKAGE = Path(__file__).resolve().parent.parent  # mobot_cli/
# The code that builds cached documents (asset loading, the plan types it fills, this folder)
# and the version number; paths, not imports: the cache sits below all of them.
_BUILDERS = ("__init__.py", "common", "assets", "sim/plan.py")


# Kinds with one entry per distinct robot text (which live clients choose): bounded by prune().
BOUNDED_KINDS = ("xacro", "robot")
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


@functools.lru_cache(maxsize=1)
def _code_version() -> str:
    # The code that builds cached results is part of every key, so an edited checkout (an
    # editable install keeps its version number) never reads entries an older build wrote.
    sha = hashlib.sha256(f"mobot cache {CACHE_FORMAT}".encode())
    sources = [p for name in _BUILDERS
               for p in ([_PACKAGE / name] if name.endswith(".py") else (_PACKAGE / name).rglob("*.py"))]
    for source in sorted(sources):
        try:
            sha.update(str(source.relative_to(_PACKAGE)).encode())
            sha.update(source.read_bytes())
        except OSError:
            pass
    return sha.hexdigest()


def digest(*parts: str | bytes) -> str:
    """SHA-256 over the parts, each length-prefixed so ('ab','c') differs from ('a','bc')."""
    sha = hashlib.sha256(_code_version().encode())
    for part in parts:
        data = part.encode("utf-8") if isinstance(part, str) else part
        sha.update(len(data).to_bytes(8, "little"))
        sha.update(data)
    return sha.hexdigest()


def file_digest(path: Path) -> str | None:
    """SHA-256 of a file's bytes, or None when it cannot be read."""
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except OSError:
        return None


def load(kind: str, key: str) -> Any | None:
    """The cached document, or None when absent or unreadable (a cache never fails a run)."""
    path = cache_dir() / kind / f"{key}.json"
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if kind in BOUNDED_KINDS:
        touch(path)
    return document


def store(kind: str, key: str, document: Any) -> None:
    """Write the document atomically; a read-only or full disk only costs the cache."""
    folder = cache_dir() / kind
    try:
        folder.mkdir(parents=True, exist_ok=True)
        write_text_atomic(folder / f"{key}.json", json.dumps(document))
        if kind in BOUNDED_KINDS:
            prune(folder)
    except OSError:
        pass


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
