"""Worlds made from a seed (``world: {generate: {kind: ..., seed: N}}``): obstacles as plain
shapes, the same for one seed on any machine (NumPy's PCG64 through ``Generator.random`` and
``Generator.integers``), written as an SDF world (sdf.py) and turned into the WorldPlan that
loading that file gives (plan.py).

Each kind is one module with a ``generate(rng, **params)`` returning its obstacles; the
parameters arrive validated (scenario/world_model.py).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

KINDS = ("barn", "boxes", "maze", "rooms")


@dataclass(frozen=True)
class Obstacle:
    """One static shape standing on the floor: a box (size x, y, z) or a cylinder (radius, length)."""

    name: str
    kind: str  # "box" | "cylinder"
    size: tuple[float, ...]
    x: float
    y: float
    yaw: float = 0.0

    @property
    def height(self) -> float:
        return self.size[2] if self.kind == "box" else self.size[1]


@dataclass(frozen=True)
class Generated:
    """A generated world: its name, obstacles, and what else the kind knows (BARN's free path)."""

    name: str
    obstacles: tuple[Obstacle, ...]
    info: dict[str, Any] = field(default_factory=dict)


def generate(kind: str, seed: int, params: dict[str, Any]) -> Generated:
    """The world of ``kind`` for ``seed`` and the kind's ``params`` (all given, validated)."""
    import numpy as np

    from mobot_cli.assets.world.generate import barn, boxes, maze, rooms

    module = {"barn": barn, "boxes": boxes, "maze": maze, "rooms": rooms}[kind]
    rng = np.random.Generator(np.random.PCG64(seed))
    obstacles, info = module.generate(rng, **params)
    return Generated(name=f"{kind}_{seed}", obstacles=tuple(obstacles), info=info)


def rounded(value: float) -> float:
    """A coordinate as the world file writes it (6 decimals), so that the plan made here and the
    plan loaded from the file hold the same numbers."""
    return float(f"{value:.6f}") + 0.0


def parameters(kind: str) -> dict[str, Any]:
    """The parameters ``kind`` takes and their defaults, in order (seed aside)."""
    import inspect

    from mobot_cli.assets.world.generate import barn, boxes, maze, rooms

    module = {"barn": barn, "boxes": boxes, "maze": maze, "rooms": rooms}[kind]
    return {name: p.default for name, p in inspect.signature(module.generate).parameters.items() if name != "rng"}


GENERATED_FILE = "generated.world"  # the run folder's copy of a generated world


def load_generated(kind: str, seed: int, params: dict[str, Any]):
    """A generated world ready for the simulation (a LoadedWorld) and its SDF text."""
    from mobot_cli.assets.world.generate.sdf import to_plan, to_sdf
    from mobot_cli.assets.world.loaded import LoadedWorld

    world = generate(kind, seed, params)
    spec = ", ".join(f"{k}: {_flow(v)}" for k, v in {"kind": kind, "seed": seed, **params}.items())
    text = to_sdf(world, f"made by mobot from world: {{generate: {{{spec}}}}}")
    counts: dict[str, int] = {}
    for o in world.obstacles:
        counts[o.kind] = counts.get(o.kind, 0) + 1
    summary = {"kind": "world", "name": world.name, "generated": {"kind": kind, "seed": seed, **params},
               "models": len(world.obstacles) + 1, "static_models": len(world.obstacles) + 1,
               "shapes": dict(sorted(counts.items())), "ground_plane": True}
    loaded = LoadedWorld(plan=to_plan(world), static_models=("ground_plane", *(o.name for o in world.obstacles)),
                         summary=summary, notices=tuple(world.info.get("notices", ())))
    return loaded, text


def _flow(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_flow(v) for v in value) + "]"
    return f"{value:g}" if isinstance(value, float) else str(value)
