"""How much of its step a robot can make (``fit``): the kinematic engine's one collision answer.

The robot is tried at the end of its step (one query, nearly always enough), then where it
stands, then by conservative advancement and bisection; robots whose footprints are farther
away than a try needs to know (footprint.py) are not asked of PyBullet.
"""

from __future__ import annotations

from mobot_cli.sim.contacts import CONTACT_SLOP
from mobot_cli.sim.kinematic.body import Mover
from mobot_cli.sim.kinematic.collide import QUERY_REACH, Near, distances, nearest
from mobot_cli.sim.kinematic.footprint import apart_from
from mobot_cli.sim.kinematic.seen import Seen

# How far a robot may end up inside another body (m): the bisection stops within this.
PENETRATION = 0.001
BISECTIONS = 8  # a 0.1 m step is resolved to 0.4 mm
# A blocked robot makes no move shorter than this (it would creep into the tolerance forever).
MIN_MOVE = 1e-4  # m


def fit(cid: int, mover: Mover, distance: float, turn: float, others: list[Mover], near: Near,
        bodies: list[int], seen: Seen):
    """The largest part of the step (1.0 when all of it) that does not push the robot into
    anything deeper than PENETRATION (or than it already is), and the distances there (a
    ``distances`` answer); the robot's body is left there. ``others``: the robots it might
    touch, ``near``: the static bodies around it (found already), ``bodies``: movers' bodies,
    ``seen``: what its queries found before (seen.py)."""
    body, z, reach = mover.robot.body, mover.z, mover.reach + QUERY_REACH
    robots = [other.robot.body for other in others] + bodies
    shaped = apart_from(mover, others)

    def at(fraction: float, limit: float = CONTACT_SLOP):
        x, y, yaw = mover.target(distance, turn, fraction)
        mover.place(x, y, z, yaw)
        # Robots whose footprints are farther than ``limit``: not asked. Past CONTACT_SLOP none
        # is touched, nor in the way (every try below compares with a floor under zero).
        known = shaped(x, y, yaw, limit) if shaped is not None else {}
        key = (x, y, z, yaw, mover.floor)
        static, before = seen.recall(key, others, known)
        found = distances(cid, body, near.within(x, y, reach), robots, QUERY_REACH, mover.floor,
                          {**before, **known}, static, near.groups)
        seen.keep(key, found, robots, known, bodies)
        return found

    full = at(1.0)
    if nearest(full) >= -PENETRATION or mover.bound == 0.0:
        return 1.0, full
    # Where it stands the nearest distance itself counts (``safe``), unless it is more than the
    # step: then no try short of the whole step is safe by it, whichever it is.
    here = at(0.0, max(CONTACT_SLOP, mover.bound))
    floor = min(-PENETRATION, nearest(here))  # already deeper: it may not go deeper still
    if nearest(full) >= floor:
        at(1.0)
        return 1.0, full
    lo, hi, best = 0.0, 1.0, here
    # Conservative advancement first: no point of the robot moves more than ``bound`` over
    # the whole step, so the part of it within the clearance here (and the tolerance) is
    # safe. Approaching a wall or a robot head-on, that is all the way: one query.
    bound = mover.bound  # no point of the robot moves farther in the whole step
    safe = (nearest(here) - floor) / bound if bound > 0.0 else 0.0
    if safe * bound < MIN_MOVE:  # pressed against it already: stay put (and be stuck)
        mover.place(mover.x, mover.y, z, mover.yaw)
        return 0.0, here
    if safe < 1.0:
        found = at(safe)
        if nearest(found) >= floor:
            x, y, yaw = mover.target(distance, turn, safe)
            mover.place(x, y, z, yaw)
            return safe, found
        hi = safe
    for _ in range(BISECTIONS):
        mid = (lo + hi) / 2.0
        found = at(mid)
        if nearest(found) >= floor:
            lo, best = mid, found
        else:
            hi = mid
    x, y, yaw = mover.target(distance, turn, lo)
    mover.place(x, y, z, yaw)
    return lo, best
