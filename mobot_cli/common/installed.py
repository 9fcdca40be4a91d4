"""An installed distribution's version, without importing importlib.metadata (slow: it brings
the email parser) and without scanning every folder on sys.path at each lookup."""

from __future__ import annotations

import functools
import os
import sys


@functools.lru_cache(maxsize=None)
def version(name: str) -> str | None:
    """The version of distribution ``name`` whose module of the same name is imported: read from
    the one ``<name>-*.dist-info`` beside it; else as importlib.metadata finds it (None: not installed)."""
    module = sys.modules.get(name)
    path = getattr(module, "__file__", None)
    if path:
        folder = os.path.dirname(path)
        if os.path.basename(path) == "__init__.py":  # a package: its folder sits beside the dist-info
            folder = os.path.dirname(folder)
        found = _beside(folder, name)
        if found is not None:
            return found
    from importlib import metadata

    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return None


def _beside(folder: str, name: str) -> str | None:
    """The Version: line of the single ``name-*.dist-info/METADATA`` in ``folder``; None if not exactly one."""
    prefix = name.replace("-", "_").lower() + "-"
    try:
        infos = [e for e in os.listdir(folder) if e.endswith(".dist-info") and e.lower().startswith(prefix)]
    except OSError:
        return None
    if len(infos) != 1:
        return None
    try:
        with open(os.path.join(folder, infos[0], "METADATA"), encoding="utf-8") as metadata:
            for line in metadata:
                if line.startswith("Version:"):
                    return line[len("Version:"):].strip()
                if not line.strip():  # the headers end at the first blank line
                    break
    except OSError:
        pass
    return None
