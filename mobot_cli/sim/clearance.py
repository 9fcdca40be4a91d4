"""Clearance: how close a robot's geometry comes to the world's geometry and to other robots.

Measured from the collision shapes (PyBullet's closest points), not from any sensor, so it
works for robots without sensors. What the robot stands on does not count: a closest point
whose normal points steeply up into the robot (as sim/contacts.py tells support from
collision) is a floor, a ramp or a mesh floor. Nor do the edges of a mesh floor's own
triangles: beside the triangle a wheel or caster stands on, PyBullet reports the neighbours'
edges and corners millimetres away, their normals anywhere from vertical to horizontal (AWS's
hospital floor gave a clearance of 0.011 m in an open corridor). So a point on a body the robot
stands on, at the floor's height (within SEAM of its support in the same query), is floor too.
(A wall of the same mesh as the floor still counts above that height.) Bodies further than
``reach`` are not looked at: the answer is then +inf ("further than reach").
"""

from __future__ import annotations

import functools
import math
from typing import Callable, Container, Iterable

from mobot_cli.sim.contacts import SEAM, SUPPORT_BAND, SUPPORT_NORMAL_Z
from mobot_cli.sim.pb import p
from mobot_cli.sim.placement import body_top

# How much further than the tightest clearance asked for the distances are measured.
REACH_MARGIN = 0.5  # m
# The closest points are asked for within FIRST_REACH first, then GROWTH times as far each time,
# up to the reach, and link by link: PyBullet answers one point per triangle within the
# distance, so a dense mesh within the reach (a 23,000-triangle table, asked about by a robot's
# six links at once) is slow and overflows the answer's buffer, which crashes the process.
FIRST_REACH = 0.05  # m
GROWTH = 1.5


class Tops:
    """Bodies' highest points for ``nearest``, those of ``statics`` kept: they never move."""

    def __init__(self, statics: Container[int]):
        self.statics, self.kept = statics, {}

    def __call__(self, cid: int, uid: int) -> float:
        top = self.kept.get(uid)
        if top is None:
            top = body_top(cid, uid)
            if uid in self.statics:
                self.kept[uid] = top
        return top


def _gap(lo, hi, reach: float, box) -> float:
    """How far a body's bounding box lies from the robot's (``lo``/``hi`` are the robot's box
    grown by ``reach``): a lower bound of its distance, 0 when they overlap."""
    d = [max(box[0][i] - (hi[i] - reach), (lo[i] + reach) - box[1][i], 0.0) for i in range(3)]
    return math.sqrt(sum(v * v for v in d))


def nearest(cid: int, body: int, reach: float, robots: Iterable[int], label: Callable[[int], str],
            meshes: Container[int] = (), top: Callable[[int, int], float] = body_top) -> tuple[float, str]:
    """The smallest distance (m, negative when overlapping) from ``body`` to anything within
    ``reach`` but its floor, and what that is; (inf, "") when nothing is that close. ``meshes``:
    the static bodies that hold triangle meshes (PyBullet answers them a point per triangle);
    ``top(cid, uid)``: a body's highest point (a World keeps its static bodies')."""
    links = range(-1, p.getNumJoints(body, physicsClientId=cid))
    boxes = [p.getAABB(body, link, physicsClientId=cid) for link in links]
    lo = [min(b[0][i] for b in boxes) - reach for i in range(3)]
    hi = [max(b[1][i] for b in boxes) + reach for i in range(3)]
    near = {uid for uid, _ in p.getOverlappingObjects(lo, hi, physicsClientId=cid) or ()} - {body}
    robots = set(robots)
    # body it stands on -> the height of its support; keyed by label: a mesh split into several
    # PyBullet bodies (sim/static_shapes.py) is one floor, its chunks' seams included
    floors: dict[str, float] = {}
    label = functools.lru_cache(maxsize=None)(label)
    # A static body wholly below the robot's support band is floor (a rug, a strip, a carpet mesh
    # laid under the floor's surface), as the map and the kinematic engine count it: not asked
    # about, its top the floor's height for the rest of its world body.
    tops = {uid: top(cid, uid) for uid in near - robots}
    low = min(b[0][2] for b in boxes) + SUPPORT_BAND  # the boxes hold margins: at most this low
    for uid in sorted(tops):
        if tops[uid] <= low:
            near.discard(uid)
            floors[label(uid)] = max(floors.get(label(uid), -math.inf), tops[uid])
    found: list[tuple[float, int, float]] = []
    dense = []  # the static triangle meshes near it
    for other in sorted(near):
        if other in meshes:
            dense.append(other)  # one point per triangle: asked for below, with care
        else:  # one point per pair of shapes: the whole robot at once
            _collect(p.getClosestPoints(body, other, reach, physicsClientId=cid), other, robots, floors, found, label)
    if dense:
        best = min((d for d, other, height in found if height > floors.get(label(other), -math.inf) + SEAM),
                   default=math.inf)
        _meshes(cid, body, links, lo, hi, reach, dense, min(reach, best), robots, floors, found, label)
    best, what = math.inf, ""
    # ... and measured from what it stands on (its box's margins lie lower): a body no higher
    # than the band above its highest support is floor too
    low = max(floors.values(), default=-math.inf) + SUPPORT_BAND
    for distance, other, height in found:
        if height <= floors.get(label(other), -math.inf) + SEAM or tops.get(other, math.inf) <= low:
            continue  # an edge of the floor's own triangles, or a body wholly within the band
        if distance < best:
            best, what = distance, label(other)
    return best, what


