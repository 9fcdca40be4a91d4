"""What a robot's queries found at a pose, asked again only where something there changed.

A blocked robot tries the same poses step after step (the end of its step, where it stands)
while the robots around it shuffle. At a pose it was asked at before, the static bodies'
answer is the same, and so is each robot's that has not moved since (Mover.moved, a tick of
the World's clock): PyBullet is asked only about the robots that moved. Anything that can move
a body's links without moving the robot (a sensor's full sync, a teleport, a spawn or removal)
starts a new epoch, and everything kept is forgotten.
"""

from __future__ import annotations

# Poses kept per robot (a blocked robot returns to two: the end of its step and where it stands).
KEEP = 8


class Seen:
    """One robot's answers by pose (x, y, z, yaw, floor), valid within an epoch."""

    def __init__(self) -> None:
        self.epoch = -1
        self.clock = 0  # the World's clock now (set before each fit)
        self.answers: dict[tuple, tuple] = {}  # pose -> (tick, (nearest static, touched statics), {robot: distance})

    def start(self, epoch: int, clock: int) -> None:
        """Before a fit: the World's epoch and clock now."""
        if epoch != self.epoch:
            self.epoch, self.answers = epoch, {}
        self.clock = clock

    def recall(self, key: tuple, others: list, known: dict) -> tuple:
        """(the static answer, or None), {robot body: distance} of the robots not moved since."""
        answer = self.answers.get(key)
        if answer is None:
            return None, {}
        tick, static, robots = answer
        return static, {o.robot.body: robots[o.robot.body] for o in others
                        if o.robot.body in robots and o.robot.body not in known and o.moved <= tick}

    def keep(self, key: tuple, found: tuple, robots: list[int], known: dict, bodies: list[int]) -> None:
        """Keep a ``distances`` answer at a pose: the static part, and the robots' exact distances
        (not the lower bounds in ``known``, nor movers' bodies, which move on their own)."""
        low_static, apart, touching = found
        if len(self.answers) >= KEEP:
            self.answers = {}
        asked = set(robots)
        static = (low_static, frozenset(b for b in touching if b not in asked))
        exact = {b: d for b, d in apart.items() if b not in known and b not in bodies}
        old = self.answers.get(key)
        if old is not None and old[0] == self.clock:  # asked twice at one tick: keep both
            exact = {**old[2], **exact}
        self.answers[key] = (self.clock, static, exact)
