"""Gazebo ``<actor>``s: their scripted trajectory and a collision shape, as MoverPlans.

Gazebo plays an actor's ``<script>``: its ``<trajectory>``s one after the other, each from its
first ``<waypoint>`` (``<time>``, a world ``<pose>``) to its last, the pose between waypoints on
gz-common's PoseAnimation splines with the trajectory's ``tension`` (sim/movers/spline.py);
``<delay_start>`` s of waiting first (again before every round when it ``<loop>``s, as gazebo
classic's Actor.cc resets its play time), ``<auto_start>`` false waits for a plugin to start it.
The skin is not simulated: an actor collides as its first link's box, cylinder or capsule
collision when it has one, else as a person-sized capsule standing on the floor under it
(docs/movers.md).
"""

from __future__ import annotations

import math
from pathlib import Path

from mobot_cli.assets.world.frames import is_number, key_of, truthy
from mobot_cli.errors import WorldError
from mobot_cli.plan import MoverPlan

PERSON_RADIUS = 0.3  # m: the capsule an actor without a collision of its own collides as
PERSON_HEIGHT = 1.7  # m


def read_actor(element, file: Path, pose_of) -> tuple[MoverPlan | None, str]:
    """The actor as a MoverPlan (None when it has no trajectory to play) and a notice about it.
    ``pose_of(element)`` parses a <pose> element to a 4x4 matrix (the reader's, located errors)."""
    name = element.get("name", "actor")
    frames: list[tuple[float, float, float, float]] = []
    curves: list[tuple[int, int, float]] = []
    offset = 0.0
    for trajectory in element.findall("script/trajectory"):
        points = {}
        for waypoint in trajectory.findall("waypoint"):
            text = (waypoint.findtext("time") or "").strip()
            if not is_number(text):
                raise WorldError(f"actor '{name}': a <waypoint> has no numeric <time>", location=key_of(waypoint, file),
                                 hint="Give each waypoint <time>SECONDS</time> and a <pose>.")
            pose = waypoint.find("pose")
            matrix = pose_of(pose)
            points[float(text)] = (float(matrix[0][3]), float(matrix[1][3]), _yaw(pose, matrix))  # one per time
        if not points:
            continue
        times = sorted(points)
        # Gazebo plays a trajectory from its first waypoint, the next one where this one ends.
        frames += [(offset + t - times[0], *points[t]) for t in times]
        curves.append((len(frames) - len(times), len(frames) - 1, _tension(trajectory, file)))
        offset += times[-1] - times[0]
    if not frames:
        return None, f"actor '{name}' has no <script><trajectory> waypoints: it is left out"
    script = element.find("script")
    delay = _number(script, "delay_start", 0.0, file)
    loop = truthy((script.findtext("loop") or "true").strip())
    auto = truthy((script.findtext("auto_start") or "true").strip())
    shape, size = _shape(element)
    notice = (f"actor '{name}' collides as a {_describe(shape, size)} (its skin is not simulated)"
              + ("" if auto else "; <auto_start> is false and nothing starts it: it stands at its first waypoint"))
    return MoverPlan(name=name, shape=shape, size=size, keyframes=tuple(frames), loop=loop, delay=delay,
                     auto_start=auto, source="actor", curves=tuple(curves)), notice


def _yaw(pose, matrix) -> float:
    """The heading as the file writes it when the pose is a plain x y z 0 0 yaw (Gazebo's spline
    follows the quaternion of that yaw, and 3.142 is not -3.141 there), else from the rotation."""
    parts = (pose.text or "").split() if pose is not None else []
    if len(parts) == 6 and not pose.attrib and all(is_number(v) for v in parts) and \
            float(parts[3]) == 0.0 and float(parts[4]) == 0.0:
        return float(parts[5])
    return math.atan2(matrix[1][0], matrix[0][0])


def _tension(trajectory, file: Path) -> float:
    """The <trajectory tension="..."> of its spline (SDF's default 0), clamped to [0, 1] as Gazebo does."""
    text = trajectory.get("tension", "0").strip()
    if not is_number(text):
        raise WorldError(f"tension '{text}' is not a number", location=key_of(trajectory, file),
                         hint="Write a decimal number between 0 and 1 (0: Catmull-Rom, 1: no overshoot).")
    return min(max(float(text), 0.0), 1.0)


def _number(parent, tag: str, default: float, file: Path) -> float:
    element = parent.find(tag) if parent is not None else None
    if element is None or not (element.text or "").strip():
        return default
    if not is_number(element.text):
        raise WorldError(f"<{tag}> '{element.text.strip()}' is not a number", location=key_of(element, file),
                         hint="Write a plain decimal number of seconds.")
    return max(0.0, float(element.text))


def _shape(element) -> tuple[str, tuple[float, ...]]:
    """The first link's box, cylinder or capsule collision (upright, at the actor's pose), else a person."""
    geometry = element.find("link/collision/geometry")
    if geometry is not None:
        box = geometry.findtext("box/size")
        if box and len(box.split()) == 3 and all(is_number(v) for v in box.split()):
            return "box", tuple(float(v) for v in box.split())
        for kind, shape in (("cylinder", "cylinder"), ("capsule", "person")):
            radius, length = geometry.findtext(f"{kind}/radius"), geometry.findtext(f"{kind}/length")
            if is_number(radius) and is_number(length):
                r, h = float(radius), float(length)
                return shape, (r, h + (2.0 * r if kind == "capsule" else 0.0))
    return "person", (PERSON_RADIUS, PERSON_HEIGHT)


def _describe(shape: str, size: tuple[float, ...]) -> str:
    if shape == "box":
        return "box {:g} x {:g} x {:g} m".format(*size)
    kind = "capsule" if shape == "person" else "cylinder"
    return f"{kind} of radius {size[0]:g} m, {size[1]:g} m tall"
