"""YAML to plain Python data, remembering the line of every key and item.

PyYAML's composer keeps a start mark on each node; we walk the node tree once, building
the data and a table from key paths (``("robots", 0, "pose", "x")``) to 1-based lines, so
that any later error can point at the line the user wrote.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from mobot_cli.errors import Location, ScenarioError

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


def parse_yaml(text: str, file: Path | None) -> Source:
    """Parse one YAML document; duplicate keys and syntax errors are located ScenarioErrors."""
    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = mark.line + 1 if mark else None
        problem = exc.problem or str(exc)
        raise ScenarioError(
            f"malformed YAML: {problem}",
            location=Location(file=file, line=line),
            hint="Fix the YAML syntax at or just before that line.",
        ) from None
    source = Source(data=None, file=file)
    if node is None:
        return source
    source.data = _build(node, (), source, yaml.SafeLoader(""))
    return source


def _build(node: yaml.Node, path: PathKey, source: Source, loader: yaml.SafeLoader) -> Any:
    source.lines.setdefault(path, node.start_mark.line + 1)
    if isinstance(node, yaml.MappingNode):
        out: dict[Any, Any] = {}
        for key_node, value_node in node.value:
            key = _scalar(key_node, loader)
            if isinstance(key, (list, dict)):
                raise ScenarioError("a mapping key must be a plain word",
                                    location=Location(file=source.file, line=key_node.start_mark.line + 1))
            if key in out:
                raise ScenarioError(
                    f"key '{key}' appears twice in the same mapping",
                    location=Location(file=source.file, line=key_node.start_mark.line + 1,
                                      key=_dotted(path + (key,))),
                    hint="Remove one of them: YAML would silently keep only the last.",
                )
            source.lines[path + (key,)] = key_node.start_mark.line + 1
            out[key] = _build(value_node, path + (key,), source, loader)
        return out
    if isinstance(node, yaml.SequenceNode):
        return [_build(item, path + (i,), source, loader) for i, item in enumerate(node.value)]
    return _scalar(node, loader)


def _scalar(node: yaml.Node, loader: yaml.SafeLoader) -> Any:
    if not isinstance(node, yaml.ScalarNode):
        return [] if isinstance(node, yaml.SequenceNode) else {}
    return loader.construct_object(node, deep=True)


def _dotted(path: PathKey) -> str:
    return ".".join(str(p) for p in path)


def parse_value(text: str) -> Any:
    """Parse a --set value as YAML ('2.0' is a float, 'true' a bool, '[1, 2]' a list)."""
    try:
        return yaml.safe_load(text) if text.strip() else ""
    except yaml.YAMLError:
        return text
