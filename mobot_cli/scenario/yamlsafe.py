"""The one YAML reader of scenarios, --set values and sweep files, with limits a user can read.

A YAML text is untrusted input: a 400-byte file of nested aliases expands to gigabytes, a
FIFO never ends, a thousand brackets overflow the Python stack and ``!!python/...`` tags name
code. So: only regular files of at most ``MAX_YAML_BYTES`` are read, nesting stops at
``MAX_DEPTH``, the expanded document holds at most ``MAX_NODES`` values (aliases counted every
time they are used), only the plain YAML types are built, and dates stay text (a date where a
number goes is then an error about that value, never a datetime reaching the model).
"""

from __future__ import annotations

import os
import re
import stat
from pathlib import Path
from typing import Any

import yaml

from mobot_cli.errors import Location, ScenarioError, shown

MAX_YAML_BYTES = 1 << 20  # 1 MiB: a generous scenario is a few kB
MAX_DEPTH = 32  # the format nests 6 levels deep (events[].spawn.commands[].at)
MAX_NODES = 100_000  # values after aliases are expanded; a 1000-robot fleet is ~5000

_CORE = "tag:yaml.org,2002:"
# Tags a scenario may write; timestamps, binary, sets and every python/... tag are refused.
SCALAR_TAGS = frozenset(_CORE + t for t in ("null", "bool", "int", "float", "str"))
SEQ_TAG, MAP_TAG = _CORE + "seq", _CORE + "map"
_KINDS = {stat.S_IFDIR: "a directory", stat.S_IFIFO: "a FIFO (named pipe)", stat.S_IFCHR: "a character device",
          stat.S_IFBLK: "a block device", stat.S_IFSOCK: "a socket"}


class Loader(yaml.SafeLoader):
    """SafeLoader without dates, merge keys (``<<``) or ``=``, composing at most MAX_DEPTH deep.

    Plain scalars become null, bool, int, float (also 1e5, as YAML 1.2 reads it) or str.
    """

    yaml_implicit_resolvers = {
        first: [(tag, regexp) for tag, regexp in resolvers if tag in SCALAR_TAGS]
        for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
    }

    def __init__(self, stream: str):
        super().__init__(stream)
        self.depth = 0

    def compose_node(self, parent, index):
        """PyYAML composes recursively: stop a deep document before Python's stack does."""
        self.depth += 1
        try:
            if self.depth > MAX_DEPTH:
                raise TooDeep(self.peek_event().start_mark)
            return super().compose_node(parent, index)
        finally:
            self.depth -= 1


