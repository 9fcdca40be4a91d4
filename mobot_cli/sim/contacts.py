"""Collision events: a robot touching anything but what it stands on.

A collision is counted once when a robot starts touching another body, not once per step
it stays in touch. Floors need no list: a contact whose normal points up into the robot
(steeper than SUPPORT_NORMAL_Z) is the robot resting on something - the ground plane, a
mesh floor, a ramp - and is support, not a collision. Contacts between two robots always
count, for both robots.
"""

from __future__ import annotations

import math
from typing import Callable, Hashable, Iterable, Protocol

from mobot_cli.sim.pb import p

# Contacts are sampled at this rate, not every step: one getContactPoints call for the whole
# world per sample keeps the step loop within a few percent of raw PyBullet.
CONTACT_RATE_HZ = 50
# |normal z| above this (about 45 degrees from vertical) and pointing up into the robot:
# the robot is standing on the other body.
SUPPORT_NORMAL_Z = 0.7
# Manifold points can be reported a little before bodies touch; closer than this is touching.
CONTACT_SLOP = 1e-3  # m
# The edges of a mesh floor's own triangles: beside the triangle a wheel stands on, PyBullet
# reports its neighbours' edges and corners a fraction of a millimetre away, their normals
# anywhere from vertical to horizontal (the huge floor triangles of Clearpath's office world,
# AWS's hospital). A point of a body the robot stands on, no higher than this above its support
# in the same sample or query, is floor too (below the 0.02 m where maps count obstacles; a
# wall of the same mesh still counts above it).
SEAM = 0.01  # m
# A contact counts as support only this close above the robot's lowest point: a wheel rolls
# onto a low step, but a floor rising into the chassis is in the way. A static body no higher
# than this above the robot's lowest point is floor (a rug, a threshold strip): the map counts
# obstacles from the same height (assets/world/floorplan.py's BAND).
SUPPORT_BAND = 0.02  # m
# A pair must be apart for this many samples (0.1 s at 50 Hz) before touching again counts as
# a new collision, so solver jitter in one long scrape along a wall is not many collisions.
RELEASE_SAMPLES = 5


class Counted(Protocol):
    """What the counter needs of a robot: its name, body and a running count."""

    name: str
    body: int
    collisions: int
    hit: str  # what its last collision was with (the counter's ``name_of``)


class ContactCounter:
    """Counts collision events per robot; call ``sample`` at a fixed rate."""

    def __init__(self, release_samples: int = RELEASE_SAMPLES,
                 name_of: Callable[[Hashable], str] | None = None,
                 person: Callable[[Hashable], bool] | None = None) -> None:
        self._name_of = name_of  # ("body", uid) or ("robot", name) -> how records name it
        self._person = person  # True for what is a person (a mover): counted apart as well
        self._samples = 0
        self._release = release_samples
        self._last_touch: dict[tuple[str, Hashable], int] = {}

    def sample(self, cid: int, robots: Iterable[Counted]) -> None:
        """Look at the world's contacts now and add new collision events to the robots."""
        self._samples += 1
        by_body = {robot.body: robot for robot in robots}
        if not by_body:
            return
        touching: set[tuple[Counted, Hashable]] = set()
        # (robot, world body) -> its highest support point: the chunks of a mesh split into
        # several PyBullet bodies are one floor (named alike)
        supports: dict[tuple[Counted, Hashable], float] = {}
        steep: list[tuple[Counted, int, float]] = []  # (robot, body, height of the body's point)
        group = self._group
        for contact in p.getContactPoints(physicsClientId=cid):
            ra, rb = by_body.get(contact[1]), by_body.get(contact[2])
            if (ra is None and rb is None) or contact[8] > CONTACT_SLOP:
                continue
            if ra is not None and rb is not None:
                if ra is not rb:
                    touching.add((ra, ("robot", rb.name)))
                    touching.add((rb, ("robot", ra.name)))
                continue
            # contactNormalOnB points from B towards A: turn it to point from the other body
            # into the robot.
            robot, other, up, height = (ra, contact[2], contact[7][2], contact[6][2]) if ra is not None \
                else (rb, contact[1], -contact[7][2], contact[5][2])
            if up > SUPPORT_NORMAL_Z:
                key = (robot, group(other))
                supports[key] = max(supports.get(key, -math.inf), height)
                continue
            steep.append((robot, other, height))
        for robot, other, height in steep:
            if height > supports.get((robot, group(other)), -math.inf) + SEAM:  # not an edge of its floor's triangles
                touching.add((robot, ("body", other)))
        self._count(touching)

    def _group(self, uid: int) -> Hashable:
        """The world body a PyBullet body is part of: its name, when the counter knows names."""
        return self._name_of(("body", uid)) if self._name_of is not None else uid

    def record(self, touching: Iterable[tuple[Counted, Hashable]]) -> None:
        """One sample of pairs found touching by other means (the kinematic engine's queries):
        (robot, ("body", uid)) or (robot, ("robot", name)), both sides of a robot pair given."""
        self._samples += 1
        self._count(touching)

    def idle(self, samples: int = 1) -> None:
        """``samples`` samples in which nothing touched (the kinematic engine tells them in a lump,
        before its next sample that has touches)."""
        self._samples += samples

    def _count(self, touching: Iterable[tuple[Counted, Hashable]]) -> None:
        # In name order, not the set's (robots hash by address): when two touches start in one
        # sample, which one a robot's ``hit`` names is the same in every run.
        for robot, other in sorted(touching, key=lambda pair: (pair[0].name, pair[1])):
            key = (robot.name, other)
            last = self._last_touch.get(key)
            if last is None or self._samples - last > self._release:
                robot.collisions += 1
                if self._person is not None and self._person(other):
                    robot.people_collisions += 1
                if self._name_of is not None:
                    robot.hit = self._name_of(other)
            self._last_touch[key] = self._samples

    def mark(self) -> tuple:
        """What the counter remembers now, for ``restore`` (sim/bullet/settled.py)."""
        return self._samples, dict(self._last_touch)

    def restore(self, mark: tuple) -> None:
        """Remember again what ``mark`` gave."""
        self._samples, touches = mark
        self._last_touch = dict(touches)

    def forget(self, name: str) -> None:
        """Drop a removed robot's pairs (PyBullet may reuse its body id)."""
        self._last_touch = {k: v for k, v in self._last_touch.items()
                            if k[0] != name and k[1] != ("robot", name)}
