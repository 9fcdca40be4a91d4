"""Mutated bundled scenarios and sweep files, and the one property they must keep.

Used by tests/test_scenario_fuzz.py (a small seeded sample) and bench/fuzz_scenarios.py
(thousands). The property: loading and resolving a mutated file, as `mobot check` and
`mobot sweep` do before anything runs, either succeeds or raises a MobotError whose text is
one paragraph naming where the problem is, in bounded time. Any other exception is a bug.
"""

from __future__ import annotations

import os
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml
from hypothesis import strategies as st

from mobot_cli.errors import MobotError

REPO = Path(__file__).resolve().parents[2]
BUNDLED = sorted((REPO / "scenarios").glob("*.yaml")) + sorted((REPO / "scenarios" / "sweeps").glob("*.yaml"))
TIME_LIMIT_S = 60.0  # CPU seconds, a generous bound for one load + resolve (wall time would count waiting)


def cpu_seconds() -> float:
    """CPU time of this process and of the children it has waited for (a sandboxed xacro)."""
    times = os.times()
    return times.user + times.system + times.children_user + times.children_system

# Raw YAML that a data structure cannot express: tags, aliases, dates, YAML 1.1 oddities.
RAW = [
    "!!python/name:os.system", "!!python/object/apply:os.system [echo hi]", "!!float abc", "!!int 0x",
    "!!int ''", "!!bool maybe", "!!binary aGVsbG8=", "!!set {a, b}", "!!omap [a: 1]", "!!timestamp 2024-01-01",
    "!!str 5", "!!null x", "!custom x", "! plain", "&a [*a]", "*nope", "2024-13-45", "2024-01-02",
    "2024-01-02T03:04:05Z", "1e308", "-1e308", "1e-308", "1.0e+309", "5e-324", ".inf", "-.inf", ".nan", "0x1F",
    "0o17", "1_000", "1:30", "~", "yes", "off", "[[[[[[", "{a: 1, a: 2}", "<<: {x: 1}", "'unterminated",
    "\"\\x00\"", "[" * 40 + "]" * 40, "&x [1, 2]", "[&y 0.5, *y]",
    "{x0: &a0 [l,l,l,l,l,l,l,l,l], x1: &a1 [*a0,*a0,*a0,*a0,*a0,*a0,*a0,*a0,*a0], "
    "x2: &a2 [*a1,*a1,*a1,*a1,*a1,*a1,*a1,*a1,*a1], x3: &a3 [*a2,*a2,*a2,*a2,*a2,*a2,*a2,*a2,*a2], "
    "x4: &a4 [*a3,*a3,*a3,*a3,*a3,*a3,*a3,*a3,*a3], x5: &a5 [*a4,*a4,*a4,*a4,*a4,*a4,*a4,*a4,*a4]}",
]
WORDS = ["version", "name", "world", "physics", "rate_hz", "gravity", "duration", "seed", "settle", "log",
         "robots", "description", "pose", "commands", "at", "for", "linear", "angular", "count", "poses",
         "events", "spawn", "delete", "expect", "within", "robot", "all", "end", "auto", "mobot", "{i}",
         "mobot_{i}", "grid", "zip", "random", "samples", "set", "scenario", "empty", "house", "encoder"]

@dataclass
class Raw:
    """A raw YAML snippet to splice into the dumped text in place of a value."""

    text: str


numbers = st.one_of(
    st.integers(), st.integers(min_value=-10, max_value=10),
    st.sampled_from([4299, 4301, 20000]).map(lambda n: Raw("9" * n)),  # Python refuses ints of > 4300 digits
    st.floats(), st.sampled_from([1e308, -1e308, 1e-308, 5e-324, 0.0, -0.0, 1e6, 1e6 + 1, 1e-3, 9e-4, 1000.0, 1001.0]),
    st.booleans(),
)
strings = st.one_of(
    st.text(max_size=40), st.sampled_from(WORDS),
    st.builds(lambda c, n: c * n, st.sampled_from(["r", "x_", "/a", "\n", "é", "{i}"]),
              st.sampled_from([21, 22, 63, 64, 65, 300, 5000])),
)
scalars = st.one_of(numbers, strings, st.none(), st.dates(), st.datetimes())
values = st.recursive(scalars, lambda inner: st.lists(inner, max_size=4) | st.dictionaries(
    st.sampled_from(WORDS) | st.text(max_size=10), inner, max_size=4), max_leaves=12)


def paths(data: Any, prefix: tuple = ()) -> list[tuple]:
    """Every key path in a parsed document, the document itself first."""
    out = [prefix]
    if isinstance(data, dict):
        for key, value in data.items():
            out.extend(paths(value, prefix + (key,)))
    elif isinstance(data, list):
        for index, value in enumerate(data):
            out.extend(paths(value, prefix + (index,)))
    return out


def _parent(data: Any, path: tuple) -> Any:
    for part in path[:-1]:
        data = data[part]
    return data


