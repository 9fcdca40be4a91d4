"""What to sweep: ``--grid``/``--zip``/``--random`` flags or a sweep file, parsed into axes.

Every axis remembers where the user wrote it (a flag or a sweep file line) so that an error
found later, while preparing one run, points back at it.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from mobot_cli.errors import Location, ScenarioError, UsageError, did_you_mean, shown
from mobot_cli.scenario.limits import SCENARIO_NAME_RE, check_name, check_reference
from mobot_cli.scenario.yamlsafe import read_yaml_file
from mobot_cli.scenario.yamlsource import Source, parse_value, parse_yaml, read_source

MAX_RUNS = 10_000  # runs of one sweep (each is prepared up front: more would keep the first run waiting)
SWEEP_FILE_KEYS = ("scenario", "name", "seed", "set", "grid", "zip", "random", "samples")


@dataclass(frozen=True)
class Axis:
    """One dimension of the sweep: a grid key, a group of zipped keys, or random keys.

    ``rows`` holds one tuple of value texts (YAML, as for --set) per position on the axis;
    a random axis has ``bounds`` instead and gets its rows when the sweep seed is known.
    """

    kind: str  # "grid" | "zip" | "random"
    keys: tuple[str, ...]
    where: tuple[Location, ...]  # one per key
    rows: tuple[tuple[str, ...], ...] = ()
    bounds: tuple[tuple[Any, Any], ...] = ()


@dataclass(frozen=True)
class SweepSpec:
    """A base scenario, fixed overrides and the axes to vary."""

    scenario: Path
    axes: tuple[Axis, ...]
    sets: tuple[tuple[str, Location], ...] = ()  # (KEY=VALUE, where it was given)
    samples: int | None = None
    seed: int | None = None
    name: str | None = None
    sweep_file: Path | None = None
    where: dict[str, Location] = field(default_factory=dict)  # "samples", "seed", ... -> location
    free: tuple[Any, ...] = ()  # random poses and goals in free space (sweep/freedraw.py FreeDraw)


def split_values(text: str) -> list[str]:
    """Split ``V1,V2,...`` at commas outside brackets and quotes ('[1, 2],3' is two values)."""
    out, depth, quote, start = [], 0, "", 0
    for i, ch in enumerate(text):
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
        elif ch == "," and depth == 0:
            out.append(text[start:i].strip())
            start = i + 1
    out.append(text[start:].strip())
    return out


def _key_values(flag: str, item: str) -> tuple[str, str, Location]:
    key, sep, raw = item.partition("=")
    where = Location(file=f"{flag} {item}")
    if not sep or not key.strip():
        raise UsageError(f"{flag} '{item}' is not KEY=VALUES", hint=f"e.g. {flag} robots.mobot.pose.x=0,0.5,1")
    return key.strip(), raw, where


def build_spec(path: Path, grid: list[str], zip_: list[str], random: list[str], samples: int | None,
               seed: int | None, sets: list[str]) -> SweepSpec:
    """The sweep a command line asks for: a scenario and flags, or a sweep file plus any flags."""
    axes = flag_axes(grid, zip_, random)
    flag_where = {"samples": Location(file="--samples"), "seed": Location(file="--seed")}
    if is_sweep_file(path):
        spec = load_sweep_file(path)
        where = {**spec.where, **{k: flag_where[k] for k, v in (("samples", samples), ("seed", seed)) if v is not None}}
        spec = replace(spec, axes=spec.axes + tuple(axes), where=where,
                       sets=spec.sets + tuple((item, Location(file=f"--set {item}")) for item in sets),
                       samples=samples if samples is not None else spec.samples,
                       seed=seed if seed is not None else spec.seed)
        return check_spec(spec)
    fixed = tuple((item, Location(file=f"--set {item}")) for item in sets)
    return check_spec(SweepSpec(scenario=path, axes=tuple(axes), sets=fixed, samples=samples, seed=seed,
                                where=flag_where))


def flag_axes(grid: list[str], zip_: list[str], random: list[str]) -> list[Axis]:
    """Axes from command-line flags: each --grid an axis, all --zip one, all --random one."""
    axes = []
    for item in grid:
        key, raw, where = _key_values("--grid", item)
        values = _values(raw, where)
        axes.append(Axis("grid", (key,), (where,), rows=tuple((v,) for v in values)))
    if zip_:
        parsed = [_key_values("--zip", item) for item in zip_]
        columns = [_values(raw, where) for _, raw, where in parsed]
        axes.append(_zip_axis([k for k, _, _ in parsed], columns, [w for _, _, w in parsed]))
    if random:
        bounds, keys, wheres = [], [], []
        for item in random:
            key, raw, where = _key_values("--random", item)
            low, sep, high = raw.partition(":")
            bounds.append(_bounds(low if sep else raw, high if sep else None, where))
            keys.append(key)
            wheres.append(where)
        axes.append(Axis("random", tuple(keys), tuple(wheres), bounds=tuple(bounds)))
    return axes


def _values(raw: str, where: Location) -> list[str]:
    values = split_values(raw)
    if raw.strip() == "" or any(v == "" for v in values):
        raise UsageError("an empty value in the list" if raw.strip() else "no values given",
                         location=where, hint="Give one or more values separated by commas, e.g. 0,0.5,1.")
    return values


def _zip_axis(keys: list[str], columns: list[list[str]], wheres: list[Location]) -> Axis:
    lengths = {len(c) for c in columns}
    if len(lengths) > 1:
        detail = ", ".join(f"'{k}' has {len(c)}" for k, c in zip(keys, columns))
        raise UsageError(f"zipped lists must be of one length: {detail}", location=wheres[0],
                         hint="Zip pairs the n-th values of each list; use grid for every combination.")
    return Axis("zip", tuple(keys), tuple(wheres), rows=tuple(zip(*columns)))


def _bounds(low: Any, high: Any, where: Location) -> tuple[Any, Any]:
    """LOW and HIGH as numbers (texts from a flag are parsed as YAML)."""
    if high is None:
        raise UsageError("random needs LOW:HIGH", location=where, hint="e.g. --random robots.mobot.pose.yaw=-3.14:3.14")
    lo = parse_value(low, where) if isinstance(low, str) else low
    hi = parse_value(high, where) if isinstance(high, str) else high
    for v in (lo, hi):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise UsageError(f"random bounds must be finite numbers, got {shown(v)}", location=where,
                             hint="e.g. 0.1:0.5 (floats) or 1:4 (whole numbers, both ends included)")
    if not lo < hi:
        raise UsageError(f"random LOW {shown(lo)} must be below HIGH {shown(hi)}", location=where)
    return lo, hi


def check_spec(spec: SweepSpec) -> SweepSpec:
    """Refuse sweeps of no runs and keys given twice."""
    if not spec.axes:
        raise UsageError("nothing to sweep: the sweep has no runs",
                         location=Location(file=spec.sweep_file) if spec.sweep_file else None,
                         hint="Give --grid KEY=V1,V2, --zip KEY=V1,V2, --random KEY=LOW:HIGH --samples N, "
                              "or a sweep file with grid/zip/random.")
    has_random = any(a.kind == "random" for a in spec.axes)
    if has_random and spec.samples is None:
        raise UsageError("random values need a number of samples", location=spec.where.get("samples"),
                         hint="Add --samples N (or samples: N in the sweep file).")
    if spec.samples is not None and not has_random:
        raise UsageError("samples is given but nothing is random", location=spec.where.get("samples"),
                         hint="Add --random KEY=LOW:HIGH, or drop --samples.")
    if spec.samples is not None and spec.samples < 1:
        raise UsageError(f"samples must be at least 1, got {spec.samples}: the sweep has no runs",
                         location=spec.where.get("samples"))
    runs = run_count(spec)
    if runs > MAX_RUNS:
        where = next((a.where[0] for a in spec.axes if a.kind != "random"), spec.where.get("samples"))
        count = f"{runs:,}" if runs < 10**12 else "over 10^12"
        raise UsageError(f"the sweep has {count} runs, more than the limit of {MAX_RUNS:,}", location=where,
                         hint="Every run is prepared before the first starts; split the sweep.")
    if spec.seed is not None and not 0 <= spec.seed < 2**32:
        raise UsageError(f"seed must be in 0..{2**32 - 1}, got {spec.seed}", location=spec.where.get("seed"))
    seen: dict[str, Location] = {}
    named = [(item.partition("=")[0].strip(), where) for item, where in spec.sets]
    named += [(k, w) for axis in spec.axes for k, w in zip(axis.keys, axis.where)]
    named += [(c, d.where) for d in spec.free for c in (d.key, *d.columns())]
    for key, where in named:
        if key in seen:
            raise UsageError(f"key '{key}' is given twice (also at {seen[key]})", location=where,
                             hint="Each key may be swept once, or set once.")
        seen[key] = where
    return spec


def run_count(spec: SweepSpec) -> int:
    """How many runs the sweep has: the product of its axes' lengths."""
    return math.prod((spec.samples or 0) if a.kind == "random" else len(a.rows) for a in spec.axes)


