"""A world (bundled name or Gazebo SDF file) to a WorldPlan, cached by content.

Each static top-level model becomes one static body holding all of its collision shapes
(so a spawn that hits it can name it); non-static models without joints that move (none, fixed
ones, zero-range ones hung from `world`) are held fixed too (mobot's worlds are static);
non-static models with joints that move are robots, simulated only when a
scenario lists them by name. An upward plane through z = 0 is the world's ground plane.
A warm load reads one JSON document and checks the files it was built from.
"""

from __future__ import annotations

import os
from dataclasses import asdict
from pathlib import Path
from typing import Any

from mobot_cli.assets.resources import ResourceResolver, bundled_dir
from mobot_cli.assets.world.loaded import LoadedWorld, WorldRobot
from mobot_cli.common import cache
from mobot_cli.errors import Location, WorldError, did_you_mean
from mobot_cli.plan import MoverPlan, StaticBody, StaticShape, WorldPlan

WORLD_SUFFIXES = (".world", ".sdf")
XACRO_WORLD_SUFFIXES = (".world.xacro", ".sdf.xacro")  # expanded as a robot description is


def bundled_world_names() -> tuple[str, ...]:
    """Names usable as `world:`, one per .sdf/.world file in the bundled worlds/."""
    root = bundled_dir("worlds")
    if not root.is_dir():
        return ()
    return tuple(sorted(p.stem for p in root.iterdir() if p.suffix in WORLD_SUFFIXES))


def world_path(world: str, base_dir: Path | None) -> Path:
    """The file a `world:` value names: a bundled name or a path relative to ``base_dir``."""
    text = str(world).strip()
    names = bundled_world_names()
    if text in names:
        root = bundled_dir("worlds")
        return next(root / f"{text}{s}" for s in WORLD_SUFFIXES if (root / f"{text}{s}").is_file())
    if text.endswith((*WORLD_SUFFIXES, *XACRO_WORLD_SUFFIXES)) or "/" in text or os.sep in text:
        path = Path(text).expanduser()
        path = path if path.is_absolute() else Path(base_dir or Path.cwd()) / path
        if not path.is_file():
            raise WorldError(f"world file {path} does not exist", location=Location(file=path),
                             hint="Relative paths are relative to the scenario's folder.")
        return path.resolve()
    raise WorldError(f"'{text}' is neither a bundled world nor a .world/.sdf file",
                     hint=(did_you_mean(text, names) + " " if names else "")
                     + "Give a bundled name or a path to a Gazebo .world or .sdf file.")


def load_world(world: str, base_dir: Path | None = None,
               skip_missing: bool = False) -> LoadedWorld:
    """Load a world (cached by the content of every file it read)."""
    path = world_path(world, base_dir)
    resolver = ResourceResolver(base_dir)
    fuel = os.environ.get("GZ_FUEL_CACHE_PATH", "")
    key = cache.digest("world", str(path), path.read_bytes(), resolver.fingerprint(),
                       str(bool(skip_missing)), fuel)
    loaded = _from_document(cache.load("world", key))
    if loaded is None:
        from mobot_cli.assets.world.build import build_world  # lxml, numpy, trimesh: cold only

        loaded, deps = build_world(path, resolver, skip_missing)
        cache.store("world", key, _to_document(loaded, deps))
    return loaded


def _stat(path: str) -> list[int]:
    try:
        info = os.stat(path)
    except OSError:
        return [-1, -1]
    return [info.st_size, info.st_mtime_ns]


def _to_document(loaded: LoadedWorld, deps: list[str]) -> dict[str, Any]:
    return {"plan": asdict(loaded.plan), "robots": [asdict(r) for r in loaded.robots],
            "static_models": list(loaded.static_models), "summary": loaded.summary,
            "notices": list(loaded.notices),
            "deps": [[d, *_stat(d)] for d in dict.fromkeys(deps)]}


def _from_document(doc: dict[str, Any] | None) -> LoadedWorld | None:
    """Rebuild a cached world; None when absent, stale or of another layout."""
    if not doc:
        return None
    try:
        if any(_stat(path) != [size, mtime] for path, size, mtime in doc["deps"]):
            return None
        plan = doc["plan"]
        bodies = tuple(StaticBody(**{
            **body, "xyz": tuple(body["xyz"]), "quat": tuple(body["quat"]),
            "shapes": tuple(StaticShape(**{**s, "size": tuple(s["size"]), "xyz": tuple(s["xyz"]),
                                           "quat": tuple(s["quat"])}) for s in body["shapes"])})
            for body in plan["bodies"])
        robots = tuple(WorldRobot(**{**r, "xyz": tuple(r["xyz"]), "quat": tuple(r["quat"]),
                                     "notices": tuple(r["notices"])}) for r in doc["robots"])
        actors = tuple(MoverPlan(**{**a, "size": tuple(a["size"]), "keyframes": tuple(tuple(k) for k in a["keyframes"]),
                                    "curves": tuple(tuple(c) for c in a["curves"]), "region": None, "start": None})
                       for a in plan.get("actors", ()))
        plan = WorldPlan(**{**plan, "bodies": bodies, "robot_models": tuple(plan["robot_models"]), "actors": actors})
        return LoadedWorld(plan=plan, robots=robots,
                           static_models=tuple(doc["static_models"]), summary=doc["summary"],
                           notices=tuple(doc["notices"]))
    except (KeyError, TypeError, ValueError):
        return None