@st.composite
def structural(draw, data: Any) -> Any:
    """One change to a parsed document: delete, replace, insert, wrap or repeat something."""
    path = draw(st.sampled_from(paths(data)))
    if not path:
        return draw(values) if draw(st.booleans()) else data
    parent, last = _parent(data, path), path[-1]
    current = parent[last]  # a number mostly becomes another number, a text another text
    like = numbers if isinstance(current, (int, float)) else strings if isinstance(current, str) else values
    new = draw(st.one_of(like, values, st.sampled_from(RAW).map(Raw)))
    kind = draw(st.sampled_from(["delete", "replace", "replace", "insert", "wrap", "repeat"]))
    if kind == "delete":
        del parent[last]
    elif kind == "replace":
        parent[last] = new
    elif kind == "insert" and isinstance(parent, dict):
        parent[draw(st.sampled_from(WORDS) | st.text(max_size=12))] = new
    elif kind == "insert":
        parent.insert(last, new)
    elif kind == "wrap":
        parent[last] = [parent[last]] if draw(st.booleans()) else {draw(st.sampled_from(WORDS)): parent[last]}
    elif isinstance(parent, list):
        parent.append(parent[last])
    return data


def dump(data: Any) -> str:
    """YAML text of ``data`` with each Raw snippet spliced in as written."""
    snippets: list[str] = []

    def mark(node: Any) -> Any:
        if isinstance(node, Raw):
            snippets.append(node.text)
            return f"@@RAW{len(snippets) - 1}@@"
        if isinstance(node, dict):
            return {k: mark(v) for k, v in node.items()}
        if isinstance(node, list):
            return [mark(v) for v in node]
        return node

    text = yaml.safe_dump(mark(data), sort_keys=False, allow_unicode=True, default_flow_style=None)
    for index, snippet in enumerate(snippets):
        text = text.replace(f"'@@RAW{index}@@'", snippet)
    return text


@st.composite
def textual(draw, text: str) -> bytes:
    """One change to the text: truncate it, insert bytes, repeat a line (a duplicate key) or add a line."""
    raw = text.encode("utf-8")
    kind = draw(st.sampled_from(["none", "truncate", "bytes", "repeat", "line"]))
    if kind == "truncate":
        return raw[: draw(st.integers(0, len(raw)))]
    if kind == "bytes":
        at = draw(st.integers(0, len(raw)))
        return raw[:at] + draw(st.binary(min_size=1, max_size=8)) + raw[at:]
    lines = text.splitlines(keepends=True) or [""]
    at = draw(st.integers(0, len(lines) - 1))
    if kind == "repeat":
        lines.insert(at, lines[at])
    elif kind == "line":
        key = draw(st.sampled_from(WORDS))
        indent = lines[at][: len(lines[at]) - len(lines[at].lstrip())]
        lines.insert(at, f"{indent}{key}: {draw(st.sampled_from(RAW))}\n")
    return "".join(lines).encode("utf-8")


@st.composite
def mutated(draw, original: Path) -> bytes:
    """A bundled file after 1-3 structural changes and maybe one change to its text."""
    text = original.read_text(encoding="utf-8")
    data = yaml.safe_load(text)
    for _ in range(draw(st.integers(0, 3))):
        data = draw(structural(data))
    return draw(textual(dump(data)))


@st.composite
def override(draw, original: Path) -> str:
    """A --set KEY=VALUE on a key of the file (or a new one) with a random YAML value."""
    data = yaml.safe_load(original.read_text(encoding="utf-8"))
    path = draw(st.sampled_from([p for p in paths(data) if p]))
    parts = [str(p) for p in path]
    if isinstance(data.get("robots"), list) and len(path) > 1 and path[0] == "robots":
        parts[1] = str(data["robots"][path[1]].get("name", path[1]))
    value = draw(st.one_of(st.sampled_from(RAW), scalars.map(lambda v: dump(v).removesuffix("\n...\n").strip())))
    return ".".join(parts) + "=" + value


def workspace(tmp: Path) -> Path:
    """A copy of scenarios/ to write mutated files into (sweep files name ../<scenario>)."""
    root = tmp / "scenarios"
    if not root.exists():
        shutil.copytree(REPO / "scenarios", root)
    return root


def load_and_resolve(path: Path, overrides: list[str]) -> None:
    """What `mobot check` (a scenario) or `mobot sweep` (a sweep file) does before running anything."""
    from mobot_cli.scenario.prepare import prepare
    from mobot_cli.sweep.expand import expand
    from mobot_cli.sweep.spec import build_spec, is_sweep_file

    if is_sweep_file(path):
        expand(build_spec(path, [], [], [], None, None, overrides))
    else:
        prepare(path, overrides)


def check(path: Path, overrides: list[str] = ()) -> str:
    """The property, on one file: 'accepted' or 'refused'; anything else raises."""
    started = cpu_seconds()  # a runaway load burns CPU; a busy machine only adds waiting
    try:
        load_and_resolve(path, list(overrides))
        outcome = "accepted"
    except MobotError as exc:
        text = str(exc)
        assert len(text.splitlines()) == 1, f"not one paragraph: {text!r}"  # also \x85, \u2028, ...
        assert str(path) in text or "--set" in text or _names_a_file(text), f"names no file: {text!r}"
        outcome = "refused"
    elapsed = cpu_seconds() - started
    assert elapsed < TIME_LIMIT_S, f"took {elapsed:.1f} s of CPU"
    return outcome


def _names_a_file(text: str) -> bool:
    """An error inside a file the scenario uses (its base scenario, a robot) names that file."""
    head = text.split(": ", 1)[0].rsplit(":", 1)[0].split(", key ", 1)[0]
    return Path(head).exists()

