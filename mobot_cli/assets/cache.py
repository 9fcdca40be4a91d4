"""A small on-disk cache of JSON documents keyed by content hashes, written atomically."""

from __future__ import annotations

import functools
import hashlib
import json
import os
import tempfile
from pathlib import Path
from typing import Any

import mobot_cli
from mobot_cli.sim.urdf_file import cache_dir, prune, touch  # one rule for the whole cache folder

# Bump when the layout of a cached document changes, so old entries are simply missed.
CACHE_FORMAT = 1
# Kinds with one entry per distinct robot text (which live clients choose): bounded by prune().
BOUNDED_KINDS = ("xacro", "robot")


@functools.lru_cache(maxsize=1)
def _code_version() -> str:
    # The code that builds cached results is part of every key, so an edited checkout (an
    # editable install keeps its version number) never reads entries an older build wrote.
    sha = hashlib.sha256(f"mobot {mobot_cli.__version__} cache {CACHE_FORMAT}".encode())
    package = Path(__file__).resolve().parent
    for source in sorted([*package.glob("*.py"), package.parent / "sim" / "plan.py"]):
        try:
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
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=f".{key}.", suffix=".tmp")
        try:
            with os.fdopen(fd, "w", encoding="utf-8") as out:
                json.dump(document, out)
            os.replace(tmp, folder / f"{key}.json")
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
        if kind in BOUNDED_KINDS:
            prune(folder)
    except OSError:
        pass
