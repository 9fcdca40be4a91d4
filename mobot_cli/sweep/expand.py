"""Axes to runs: the cartesian product of the axes, a seed per run, every run prepared up front.

Preparing every run before any starts is what makes a bad value (an unknown key, a string
where a number goes) an exit-2 error naming the flag or sweep-file line, with nothing run.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import random
import re
from dataclasses import dataclass, replace
from typing import Iterable

from mobot_cli.errors import Location, MobotError
from mobot_cli.scenario.prepare import Prepared, prepare
from mobot_cli.sweep.spec import Axis, SweepSpec

_PLAIN_SEED = re.compile(r"0|[1-9][0-9]*")  # what YAML reads as that whole number, and nothing else


@dataclass(frozen=True)
class Variant:
    """One run of the sweep: its index, the values it sets, and its seed."""

    index: int
    params: tuple[tuple[str, str], ...]  # (key, value text), in axis order
    seed: int

    def overrides(self) -> list[str]:
        return [f"{k}={v}" for k, v in self.params]


@dataclass(frozen=True)
class Sweep:
    """A sweep ready to run: every variant prepared, in index order."""

    spec: SweepSpec
    name: str
    seed: int
    keys: tuple[str, ...]  # the swept keys, the parameter columns of results.csv
    variants: tuple[Variant, ...]
    prepared: tuple[Prepared, ...]

    def robots(self) -> list[str]:
        """Every robot name any run has, in order of first appearance."""
        names: dict[str, None] = {}
        for prepared in self.prepared:
            plan = prepared.plan
            spawned = [e.spawn.name for e in plan.events if e.spawn is not None]
            names.update(dict.fromkeys([r.name for r in plan.robots] + spawned))
        return list(names)

    def measured(self) -> list[str]:
        """The robots that drive to goals in any run: their metrics are columns too."""
        from mobot_cli.plan import GoalStep

        return [name for prepared in self.prepared
                for robot in [*prepared.plan.robots, *(e.spawn for e in prepared.plan.events if e.spawn is not None)]
                if any(isinstance(c, GoalStep) for c in robot.commands) for name in [robot.name]]


def derive_seed(sweep_seed: int, index: int) -> int:
    """A run's seed: a hash of the sweep seed and the run's index, in 0..2**32-1."""
    digest = hashlib.sha256(f"mobot-sweep:{sweep_seed}:{index}".encode()).digest()
    return int.from_bytes(digest[:4], "little")


def random_rows(axis: Axis, samples: int, sweep_seed: int) -> tuple[tuple[str, ...], ...]:
    """``samples`` rows of uniform values; whole-number bounds draw whole numbers, both ends in."""
    rng = random.Random(f"mobot-sweep-random:{sweep_seed}")  # a str seed is hashed the same everywhere
    rows = []
    for _ in range(samples):
        row = []
        for lo, hi in axis.bounds:
            if isinstance(lo, int) and isinstance(hi, int):
                row.append(str(rng.randint(lo, hi)))
            else:
                row.append(json.dumps(round(rng.uniform(lo, hi), 6)))
        rows.append(tuple(row))
    return tuple(rows)


def expand(spec: SweepSpec) -> Sweep:
    """Prepare the base scenario and every run; a located MobotError when any is bad."""
    origins = {item: where for item, where in spec.sets}
    sets = [item for item, _ in spec.sets]
    base = _prepare(spec, sets, origins, note=None)
    sweep_seed = spec.seed if spec.seed is not None else base.plan.seed
    axes = [a if a.kind != "random" else Axis(a.kind, a.keys, a.where, rows=random_rows(a, spec.samples, sweep_seed))
            for a in spec.axes]
    keys = tuple(k for a in axes for k in a.keys) + tuple(c for d in spec.free for c in d.columns())
    seed_swept = "seed" in keys or "seed" in (item.partition("=")[0].strip() for item in sets)
    for axis in axes:
        for row in axis.rows:
            origins.update({f"{k}={v}": w for k, v, w in zip(axis.keys, row, axis.where)})
    variants, prepared = [], []
    done = {_without_seed(sets): base}  # runs that differ only in their seed share one preparation
    for index, combo in enumerate(itertools.product(*(a.rows for a in axes))):
        params = tuple(zip(keys, (v for row in combo for v in row)))
        seed = derive_seed(sweep_seed, index)
        if spec.free:
            params += _free_draws(spec, sets, params, origins, sweep_seed, index)
        overrides = sets + [f"{k}={v}" for k, v in params] + ([] if seed_swept else [f"seed={seed}"])
        run = _reseeded(done.get(_without_seed(overrides)), overrides)
        if run is None:
            run = _prepare(spec, overrides, origins, note=f"run {index}: " + ", ".join(f"{k}={v}" for k, v in params))
            done.setdefault(_without_seed(overrides), run)
        variants.append(Variant(index, params, run.plan.seed))
        prepared.append(run)
    name = spec.name or base.plan.name
    return Sweep(spec, name, sweep_seed, keys, tuple(variants), tuple(prepared))


def _free_draws(spec: SweepSpec, sets: list[str], params: tuple, origins: dict[str, Location],
                sweep_seed: int, index: int) -> tuple:
    """Run ``index``'s poses and goals drawn in free space of its own world (its other values set):
    only the world is loaded here, the run is prepared (and checked) with the drawn values."""
    from mobot_cli.scenario.load import validate_ready
    from mobot_cli.scenario.overrides import read_ready
    from mobot_cli.scenario.resolve import world_of
    from mobot_cli.sweep.freedraw import draw, rng_for, starts

    note = f"run {index}" + "".join(f", {k}={v}" for k, v in params)
    try:
        source = read_ready(spec.scenario, sets + [f"{k}={v}" for k, v in params])
        scenario = validate_ready(source)
        world = world_of(scenario, source).plan
    except MobotError as exc:
        raise _relocated(exc, origins, note) from None
    drawn = draw(spec.free, world, starts(scenario), rng_for(sweep_seed, index), note)
    for (key, value), d in zip(drawn, (d for d in spec.free for _ in d.columns())):
        origins[f"{key}={value}"] = d.where
    return tuple(drawn)


def _is_seed(override: str) -> bool:
    return override.partition("=")[0].strip() == "seed"


def _without_seed(overrides: Iterable[str]) -> tuple[str, ...]:
    return tuple(o for o in overrides if not _is_seed(o))


def _reseeded(prepared: Prepared | None, overrides: list[str]) -> Prepared | None:
    """``prepared`` (made with the same overrides but for the seed) with the seed these overrides
    set, without preparing the scenario again (every run would pay for it): a scenario's seed changes its plan's
    seed and one line of the resolved YAML, nothing else. None when that cannot be sure: no
    prepared twin, no seed given, a seed written other than as a plain whole number in range (the full
    preparation then checks it and names the flag), or a resolved YAML without one such line."""
    texts = [o.partition("=")[2].strip() for o in overrides if _is_seed(o)]
    if prepared is None or not texts or not _PLAIN_SEED.fullmatch(texts[-1]) or int(texts[-1]) >= 2**32:
        return None
    seed, old = int(texts[-1]), f"\nseed: {prepared.plan.seed}\n"
    if prepared.resolved_yaml.count(old) != 1:
        return None
    return Prepared(prepared.scenario.model_copy(update={"seed": seed}), replace(prepared.plan, seed=seed),
                    prepared.resolved_yaml.replace(old, f"\nseed: {seed}\n"))


def _prepare(spec: SweepSpec, overrides: Iterable[str], origins: dict[str, Location],
             note: str | None) -> Prepared:
    try:
        return prepare(spec.scenario, list(overrides))
    except MobotError as exc:
        raise _relocated(exc, origins, note) from None


def _relocated(exc: MobotError, origins: dict[str, Location], note: str | None) -> MobotError:
    """Point an error about a --set override at the flag or sweep-file line that made it."""
    file = exc.location.file
    if isinstance(file, str) and file.startswith("--set ") and file[len("--set "):] in origins:
        where = origins[file[len("--set "):]]
        location = Location(file=where.file, line=where.line, key=exc.location.key or where.key)
        return type(exc)(exc.message, location=location, hint=exc.hint)
    for text, where in origins.items():  # an override whose path does not exist in the scenario
        prefix = f"--set {text.partition('=')[0]}: "
        if exc.message.startswith(prefix):
            return type(exc)(exc.message[len(prefix):], location=where, hint=exc.hint)
    message = f"{exc.message} (in {note})" if note else exc.message
    return type(exc)(message, location=exc.location, hint=exc.hint)
