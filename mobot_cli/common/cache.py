"""mobot's cache folder, and a small on-disk cache of JSON documents keyed by content hashes.

The folder must be private: created 0700 by mobot, or owned by this user with no group or other
write, and every parent owned by this user or root and writable by others only when sticky
(/tmp). Otherwise caching is off for the process, with one warning. Inside it, no link is ever
followed, only regular files are read (a FIFO is a miss, never a hang), entries carry their key
and the hash of their body, files are written atomically, cleanup unlinks only regular files
inside it, and every fault is a miss: a cache only ever costs time (docs/security.md).
"""

from __future__ import annotations

import contextlib
import errno
import functools
import hashlib
import json
import os
import stat
from pathlib import Path
from typing import Any

from mobot_cli.common.files import write_bytes_atomic

# Bump when the layout of a cached document changes, so old entries are simply missed.
CACHE_FORMAT = 3
_PACKAGE = Path(__file__).resolve().parent.parent  # mobot_cli/
# The code that builds cached documents (asset loading, the plan types it fills, this folder)
# and the version number; paths, not imports: the cache sits below all of them.
# sim/drive.py: drive detection takes its skid-steer multiplier from there.
_BUILDERS = ("__init__.py", "common", "assets", "plan.py", "sim/drive.py")


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


def root() -> Path | None:
    """The cache folder when it is private (created 0700 or verified), else None: caching is off."""
    return _checked(os.path.abspath(cache_dir()))[0]


def warning() -> str | None:
    """Why caching is off (the one notice a command prints), or None when it is on."""
    return _checked(os.path.abspath(cache_dir()))[1]


@functools.lru_cache(maxsize=8)
def _checked(path: str) -> tuple[Path | None, str | None]:
    # Once per process and folder: a user who can write the folder (or rename it or a parent)
    # could feed us forged entries or plant links, so such a folder is not used at all.
    try:
        problem = _private(Path(path))
    except OSError as exc:
        problem = f"cannot use it: {exc.strerror or exc}"
    if problem is None:
        return Path(path), None
    return None, (f"the cache folder {path} {problem}; caching is off (runs only take longer). "
                  "Set MOBOT_CACHE_DIR to a folder only you can write.")


def _private(path: Path) -> str | None:
    """Create ``path`` (0700) if missing; why only this user could not be its sole writer, or None."""
    me = os.geteuid()
    try:
        info = os.lstat(path)
    except FileNotFoundError:
        os.makedirs(path.parent, exist_ok=True)
        with contextlib.suppress(FileExistsError):
            os.mkdir(path, 0o700)
        info = os.lstat(path)
    if stat.S_ISLNK(info.st_mode):
        return "is a symbolic link (mobot never follows links in its cache)"
    if not stat.S_ISDIR(info.st_mode):
        return "is not a folder"
    if info.st_uid != me:
        return f"belongs to another user (uid {info.st_uid})"
    if info.st_mode & 0o022:
        return f"is writable by other users (mode {stat.S_IMODE(info.st_mode):04o})"
    parent = Path(os.path.realpath(path.parent))
    while True:
        up = os.stat(parent)
        if up.st_uid not in (me, 0):
            return f"lies in {parent}, which belongs to another user (uid {up.st_uid})"
        if up.st_mode & 0o022 and not up.st_mode & stat.S_ISVTX:
            return f"lies in {parent}, which other users can write (mode {stat.S_IMODE(up.st_mode):04o})"
        if parent.parent == parent:
            return None
        parent = parent.parent


def _folder(kind: str) -> Path | None:
    """A kind's subfolder of the private cache, created 0700; None when unusable (a miss)."""
    base = root()
    if base is None:
        return None
    folder = base / kind
    try:
        with contextlib.suppress(FileExistsError):
            os.mkdir(folder, 0o700)
        info = os.lstat(folder)
    except OSError:
        return None
    if not stat.S_ISDIR(info.st_mode) or info.st_uid != os.geteuid() or info.st_mode & 0o022:
        return None  # a link, a file or someone else's folder where ours should be
    return folder