def load_sweep_file(path: Path) -> SweepSpec:
    """Read a sweep file: {scenario, name, seed, set, grid, zip, random, samples}; unchecked."""
    source = read_source(path, "sweep")
    data = source.data
    if not isinstance(data, dict):
        raise ScenarioError("a sweep file must be a mapping (scenario, grid, zip, random, ...)",
                            location=Location(file=path))
    for key in data:
        if key not in SWEEP_FILE_KEYS:
            raise ScenarioError(f"unknown key {shown(key)} in a sweep file", location=source.locate_key((key,)),
                                hint=did_you_mean(str(key), SWEEP_FILE_KEYS))
    scenario = _scenario_path(source, path)
    axes = []
    for key, values in _mapping(source, "grid").items():
        axes.append(Axis("grid", (key,), (_at(source, "grid", key),), rows=tuple(
            (_text(v),) for v in _list(source, ("grid", key), values))))
    zipped = _mapping(source, "zip")
    if zipped:
        columns = [[_text(v) for v in _list(source, ("zip", k), vs)] for k, vs in zipped.items()]
        axes.append(_zip_axis(list(zipped), columns, [_at(source, "zip", k) for k in zipped]))
    randoms = _mapping(source, "random")
    free = []
    if randoms:
        from mobot_cli.sweep import freedraw

        bounds, keys = [], []
        for key, pair in randoms.items():
            where = _at(source, "random", key)
            if isinstance(pair, dict):
                free.append(freedraw.parse(key, pair, where))
                continue
            if not isinstance(pair, list) or len(pair) != 2:
                raise ScenarioError("a random key takes [LOW, HIGH] (or, for a pose or goal, a region)",
                                    location=where, hint="e.g. [-3.14, 3.14], or {region: [-4, -0.5, 1, 4.5], "
                                                         "clearance: 0.4}")
            bounds.append(_bounds(pair[0], pair[1], where))
            keys.append(key)
        axes.append(Axis("random", tuple(keys), tuple(_at(source, "random", k) for k in keys),
                         bounds=tuple(bounds)))
    fixed = [(f"{k}={_text(v)}", _at(source, "set", k)) for k, v in _mapping(source, "set").items()]
    where = {k: source.locate_key((k,)) if k in data else Location(file=path) for k in ("samples", "seed")}
    name = data.get("name")
    if name is not None:
        _sweep_name(name, source.locate_key(("name",)))
    return SweepSpec(scenario=scenario, axes=tuple(axes), sets=tuple(fixed), samples=_int(source, "samples"),
                     seed=_int(source, "seed"), name=name or path.stem, sweep_file=path, where=where,
                     free=tuple(free))


