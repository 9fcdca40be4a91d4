"""YAML to plain Python data, remembering the line of every key and item.

PyYAML's composer keeps a start mark on each node; we walk the node tree once, building
the data and a table from key paths (``("robots", 0, "pose", "x")``) to 1-based lines, so
that any later error can point at the line the user wrote. Reading limits are in yamlsafe.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from mobot_cli.errors import Location, ScenarioError, shown
from mobot_cli.scenario.source import PathKey, Source
from mobot_cli.scenario.yamlsafe import MAX_DEPTH, MAX_NODES, check_tag, compose, construct_scalar, read_yaml_file


def read_source(path: Path | str, what: str = "scenario") -> Source:
    """Read and parse a YAML file (limits and errors: yamlsafe.read_yaml_file, parse_yaml)."""
    path = Path(path)
    return parse_yaml(read_yaml_file(path, what), path)


def to_yaml(document: dict[str, Any]) -> str:
    """Dump a resolved document (scenario/document.py) as block-style YAML, keys in the order given."""
    return yaml.safe_dump(document, sort_keys=False, default_flow_style=None, width=100)


def parse_yaml(text: str, file: Path | None) -> Source:
    """Parse one YAML document; duplicate keys, syntax errors and refused YAML are located ScenarioErrors."""
    node = compose(text, Location(file=file))
    source = Source(data=None, file=file)
    if node is not None:
        source.data = _Builder(source, Location(file=file), numbered=True).build(node, ())
    return source


def parse_value(text: str, where: Location | None = None) -> Any:
    """Parse a --set value as YAML ('2.0' is a float, 'true' a bool, '[1, 2]' a list).

    Text that is not YAML stays text; refused YAML (tags, aliases that expand too far, deep
    nesting) is a ScenarioError at ``where``, as in a file.
    """
    if not text.strip():
        return ""
    where = where or Location(file="--set value")
    try:
        node = compose(text, where, numbered=False)
    except ScenarioError as exc:
        if exc.message.startswith("malformed YAML"):
            return text
        raise
    if node is None:
        return None
    return _Builder(Source(data=None), where, numbered=False).build(node, ())


class _Builder:
    """Walks composed nodes once into plain data, counting values against MAX_NODES."""

    def __init__(self, source: Source, where: Location, numbered: bool):
        self.source, self.where, self.numbered = source, where, numbered
        self.count = 0

    def at(self, node: yaml.Node, path: PathKey = ()) -> Location:
        """Where ``node`` is: its line in the file (and its key), or the --set value."""
        key = _dotted(path) or None
        if not self.numbered:
            return Location(file=self.where.file, key=key)
        return Location(file=self.where.file, line=node.start_mark.line + 1, key=key)

    def build(self, node: yaml.Node, path: PathKey) -> Any:
        """Plain data for ``node``; lines of keys and items go into the source's table."""
        self.count += 1
        if self.count > MAX_NODES:
            raise ScenarioError(f"the YAML holds more than {MAX_NODES} values once its aliases (*name) are "
                                "expanded", location=self.at(node),
                                hint="Aliases repeat their anchor's content every time they are used; "
                                     "write the values out, or split the scenario.")
        if len(path) > MAX_DEPTH:  # only an alias to its own ancestor gets this deep: `&a [*a]`
            raise ScenarioError(f"the YAML nests deeper than {MAX_DEPTH} levels", location=self.at(node),
                                hint="An alias inside its own anchor repeats forever.")
        check_tag(node, self.at(node, path))
        self.source.lines.setdefault(path, node.start_mark.line + 1)
        if isinstance(node, yaml.MappingNode):
            return self.mapping(node, path)
        if isinstance(node, yaml.SequenceNode):
            return [self.build(item, path + (i,)) for i, item in enumerate(node.value)]
        return construct_scalar(node, self.at(node, path))

    def mapping(self, node: yaml.MappingNode, path: PathKey) -> dict[Any, Any]:
        out: dict[Any, Any] = {}
        for key_node, value_node in node.value:
            if not isinstance(key_node, yaml.ScalarNode):
                raise ScenarioError("a mapping key must be a plain word", location=self.at(key_node, path))
            key = construct_scalar(key_node, self.at(key_node, path))
            if key in out:
                raise ScenarioError(
                    f"key {shown(key)} appears twice in the same mapping", location=self.at(key_node, path + (key,)),
                    hint="Remove one of them: YAML would silently keep only the last.")
            self.source.lines[path + (key,)] = key_node.start_mark.line + 1
            out[key] = self.build(value_node, path + (key,))
        return out


def _dotted(path: PathKey) -> str:
    """('robots', 0, 'pose') as 'robots[0].pose' (names are not known while building)."""
    return ".".join(f"[{p}]" if isinstance(p, int) and not isinstance(p, bool) else str(p)
                    for p in path).replace(".[", "[")