def _read(path: Path, limit: int | None = None) -> bytes | None:
    """A regular file's bytes, never through a link and never blocking (a FIFO is a miss)."""
    limit = CACHE_MAX_BYTES if limit is None else limit
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError:
        return None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode) or info.st_uid != os.geteuid() or info.st_size > limit:
            return None
        chunks, total = [], 0
        while chunk := os.read(fd, 1 << 20):
            chunks.append(chunk)
            total += len(chunk)
            if total > limit:
                return None
        return b"".join(chunks)
    except OSError:
        return None
    finally:
        os.close(fd)


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
    """The cached document, or None when absent, unreadable, damaged or forged (never an error)."""
    folder = _folder(kind)
    data = None if folder is None else _read(folder / f"{key}.json")
    if data is None:
        return None
    header, _, body = data.partition(b"\n")
    # The header names the key and the body's hash: an entry copied under another name, cut
    # short or edited is a miss, whatever its JSON says.
    if header != f"mobot-cache {key} {hashlib.sha256(body).hexdigest()}".encode():
        return None
    try:
        document = json.loads(body)
    except ValueError:
        return None
    if kind in BOUNDED_KINDS:
        touch(folder / f"{key}.json")  # type: ignore[operator]
    return document


def store(kind: str, key: str, document: Any) -> None:
    """Write the document atomically; a read-only, full or missing cache only costs time."""
    folder = _folder(kind)
    if folder is None:
        return
    try:
        body = json.dumps(document, allow_nan=False).encode("utf-8")
        header = f"mobot-cache {key} {hashlib.sha256(body).hexdigest()}\n".encode()
        write_bytes_atomic(folder / f"{key}.json", header + body)
        if kind in BOUNDED_KINDS:
            prune(folder)
    except (OSError, ValueError, TypeError):
        pass


def load_file(kind: str, name: str, sha256: str) -> Path | None:
    """A cached file whose bytes hash to ``sha256`` (a hex prefix of 32 digits or more), else None."""
    folder = _folder(kind)
    data = None if folder is None else _read(folder / name)
    if data is None or hashlib.sha256(data).hexdigest()[:len(sha256)] != sha256:
        return None
    touch(folder / name)  # type: ignore[operator]
    return folder / name  # type: ignore[operator]


def store_file(kind: str, name: str, data: bytes, bounded: bool = False) -> Path:
    """Write a file another library opens by path (PyBullet): into the cache or, when the cache
    is off or faulty, into a private folder of this process that is removed at exit."""
    for folder in (_folder(kind), _scratch(kind)):
        if folder is None:
            continue
        try:
            write_bytes_atomic(folder / name, data)
        except OSError:
            continue
        if bounded:
            prune(folder)
        return folder / name
    raise OSError(errno.EACCES, f"cannot write {name} to the cache or to a temporary folder")


@functools.lru_cache(maxsize=None)
def _scratch(kind: str) -> Path | None:
    import atexit
    import shutil
    import tempfile

    try:
        folder = Path(tempfile.mkdtemp(prefix=f"mobot-{kind}-"))  # 0700, ours
    except OSError:
        return None
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    return folder


def touch(path: Path) -> None:
    """Mark a cache file as just used (pruning keeps the most recently used); never through a link."""
    try:
        os.utime(path, follow_symlinks=False)
    except (OSError, NotImplementedError):
        pass


def prune(folder: Path, max_files: int | None = None, max_bytes: int | None = None) -> int:
    """Delete a cache folder's least recently used files beyond the limits; returns how many went.

    The newest file always stays (it was just written for use). Files being written (.tmp) are left alone.
    """
    max_files = CACHE_MAX_FILES if max_files is None else max_files
    max_bytes = CACHE_MAX_BYTES if max_bytes is None else max_bytes
    # Through a descriptor of the folder itself (never of a link to it), unlinking only regular
    # files that lstat finds there: cleanup cannot reach outside the cache.
    try:
        fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW | os.O_CLOEXEC)
    except OSError:
        return 0
    try:
        entries = []
        with os.scandir(fd) as scan:
            for entry in scan:
                if entry.name.endswith(".tmp") or not entry.is_file(follow_symlinks=False):
                    continue
                try:
                    info = entry.stat(follow_symlinks=False)
                except OSError:
                    continue
                entries.append((info.st_mtime_ns, info.st_size, entry.name))
        entries.sort(reverse=True)
        kept, removed = 0, 0
        for index, (_, size, name) in enumerate(entries):
            kept += size
            if index > 0 and (index >= max_files or kept > max_bytes):
                with contextlib.suppress(OSError):
                    os.unlink(name, dir_fd=fd)
                    removed += 1
        return removed
    except OSError:
        return 0
    finally:
        os.close(fd)