def _sweep_name(name: Any, where: Location) -> None:
    """The sweep's name names its folder: the scenario name's rule."""
    if not isinstance(name, str):
        raise ScenarioError(f"the sweep name must be text, got {shown(name)}", location=where)
    try:
        check_name(name, "sweep", SCENARIO_NAME_RE, "use letters, digits, '_', '-' and '.'")
    except ValueError as exc:
        raise ScenarioError(str(exc), location=where) from None


def is_sweep_file(path: Path) -> bool:
    """True when a YAML file is a sweep file (it names a base ``scenario:``), not a scenario."""
    try:
        head = read_yaml_file(path)
    except ScenarioError:
        return False  # loading it as a scenario reports what is wrong with the file
    data = parse_yaml(head, path).data if head.strip() else None
    return isinstance(data, dict) and "scenario" in data and "version" not in data


def _scenario_path(source: Source, path: Path) -> Path:
    value = source.data.get("scenario")
    where = source.locate_key(("scenario",))
    if not isinstance(value, str) or not value:
        raise ScenarioError("'scenario' must name the base scenario file", location=where)
    try:
        check_reference(value)
    except ValueError as exc:
        raise ScenarioError(str(exc), location=where) from None
    scenario = (path.parent / value).resolve()
    if not scenario.is_file():
        raise ScenarioError(f"scenario file not found: {scenario}", location=where,
                            hint="Paths in a sweep file are relative to the sweep file.")
    return scenario


def _mapping(source: Source, key: str) -> dict[str, Any]:
    value = source.data.get(key, {})
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise ScenarioError(f"'{key}' must be a mapping of KEY: values", location=source.locate_key((key,)),
                            hint="e.g. grid: {robots.mobot.pose.x: [0, 0.5, 1]}")
    return {str(k): v for k, v in value.items()}


def _list(source: Source, path: tuple, values: Any) -> list:
    if not isinstance(values, list) or not values:
        raise ScenarioError("needs a non-empty list of values" if isinstance(values, list) else
                            f"needs a list of values, got {values!r}", location=source.locate_key(path),
                            hint="e.g. [0, 0.5, 1]")
    return values


def _int(source: Source, key: str) -> int | None:
    value = source.data.get(key)
    if value is not None and (isinstance(value, bool) or not isinstance(value, int)):
        raise ScenarioError(f"'{key}' must be a whole number, got {value!r}", location=source.locate_key((key,)))
    return value


def _at(source: Source, section: str, key: str) -> Location:
    return source.locate_key((section, key))


def _text(value: Any) -> str:
    """A YAML value as --set text that parses back to the same value."""
    if isinstance(value, str) and value == parse_value(value):
        return value  # plain words as written: 'encoder', not '"encoder"'
    return json.dumps(value, default=str)  # JSON is YAML: "true" stays a string, 0.5 a float
