"""URDF text to a file PyBullet can load, and the few URDF facts the simulation needs.

A `mobot run`'s helper process works both out for the run's robots while the run imports the
engine (``facts``, run/ahead.py) and the run takes them (``known``): it then neither hashes nor
parses a URDF, nor imports what that takes (~6 ms of its start).
"""

from __future__ import annotations

import contextlib
import os
import sys
from pathlib import Path

_known: dict[str, tuple[Path, frozenset[str]]] = {}  # URDF text -> its file and links_with_friction


def facts(texts) -> dict[str, tuple[Path, frozenset[str]]]:
    """``urdf_path`` and ``links_with_friction`` of each text (its file written now), for another
    process to take with ``known``; a text that does not parse, or whose file cannot be written,
    is left to that process, which reports it where the robot is spawned, as without a helper."""
    found = {}
    for text in texts:
        try:
            found[text] = (urdf_path(text), links_with_friction(text))
        except Exception:  # noqa: BLE001 - whatever it is, the run meets it again and says so
            pass
    return found


def known(found: dict[str, tuple[Path, frozenset[str]]]) -> None:
    """Take the facts another process worked out (``facts``): this one need not work them out."""
    _known.update(found)


def urdf_path(text: str, folder: str = "urdf") -> Path:
    """A file holding ``text``, named by its content hash, written once and atomically.

    The folder is bounded (``prune``): every distinct text a live client sends makes a file.
    """
    if folder == "urdf" and text in _known and _known[text][0].is_file():
        return _known[text][0]
    import hashlib

    from mobot_cli.common.cache import cache_dir, prune, touch
    from mobot_cli.common.files import write_text_atomic

    digest = hashlib.sha256(text.encode("utf-8")).hexdigest()[:32]
    path = cache_dir() / folder / f"{digest}.urdf"
    if path.is_file():
        touch(path)
        return path
    path.parent.mkdir(parents=True, exist_ok=True)
    write_text_atomic(path, text)  # parallel sweep workers may write the same file
    prune(path.parent)
    return path


def links_with_friction(text: str) -> frozenset[str]:
    """Names of links whose URDF sets ``<contact><lateral_friction>`` (their author chose it)."""
    if text in _known:
        return _known[text][1]
    import xml.etree.ElementTree as ET

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
