"""A scenario document as plain data, with the line of every key and item and the --set texts
applied to it: what errors point at. Made by scenario/yamlsource.py; free of PyYAML."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mobot_cli.errors import Location

PathKey = tuple[Any, ...]


@dataclass
class Source:
    """Data parsed from one YAML document plus where each piece came from."""

    data: Any
    file: Path | None = None
    lines: dict[PathKey, int] = field(default_factory=dict)
    overrides: dict[PathKey, str] = field(default_factory=dict)  # path -> the --set text

    def locate(self, path: PathKey) -> Location:
        """Location of the deepest known prefix of ``path`` (a --set wins over the file)."""
        if tuple(path) not in self.lines:  # made by an override, e.g. a mistyped --set key
            for done, text in self.overrides.items():
                if done[: len(path)] == tuple(path):
                    return Location(file="--set " + text)
        for n in range(len(path), -1, -1):
            prefix = tuple(path[:n])
            if prefix in self.overrides:
                return Location(file="--set " + self.overrides[prefix], key=None)
            if prefix in self.lines:
                return Location(file=self.file, line=self.lines[prefix])
        return Location(file=self.file)

    def key_text(self, path: PathKey) -> str:
        """Render ('robots', 0, 'pose', 'x') as 'robots.mobot.pose.x', the --set spelling."""
        out: list[str] = []
        node = self.data
        for part in path:
            if isinstance(part, int) and isinstance(node, list):
                item = node[part] if part < len(node) else None
                name = item.get("name") if isinstance(item, dict) else None
                out.append(str(name) if isinstance(name, str) else f"[{part}]")
            else:
                out.append(str(part))
            try:
                node = node[part]
            except (KeyError, IndexError, TypeError):
                node = None
        return ".".join(out).replace(".[", "[")

    def locate_key(self, path: PathKey) -> Location:
        """Like ``locate`` but also naming the key, for errors about one value."""
        where = self.locate(path)
        return Location(file=where.file, line=where.line, key=self.key_text(path))
