"""URDF text to a file PyBullet can load, and the few URDF facts the simulation needs."""

from __future__ import annotations

import contextlib
import hashlib
import os
import sys
import xml.etree.ElementTree as ET
from pathlib import Path


def cache_dir() -> Path:
    """mobot's cache folder: $MOBOT_CACHE_DIR, else $XDG_CACHE_HOME/mobot, else ~/.cache/mobot."""
    explicit = os.environ.get("MOBOT_CACHE_DIR")
    if explicit:
        return Path(explicit).expanduser()
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg).expanduser() if xdg else Path.home() / ".cache") / "mobot"


def urdf_path(text: str, folder: str = "urdf") -> Path:
    """A file holding ``text``, named by its content hash, written once and atomically."""
    digest = hashlib.sha256(text.encode("utf-8")).hexdigest()[:32]
    path = cache_dir() / folder / f"{digest}.urdf"
    if not path.is_file():
        path.parent.mkdir(parents=True, exist_ok=True)
        # Parallel sweep workers may write the same file: write aside, then rename.
        tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, path)
    return path


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