# YAML 1.2 floats without a dot (1e308, 5E-3): PyYAML's 1.1 rules read them as text.
Loader.add_implicit_resolver(_CORE + "float", re.compile(r"^[-+]?[0-9][0-9_]*(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
                             list("-+0123456789"))


class TooDeep(Exception):
    """Nesting beyond MAX_DEPTH, at ``mark``."""

    def __init__(self, mark):
        super().__init__(mark)
        self.mark = mark


def read_yaml_file(path: Path, what: str = "scenario") -> str:
    """The text of a YAML file: a regular file of at most MAX_YAML_BYTES, else a ScenarioError."""
    where = Location(file=path)
    try:
        info = os.stat(path)  # stat, not open: opening a FIFO would already block
    except FileNotFoundError:
        raise ScenarioError(f"{what} file not found: {path}",
                            hint="Check the path; bundled examples are in scenarios/.") from None
    except OSError as exc:
        raise ScenarioError(f"cannot read {what} file {path}: {exc.strerror or exc}") from None
    kind = _KINDS.get(stat.S_IFMT(info.st_mode))
    if kind is not None:
        raise ScenarioError(f"the {what} is {kind}, not a regular file", location=where,
                            hint=f"Give the path of a {what} YAML file.")
    too_big = ScenarioError(f"the {what} file is larger than {MAX_YAML_BYTES / 2**20:g} MiB", location=where,
                            hint="That is far beyond any scenario: is it the right file?")
    if info.st_size > MAX_YAML_BYTES:
        raise too_big
    try:
        with open(path, "rb") as handle:
            data = handle.read(MAX_YAML_BYTES + 1)  # files like /proc/* report size 0
    except OSError as exc:
        raise ScenarioError(f"cannot read {what} file {path}: {exc.strerror or exc}") from None
    if len(data) > MAX_YAML_BYTES:
        raise too_big
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise ScenarioError(f"the {what} file is not UTF-8 text (byte {exc.start})",
                            location=Location(file=path, line=line),
                            hint="Save it as UTF-8.") from None


def compose(text: str, where: Location, numbered: bool = True) -> yaml.Node | None:
    """Parse one YAML document into nodes; malformed or too deep YAML is a located ScenarioError.

    ``numbered``: errors name the line in ``where.file`` (False for a --set value).
    """
    if len(text) > MAX_YAML_BYTES:
        raise ScenarioError(f"the YAML text is longer than {MAX_YAML_BYTES / 2**20:g} MiB", location=where)
    loader = None
    try:
        loader = Loader(text)  # its reader already refuses control characters
        return loader.get_single_node()
    except TooDeep as exc:
        raise ScenarioError(f"the YAML nests deeper than {MAX_DEPTH} levels", location=_at(where, exc.mark, numbered),
                            hint="The scenario format nests a few levels; look for runaway brackets.") from None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        problem = exc.problem or str(exc)
        if exc.context and "duplicate anchor" in exc.context:  # the problem alone says "second occurrence"
            problem = exc.context.partition(";")[0]
        raise ScenarioError(f"malformed YAML: {_one_line(problem)}", location=_at(where, mark, numbered),
                            hint="Fix the YAML syntax at or just before that line.") from None
    except yaml.YAMLError as exc:  # ReaderError: a control character; it knows its offset only
        offset = getattr(exc, "position", None)
        line = text[:offset].count("\n") + 1 if isinstance(offset, int) else None
        raise ScenarioError(f"malformed YAML: {_one_line(str(exc))}",
                            location=Location(file=where.file, line=line if numbered else None),
                            hint="Remove control characters; a scenario is plain UTF-8 text.") from None
    finally:
        if loader is not None:
            loader.dispose()


def construct_scalar(node: yaml.ScalarNode, where: Location) -> Any:
    """A scalar node to None, bool, int, float or str; other tags and bad values are errors."""
    tag = node.tag
    check_tag(node, where)
    try:
        return Loader.yaml_constructors[tag](_CONSTRUCTOR, node)
    except (ValueError, LookupError, TypeError, OverflowError, yaml.YAMLError):
        raise ScenarioError(f"{shown(node.value, 40)} cannot be read as {short_tag(tag)}", location=where,
                            hint="Fix the value, or quote it to make it text.") from None


def check_tag(node: yaml.Node, where: Location) -> None:
    """Refuse every tag but the plain ones: !!str on a scalar, !!seq on a list, !!map on a mapping."""
    if isinstance(node, yaml.ScalarNode):
        allowed = node.tag in SCALAR_TAGS
    else:
        allowed = node.tag == (SEQ_TAG if isinstance(node, yaml.SequenceNode) else MAP_TAG)
    if not allowed:
        raise ScenarioError(f"the YAML tag '{short_tag(node.tag)}' is not allowed", location=where,
                            hint="Scenarios hold plain values: numbers, text, true/false, lists and mappings.")


def short_tag(tag: str) -> str:
    """'tag:yaml.org,2002:float' as a user writes it: '!!float'."""
    text = "!!" + tag[len(_CORE):] if tag.startswith(_CORE) else tag
    return _one_line(text if len(text) <= 60 else text[:57] + "...")


def _at(where: Location, mark, numbered: bool) -> Location:
    if mark is None or not numbered:
        return where
    return Location(file=where.file, line=mark.line + 1)


def _one_line(text: str) -> str:
    return " ".join(text.split())


_CONSTRUCTOR = Loader("")  # builds scalars only; node-to-value constructors keep no state for them
