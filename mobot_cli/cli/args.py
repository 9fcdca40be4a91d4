"""Parsing of command-line arguments shared by several commands."""

from __future__ import annotations

import time
from pathlib import Path

from mobot_cli.errors import UsageError


def parse_mappings(items: list[str]) -> dict[str, str]:
    """xacro-style ``NAME:=VALUE`` arguments to a dict; anything else is a usage error."""
    out: dict[str, str] = {}
    for item in items:
        name, sep, value = item.partition(":=")
        if not sep or not name:
            raise UsageError(f"argument '{item}' is not NAME:=VALUE", hint="e.g. lidar:=true")
        out[name] = value
    return out


def default_out(folder: str, name: str) -> Path:
    """``folder/<name>-<YYYYmmdd-HHMMSS>``, with a suffix if that exists already."""
    base = Path(folder) / f"{name}-{time.strftime('%Y%m%d-%H%M%S')}"
    candidate, n = base, 1
    while candidate.exists():
        candidate, n = base.with_name(f"{base.name}-{n}"), n + 1
    return candidate
