"""A settled robot kept with its body: a Gymnasium reset puts the settle's end back instead of stepping.

Every reset of a Gymnasium env spawns the same robot at the same pose in the same world and lets it
settle (0.5 s: 120 physics steps at 240 Hz, most of what a reset costs). With nothing else in
the world and nothing drawn from the seed, those steps end in the same state every time. So the
first settle's end is kept with the kept robot body (kept_body.py): PyBullet's ``saveState`` (in
memory; it holds the bodies' positions and velocities and the contact points whose impulses
warm-start the solver: restoreState runs the collision pass at the restored poses and gives each
manifold of a body pair its saved points, and empties one with none saved, so nothing of the
episode before warm-starts the next) and the numbers the World's Python side changed meanwhile (the step count, the
robot's odometry, its health watch, the contact counter, the notices said, the timeline's
marks). The next World built the same way, with the same robot spawned at step 0, restores them
instead of stepping (``resettle``); episodes are byte for byte those of a settle that steps
(tests/gym/test_settled.py).

Only what is provably the same is kept: a World with one robot, the kept body, nothing else
spawned and no step taken before the settle; no sensors (their noise is drawn from the seed), no
movers or actors, no clearance watch; a plain wheel drive (or none) without twist feedback,
acceleration ramps or springs; a kept body and a key (the settle's steps, the robot's plan,
the physics, the world and the timeline's log cadence) equal to the first. Anything else
settles by stepping, as before. Not in a saved state: the motor torques applied in the last step
(``getJointStates``' fourth value), an output of that step that the next step replaces; mobot
reads them only after a step.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Optional

from mobot_cli.sim.bullet.robot import _Drive
from mobot_cli.sim.pb import p


@dataclass(frozen=True)
class Settled:
    """A settle's end: PyBullet's saved state and the Python side's numbers."""

    key: Any
    state: int  # a p.saveState id
    steps: int
    notices: tuple[str, ...]
    robot: tuple  # cmd, cmd_y, collisions, hit, people_collisions
    drive: Optional[tuple]  # odometry x, y, yaw; last wheel positions; integrated_at; rates, goal, twist, trim_from
    watch: Any  # faults.Watch
    contacts: Any  # ContactCounter.mark()
    marks: Any  # the timeline's (opaque here)


class Settling:
    """What a World does with a kept settle (the base sim/bullet/world.py's World takes it from);
    the World has ``_cid``, ``physics``, ``plan``, ``notices``, ``_steps``, ``_robots``,
    ``_kept`` (kept_body.KeptBody or None), ``_health``, ``_contacts`` and the lists and
    parts ``_settled_robot`` looks at."""

    def settle_key(self, steps: int, cadence: Any) -> Optional[tuple]:
        """What a settle of ``steps`` from now depends on, or None when it cannot be kept: not at
        step 0, or not a world whose state a Settled holds whole."""
        robot = self._settled_robot()
        if robot is None or self._steps != 0 or steps <= 0:
            return None
        return steps, robot.plan, self.physics, self.plan, cadence

    def keep_settled(self, key: tuple, marks: Any) -> None:
        """Keep the state now, the end of the settle ``key`` (settle_key), with the kept body."""
        robot = self._settled_robot()
        if robot is None or self._steps != key[0]:
            return
        drop(self._cid, self._kept.settled)  # another settle's: one kept end per body
        drive = robot.drive
        numbers = None if drive is None else (
            (drive.odometry.x, drive.odometry.y, drive.odometry.yaw), list(drive.last), drive.integrated_at,
            list(drive.rates), list(drive.goal), drive.twist, drive.trim_from)
        saved = Settled(key, p.saveState(physicsClientId=self._cid), self._steps, tuple(self.notices),
                        (robot.cmd, robot.cmd_y, robot.collisions, robot.hit, robot.people_collisions), numbers,
                        dataclasses.replace(self._health.watches[robot.name]), self._contacts.mark(), marks)
        self._kept = dataclasses.replace(self._kept, settled=saved)

    def resettle(self, key: Optional[tuple]) -> Any:
        """Put back the kept end of the settle ``key`` instead of stepping; its timeline's marks,
        or None (nothing done: there is none for ``key``)."""
        saved = self._kept.settled if key is not None and self._kept is not None else None
        if saved is None or saved.key != key:
            return None
        robot = self._settled_robot()
        p.restoreState(stateId=saved.state, physicsClientId=self._cid)
        self._steps = saved.steps
        self.notices[:] = saved.notices
        robot.cmd, robot.cmd_y, robot.collisions, robot.hit, robot.people_collisions = saved.robot
        if saved.drive is not None:
            drive = robot.drive
            (x, y, yaw), last, drive.integrated_at, rates, goal, drive.twist, drive.trim_from = saved.drive
            drive.odometry.x, drive.odometry.y, drive.odometry.yaw = x, y, yaw
            drive.last, drive.rates, drive.goal = list(last), list(rates), list(goal)
        self._health.watches[robot.name] = dataclasses.replace(saved.watch)
        self._contacts.restore(saved.contacts)
        return saved.marks

    def _settled_robot(self):
        """The world's one robot when the world's state is one a Settled holds whole, else None."""
        if self.physics.engine != "bullet" or self._kept is None or len(self._robots) != 1:
            return None
        robot = next(iter(self._robots.values()))
        plain = robot.drive is None or (type(robot.drive) is _Drive and robot.drive.trim is None)
        if (robot.body != self._kept.body or not plain or self._sensing is not None or self._stage is not None
                or self._clearance or self._ramping or self._sprung or self._pushed):
            return None
        return robot


def drop(cid: int, saved: Optional[Settled]) -> None:
    """Free a kept settle's saved state."""
    if saved is not None:
        p.removeState(saved.state, physicsClientId=cid)
