"""Which robots a robot being placed might reach into: a broad phase for spawn checks.

A spawn (and a teleport) is refused when the robot reaches more than a centimetre into another
body, which PyBullet measures pair by pair (placement.check_clear, ~10 us a pair). Asked of
every robot already there, a fleet of N costs N^2 / 2 pairs: 1,000 robots, 500,000 queries.
Penetration needs the two bodies' boxes to overlap, so only the robots whose boxes (PyBullet's
link AABBs, a millimetre loose, widened by SLACK more) meet the new one's are asked: the same
refusals, with the same messages, in the same order.

The boxes are measured once and kept while nothing moves: until the world steps (its step count
changes), a robot is teleported or removed, or ``forget()`` is called (the kinematic engine calls
it when it puts bodies where their robots are with their wheels turned).
"""

from __future__ import annotations

from itertools import islice
from typing import Iterable

import numpy as np

from mobot_cli.sim.pb import p

SLACK = 0.01  # m added on every side: far more than any rounding of the boxes


def body_box(cid: int, body: int) -> tuple[list[float], list[float]]:
    """The union of a body's link AABBs."""
    lo, hi = p.getAABB(body, -1, physicsClientId=cid)
    lo, hi = list(lo), list(hi)
    for link in range(p.getNumJoints(body, physicsClientId=cid)):
        a, b = p.getAABB(body, link, physicsClientId=cid)
        for k in range(3):
            lo[k], hi[k] = min(lo[k], a[k]), max(hi[k], b[k])
    return lo, hi


class RobotBoxes:
    """The robots' boxes, in spawn order, kept while nothing moves (see the module)."""

    def __init__(self) -> None:
        self.forget()

    def forget(self) -> None:
        """Measure every box again at the next query."""
        self._at: int | None = None
        self._bodies: list[int] = []
        self._robots: list = []
        self._lo = np.empty((16, 3))
        self._hi = np.empty((16, 3))

    def _add(self, cid: int, robot) -> None:
        body = robot.body
        n = len(self._bodies)
        if n == len(self._lo):  # grow by doubling: a fleet costs linear time
            self._lo = np.concatenate([self._lo, np.empty_like(self._lo)])
            self._hi = np.concatenate([self._hi, np.empty_like(self._hi)])
        self._lo[n], self._hi[n] = body_box(cid, body)
        self._bodies.append(body)
        self._robots.append(robot)

    def near(self, cid: int, step: int, robots: Iterable, count: int, body: int) -> list:
        """Those of ``robots`` (``count`` objects with a ``body`` id, in spawn order) whose
        boxes meet ``body``'s, in that order. ``robots`` lists the robots measured before in the same
        order (a removal calls ``forget()``), and may end with new ones: only those are looked at."""
        if self._at != step or len(self._bodies) > count:
            self.forget()
            self._at = step
        for other in islice(robots, len(self._bodies), None):  # skips the known ones in C
            self._add(cid, other)
        n = len(self._bodies)
        if not n:
            return []
        lo, hi = body_box(cid, body)
        lo_b, hi_b = np.array(lo) - SLACK, np.array(hi) + SLACK
        # Apart on some axis: one box ends before the other starts (NaN is never apart: asked).
        apart = ((self._hi[:n] < lo_b) | (self._lo[:n] > hi_b)).any(axis=1)
        return [self._robots[i] for i in np.flatnonzero(~apart).tolist() if self._bodies[i] != body]
