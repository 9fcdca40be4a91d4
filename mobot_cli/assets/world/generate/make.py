"""Making a generated world: the kind's module with a seeded NumPy generator, then its SDF
text and the LoadedWorld the run needs."""

from __future__ import annotations

from typing import Any

from mobot_cli.assets.world.generate.shapes import Generated

KINDS = ("barn", "boxes", "maze", "rooms")
GENERATED_FILE = "generated.world"  # the run folder's copy of a generated world


def _module(kind: str):
    from mobot_cli.assets.world.generate import barn, boxes, maze, rooms  # the kinds, each a module

    return {"barn": barn, "boxes": boxes, "maze": maze, "rooms": rooms}[kind]


def generate(kind: str, seed: int, params: dict[str, Any]) -> Generated:
    """The world of ``kind`` for ``seed`` and the kind's ``params`` (all given, validated)."""
    import numpy as np

    module = _module(kind)
    rng = np.random.Generator(np.random.PCG64(seed))
    obstacles, info = module.generate(rng, **params)
    return Generated(name=f"{kind}_{seed}", obstacles=tuple(obstacles), info=info)


def parameters(kind: str) -> dict[str, Any]:
    """The parameters ``kind`` takes and their defaults, in order (seed aside)."""
    import inspect

    module = _module(kind)
    return {name: p.default for name, p in inspect.signature(module.generate).parameters.items() if name != "rng"}



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
