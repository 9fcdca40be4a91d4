"""URDF text to a file PyBullet can load, and the few URDF facts the simulation needs."""

from __future__ import annotations

from pathlib import Path


def urdf_path(text: str, folder: str = "urdf") -> Path:
    """A file holding ``text``, named by its content hash, written once and atomically.

    The folder is bounded (``prune``): every distinct text a live client sends makes a file.
    """
    import hashlib

    from mobot_cli.common import cache

    data = text.encode("utf-8")
    digest = hashlib.sha256(data).hexdigest()[:32]
    # A hit is checked against its name; the cache off or faulty, the file goes to a private
    # temporary folder instead (a cache only costs time). Parallel sweep workers may write it too.
    return cache.load_file(folder, f"{digest}.urdf", digest) or \
        cache.store_file(folder, f"{digest}.urdf", data, bounded=True)


def links_with_friction(text: str) -> frozenset[str]:
    """Names of links whose URDF sets ``<contact><lateral_friction>`` (their author chose it)."""
    import xml.etree.ElementTree as ET

    root = ET.fromstring(text)
    return frozenset(
        link.get("name", "")
        for link in root.findall("link")
        if link.find("contact/lateral_friction") is not None
    )
