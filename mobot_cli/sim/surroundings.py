"""What surrounds a freshly spawned robot: is it inside a piece of furniture, or under the floor?

Penetration tests (placement.check_clear) miss both cases when the world is made of triangle
meshes, which have no inside: a robot inside a wardrobe, or wholly below a mesh floor,
touches no triangle. Rays do see them. A ray from inside a closed surface crosses it an odd
number of times in every direction; a ray from outside crosses it an even number of times.
"""

from __future__ import annotations

from mobot_cli.errors import SpawnError
from mobot_cli.sim.pb import p
from mobot_cli.sim.placement import (
    MAX_CROSSINGS,
    MAX_SPAWN_PENETRATION,
    RAY_REACH,
    RAY_STEP,
    Bounds,
    Part,
    _at,
    _part_text,
    no_part,
)

# Up and the four horizontal directions; down is left out: below a robot is its floor, and a
# ground plane (a half space) is "crossed" once by any ray going down.
DIRECTIONS = ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0),
              (0.0, -1.0, 0.0))


# Rays see static bodies only (PyBullet's collision filter group of bodies without mass): a ray
# from inside a robot's convex shape finds it again at every RAY_STEP, and would walk through a
# neighbouring robot in MAX_CROSSINGS tiny steps, never reaching the world behind it.
STATIC_GROUP = 2


def surfaces_along(cid: int, origins, directions) -> list[list[tuple[int, float]]]:
    """For each ray (origin, direction), the (body, distance) of every static surface it crosses."""
    found: list[list[tuple[int, float]]] = [[] for _ in origins]
    starts = [tuple(o) for o in origins]
    travelled = [0.0] * len(origins)
    live = list(range(len(origins)))
    for _ in range(MAX_CROSSINGS):
        if not live:
            break
        ends = [tuple(s + d * (RAY_REACH - travelled[i]) for s, d in zip(starts[i], directions[i]))
                for i in live]
        hits = p.rayTestBatch([starts[i] for i in live], ends, collisionFilterMask=STATIC_GROUP, physicsClientId=cid)
        still = []
        for i, hit in zip(live, hits):
            if hit[0] < 0:
                continue
            step = hit[2] * (RAY_REACH - travelled[i])
            travelled[i] += step + RAY_STEP
            found[i].append((hit[0], travelled[i] - RAY_STEP))
            starts[i] = tuple(h + d * RAY_STEP for h, d in zip(hit[3], directions[i]))
            if travelled[i] < RAY_REACH:
                still.append(i)
        live = still
    return found


def _centre(box: Bounds) -> tuple[float, float, float]:
    lo, hi = box
    return ((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2)


def check_not_inside(cid: int, solids: dict[int, str], name: str, xyz, box: Bounds,
                     part: Part = no_part) -> None:
    """Refuse a robot (bounds ``box``) whose centre lies inside a static body's closed surface;
    ``part`` says which part of it."""
    if not solids:
        return
    centre = _centre(box)
    up = surfaces_along(cid, [centre], [DIRECTIONS[0]])[0]
    first = next((b for b, _ in up if b in solids), None)
    if first is None:
        return
    rays = surfaces_along(cid, [centre] * len(DIRECTIONS), DIRECTIONS)
    if all(sum(1 for b, _ in ray if b == first) % 2 == 1 for ray in rays):
        raise SpawnError(f"robot '{name}' spawned at {_at(xyz)} is inside {solids[first]}"
                         + _part_text(part(first)), hint="Move the robot clear of it.")


def _aside(text: str) -> str:
    return f" ({text})" if text else ""


def check_above_floor(cid: int, floors: dict[int, str], name: str, xyz, box: Bounds,
                      part: Part = no_part) -> None:
    """Refuse a robot (bounds ``box``) with no floor below it but a floor above its lowest point;
    ``part`` says which part of that floor."""
    if not floors:
        return
    lo = box[0]
    x, y, _ = _centre(box)
    start = (x, y, lo[2] + MAX_SPAWN_PENETRATION)  # a few millimetres into the floor is fine
    down, up = surfaces_along(cid, [start, start], [(0.0, 0.0, -1.0), (0.0, 0.0, 1.0)])
    if any(b in floors for b, _ in down):
        return
    above = next(((b, d) for b, d in up if b in floors), None)
    if above is not None:
        raise SpawnError(
            f"robot '{name}' spawned at {_at(xyz)} is below the floor: {floors[above[0]]}"
            f"{_aside(part(above[0]))} is above its lowest point and nothing is below it",
            hint="Raise z, or use z: auto to rest it on the floor.")