def _meshes(cid: int, body: int, links, lo, hi, reach: float, meshes: list[int], beyond: float, robots: set[int],
            floors: dict[str, float], found: list, label: Callable[[int], str]) -> None:
    """The closest points of static triangle meshes: link by link, within FIRST_REACH first and
    GROWTH times as far each time, until a point that is not floor turns up, or ``beyond`` (a
    nearer point already found elsewhere) or the reach is passed. Within a radius the meshes
    are asked nearest box first, each world body's pieces together, and each only within the
    nearest point found so far: a dense mesh further off (a 50,000-triangle cup on a table
    beside the robot) is not asked for every triangle it has within the radius."""
    gaps: dict[str, list[tuple[float, int]]] = {}
    for other in meshes:
        box = p.getAABB(other, -1, physicsClientId=cid)
        gaps.setdefault(label(other), []).append((_gap(lo, hi, reach, box), other))
    order = sorted((min(gap for gap, _ in pieces), name, sorted(pieces)) for name, pieces in gaps.items())
    radius = min(reach, FIRST_REACH)
    while True:  # the nearest point is among those within the smallest radius that finds one
        points: list[tuple[float, int, float]] = []
        heights: dict[str, float] = {}
        best = math.inf  # the nearest point found within this radius that is not floor
        for nearest_gap, name, pieces in order:
            if nearest_gap > min(radius, best, beyond):
                break  # this body's box, and every later one's, lies further than that
            start = len(points)
            for gap, other in pieces:
                distance = min(radius, best, beyond)
                if gap > distance:
                    continue
                for link in links:  # link by link: PyBullet overflows on too many points in one answer
                    _collect(p.getClosestPoints(body, other, distance, linkIndexA=link, physicsClientId=cid),
                             other, robots, heights, points, label)
            floor = heights.get(name, -math.inf) + SEAM  # this body's support, once all its pieces are asked
            best = min((d for d, _, height in points[start:] if height > floor), default=best)
        if radius >= min(reach, beyond) or best < math.inf:
            break
        radius = min(reach, radius * GROWTH)
    for other, height in heights.items():
        floors[other] = max(floors.get(other, -math.inf), height)
    found.extend(points)


def _collect(points, other: int, robots: set[int], floors: dict[str, float], found: list,
             label: Callable[[int], str]) -> None:
    """Sort closest points into what the robot stands on (floors, by label) and the rest (found)."""
    for point in points:
        distance, normal_up, height = point[8], point[7][2], point[6][2]  # normal on B: into ours
        if other not in robots and normal_up > SUPPORT_NORMAL_Z:
            key = label(other)
            floors[key] = max(floors.get(key, -math.inf), height)  # what it stands on
        else:
            found.append((distance, other, height))
