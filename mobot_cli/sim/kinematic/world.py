"""The kinematic engine: robots follow their commanded twist; nothing is simulated by PyBullet.

``physics: {engine: kinematic}``. The World's interface, records and checks are the physics
engine's (sim/bullet/world.py): robots are loaded, placed and checked the same way, sensors read the
same PyBullet bodies. What differs is ``step``: each robot's wheel rates ramp toward its
command (sim/kinematic/body.py) and the body moves along the exact arc they give, unless
its collision shapes would then overlap a static body or another robot more than
``PENETRATION``; then it makes the largest part of the step that does not (found by
bisection), or stays put. It rests on the highest floor under its footprint (it climbs what
its contacts count as support, sim/kinematic/collide.py) and keeps its spawn roll and pitch.
Touching counts as a collision exactly as in the physics engine (sim/contacts.py).

Cost: a robot in open space costs a few microseconds a step: the clearance measured at its
last query lets it move that far before PyBullet is asked again, and its PyBullet body is
moved only when something looks at it.
"""

from __future__ import annotations

import math

import numpy as np

from mobot_cli.errors import SimulationFault, SpawnError
from mobot_cli.plan import Physics, RobotPlan, SpawnPose, WorldPlan
from mobot_cli.sim.bullet.robot import HOLONOMIC, check_command
from mobot_cli.sim.bullet.world import World
from mobot_cli.sim.contacts import CONTACT_RATE_HZ, CONTACT_SLOP, RELEASE_SAMPLES, ContactCounter
from mobot_cli.sim.kinematic.body import Mover
from mobot_cli.sim.kinematic.collide import (
    NEAR_MARGIN,
    QUERY_REACH,
    SUPPORT_BAND,
    Floor,
    Near,
    feet,
    static_boxes,
)
from mobot_cli.sim.kinematic.fit import fit
from mobot_cli.sim.kinematic.footprint import rectangle, shape
from mobot_cli.sim.kinematic.holonomic import HolonomicMover
from mobot_cli.sim.kinematic.pairs import robot_pairs, touched_pairs
from mobot_cli.sim.placement import body_bounds, body_top
from mobot_cli.sim.state import RobotState

# The floor under a robot changes only by more than this (rays in float32 jitter below it).
FLOOR_TOLERANCE = 1e-6  # m


class KinematicWorld(World):
    """A World whose robots move kinematically (see the module's docstring)."""

    def __init__(self, physics: Physics, world: WorldPlan, seed: int = 0, fresh: bool = False):
        super().__init__(physics, world, seed, fresh)
        self._start_kinematics()

    def _start_kinematics(self) -> None:
        """The engine's own state for the world as built, with no robots yet."""
        physics, world = self.physics, self.plan
        self._movers: dict[str, Mover] = {}
        self._order: list[Mover] = []
        self._by_body: dict[int, object] = {}  # body id -> SimRobot, of the robots in _order
        # robot i, j -> their distance when last measured plus both travels then (-inf: never)
        self._measured = np.zeros((0, 0))
        self._room = self._measured  # _measured is its top-left corner (see _reindex)
        self._reach = np.zeros(0)
        self._rects: dict[tuple, tuple | None] = {}  # (URDF, joint positions) -> its footprint
        self._shapes = np.zeros((0, 4))  # footprints: centre x, y and half sizes (NaN: none), see pairs.py
        self._near: dict[str, Near] = {}
        self._floor = Floor(self._cid, world)
        self._flat = self._floor.flat and world.ground_plane  # the floor is z = 0 everywhere
        # static body -> the top of its box: one no higher than a robot's support band is floor
        self._tops = {uid: body_top(self._cid, uid) for uid in self._statics if uid != self._ground}
        self._boxes = static_boxes(self._cid, world, [uid for uid in self._statics if uid != self._ground])
        self._contact_every = max(1, round(physics.rate_hz / CONTACT_RATE_HZ))
        sample_hz = physics.rate_hz / self._contact_every
        # A pair must be apart 0.1 s before touching again counts again, at any rate.
        self._contacts = ContactCounter(max(1, round(RELEASE_SAMPLES * sample_hz / CONTACT_RATE_HZ)),
                                        name_of=self._hit_name, person=self._is_person)
        self._idle = 0  # samples without touches not yet told to _contacts
        # Counts every move and query (Mover.moved, queried, stuck): which came first, within a step too.
        self._clock = 0
        self._epoch = 0  # counts what may move a body's links unseen: Mover.seen forgets (seen.py)
        self._all_synced = -1  # the step at which every body was last put where its robot is
        self._mover_bodies: list[int] = []  # movers' bodies in the world this step (step() finds them)

    def reset(self) -> None:
        """Back to the world as built, at step 0, with no robots (see World.reset)."""
        super().reset()
        self._start_kinematics()

    def teleport(self, name: str, pose: SpawnPose, linear=(0.0, 0.0, 0.0), angular=(0.0, 0.0, 0.0)) -> None:
        """Move a robot, checked like a spawn (World.teleport); it goes on from there at its wheels'
        rates: the twist given is not kept, the robot follows its command."""
        self._sync_all()  # checked against the other robots where they are
        super().teleport(name, pose, linear, angular)
        mover = self._movers[name]
        self._clock, self._epoch = self._clock + 1, self._epoch + 1
        mover.relocate(self._clock)
        self._all_synced = -1
        self._measured[mover.index, :] = -np.inf  # its distances to the others: measure again
        self._measured[:, mover.index] = -np.inf

    def kinematics(self, name: str):
        """The root link's world pose and velocity now (its body put where it is first)."""
        if name in self._movers:
            self._movers[name].sync(full=True)
            self._epoch += 1
            self._robot_boxes.forget()  # its wheels turned: its box may have changed
        return super().kinematics(name)

    def spawn(self, robot: RobotPlan) -> None:
        """Load and check the robot as the physics engine does, then stand it on the floor."""
        self._sync_all()  # a spawn is checked against the other robots where they are
        self._epoch += 1  # a body id may be a removed robot's
        super().spawn(robot)
        sim = self._robots[robot.name]
        try:
            (lo, hi) = body_bounds(self._probes, sim.body)
            x, y, z = sim.link_pose()[0]
            reach = float(np.hypot(max(x - lo[0], hi[0] - x), max(y - lo[1], hi[1] - y)))
            kind = HolonomicMover if robot.drive is not None and robot.drive.kind in HOLONOMIC else Mover
            mover = kind(sim, self.physics.dt, lo[2], reach,
                         feet(self._probes, sim.body, lo, (x, y, sim.spawn_xy_yaw[2])))
            mover.above = hi[2] - z  # its highest point above its link origin
            if mover.level:  # its footprint, measured facing +x (once for robots alike)
                key = (robot.urdf, tuple(sorted(mover.positions.items())))
                if key not in self._rects:
                    mover.place(mover.x, mover.y, mover.z, 0.0)
                    self._rects[key], mover.synced = rectangle(self._cid, sim.body, mover.x, mover.y), False
                mover.rect = self._rects[key]
            floor = self._floor_under([mover], mover.floor + SUPPORT_BAND)[0]
            if not np.isfinite(floor):
                raise SpawnError(f"robot '{robot.name}' has no floor under it",
                                 hint="Spawn it above the ground or a floor of the world.")
            mover.floor, mover.z = floor, floor + mover.height
            mover.sync()
        except BaseException:
            super().remove(robot.name)
            raise
        self._movers[robot.name] = mover
        self._reindex()
        self._near[robot.name] = Near(self._cid, self._tops, self._boxes, self._statics)

    def remove(self, name: str) -> None:
        """Delete a robot from the world."""
        super().remove(name)
        self._epoch += 1
        gone = self._movers.pop(name, None)
        if gone is not None:
            keep = [m.index for m in self._movers.values()]
            self._measured = self._measured[np.ix_(keep, keep)]
            self._reindex(grown=False)
        self._near.pop(name, None)

    def _reindex(self, grown: bool = True) -> None:
        """Robots in spawn order, each knowing its row in the pair matrix (a new one: unmeasured).

        A spawn appends (the matrix grows into room kept for it, doubling: a fleet spawns in
        linear time); a removal renumbers everyone."""
        movers = self._movers
        if grown and len(self._order) == len(movers) - 1:
            mover = next(reversed(movers.values()))
            mover.index = len(self._order)
            self._order.append(mover)
            self._by_body[mover.robot.body] = mover.robot
            self._reach = np.append(self._reach, mover.reach)
            self._shapes = np.vstack([self._shapes, shape(mover.rect)])
            n = len(self._order)
            if n > len(self._room):
                room = np.full((2 * n, 2 * n), -np.inf)
                room[:n - 1, :n - 1] = self._measured
                self._room = room
            self._room[n - 1, :n] = -np.inf
            self._room[:n, n - 1] = -np.inf
            self._measured = self._room[:n, :n]
            return
        self._order = list(movers.values())
        self._by_body = {m.robot.body: m.robot for m in self._order}
        self._reach = np.array([m.reach for m in self._order])
        self._shapes = np.array([shape(m.rect) for m in self._order]).reshape(-1, 4)
        for index, mover in enumerate(self._order):
            mover.index = index
        n, had = len(self._order), min(len(self._order), len(self._measured))
        measured = np.full((n, n), -np.inf)
        measured[:had, :had] = self._measured[:had, :had]
        self._room = self._measured = measured

    def set_command(self, name: str, linear: float, angular: float, linear_y: float = 0.0) -> None:
        """Command a body twist (m/s, rad/s; ``linear_y`` sideways, holonomic drives only);
        ValueError for a robot without a drive, or a sideways command to one that is not holonomic."""
        robot = self._robot(name)
        check_command(robot.name, robot.drive.spec if robot.drive is not None else None, linear_y)
        robot.cmd, robot.cmd_y = (float(linear), float(angular)), float(linear_y)
        mover = self._movers[name]
        self._all_synced = -1  # a car's steering joints turn now
        if isinstance(mover, HolonomicMover):
            mover.command(float(linear), float(angular), float(linear_y))
        else:
            mover.command(float(linear), float(angular))

    def step(self) -> None:
        """Move every robot one step along its twist, as far as nothing is in the way."""
        # Runs every step for every robot: a robot in open space costs one motion() and one move().
        if self._kept_waits:
            self._drop_kept()
        self._steps += 1
        moves = []
        for mover in self._order:
            motion = mover.motion()
            if motion is not None or mover.touches:
                moves.append((mover, motion))
        if moves:
            near = self._robot_pairs(moves) if len(self._order) > 1 else {}
            move, moved = self._move, []
            # movers' bodies near a robot (sim/movers/stage.py): in the way as robots are, never skipped
            self._mover_bodies = self._stage.placed_bodies() if self._stage is not None else []
            for mover, motion in moves:
                bound = mover.bound
                if mover not in near and not mover.touches and not self._mover_bodies and \
                        mover.used + bound < mover.clear - CONTACT_SLOP:
                    # Nothing static within reach of this step (the clearance last measured) and
                    # no robot near: the whole step, no query.
                    mover.used += bound
                    mover.move(motion[0], motion[1], 1.0)
                    self._clock += 1
                    mover.moved, mover.travel = self._clock, mover.travel + bound
                    moved.append(mover)
                elif move(mover, motion, near.get(mover, ())):
                    moved.append(mover)
            if moved and not self._flat:
                self._lift(moved)
        if self._stage is not None and self._steps % self._stage.every == 0:
            self._stage.update(self._steps, self._robots_xy())
        if self._steps % self._contact_every == 0:
            self._count()

    def _robot_pairs(self, moves) -> dict[Mover, list[Mover]]:
        """The robots each moving robot might touch this step (sim/kinematic/pairs.py)."""
        return robot_pairs(self._order, self._reach, self._measured, moves, self._shapes)

    def _move(self, mover: Mover, motion, others: list[Mover]) -> bool:
        """One robot's step, asking PyBullet what is in its way (step() makes a step in open
        space itself); True when it moved."""
        distance, turn = (motion[0], motion[1]) if motion is not None else (0.0, 0.0)
        bound = mover.bound
        stuck = mover.stuck
        if stuck is not None and motion == stuck[0] and _still(others, stuck[1]) and not self._mover_bodies:
            mover.move(distance, turn, 0.0)  # blocked by the same things from the same pose
            return False
        if motion is None and mover.moved <= mover.queried and _still(others, mover.queried) and not self._mover_bodies:
            return False  # touching, and nothing moved since: the same touches
        for other in others:
            other.sync()
        near = self._near[mover.robot.name]
        near.around(mover.x, mover.y, mover.z, mover.reach, mover.height, mover.floor, mover.z + mover.above)
        mover.seen.start(self._epoch, self._clock)
        fraction, (static, apart, touching) = fit(self._cid, mover, distance, turn, others, near, self._mover_bodies,
                                                  mover.seen)
        if not self._tops:  # no static body but the ground: nothing static is ever in the way
            static = math.inf
        elif not others and not near.bodies:
            # Nothing static within the box Near looked in: none within NEAR_MARGIN / 2 either.
            static = QUERY_REACH + NEAR_MARGIN / 2.0
        if motion is not None:
            mover.move(distance, turn, fraction)
            if fraction > 0.0:
                self._clock += 1
                mover.moved, mover.travel = self._clock, mover.travel + bound * fraction
            mover.synced = True  # _fit left the body at the pose it moved to
        self._clock += 1  # what the query found is where the robot is now: after its move
        mover.clear, mover.used, mover.touches, mover.queried = static, 0.0, touching, self._clock
        if motion is not None:
            mover.stuck = (motion, self._clock) if fraction == 0.0 else None
        for other in others:  # distance now, plus both travels so far: see _robot_pairs
            i, j = mover.index, other.index
            self._measured[i, j] = self._measured[j, i] = \
                apart.get(other.robot.body, QUERY_REACH) + mover.travel + other.travel
        return motion is not None and fraction > 0.0

    def _lift(self, moved: list[Mover]) -> None:
        """Stand the robots that moved on the floor now under them (one ray batch for all)."""
        floors = self._floor_under(moved, np.array([m.floor + SUPPORT_BAND for m in moved]))
        for mover, floor in zip(moved, floors):
            if not np.isfinite(floor):
                raise SimulationFault(
                    f"robot '{mover.robot.name}' drove off the floor (nothing under it) at step {self._steps}",
                    hint="Keep it on the world's floor, or give the world a ground plane.",
                    robot=mover.robot.name, step=self._steps, kind="off_floor")
            if abs(floor - mover.floor) > FLOOR_TOLERANCE:  # not the rays' rounding
                self._clock += 1
                mover.moved, mover.travel = self._clock, mover.travel + abs(floor - mover.floor)
                mover.used += abs(floor - mover.floor)
                mover.floor, mover.z = floor, floor + mover.height
                mover.synced = False

    def _floor_under(self, movers: list[Mover], tops) -> np.ndarray:
        """The highest floor under each robot's footprint, below ``tops``."""
        if self._flat:
            return np.zeros(len(movers))
        points, top = [], []
        for mover, t in zip(movers, np.broadcast_to(tops, (len(movers),)).tolist()):
            # numpy's cosine as ever, taken out as a float: the same numbers, at Python's speed
            c, s, x, y = float(np.cos(mover.yaw)), float(np.sin(mover.yaw)), mover.x, mover.y
            points += [(x + c * fx - s * fy, y + s * fx + c * fy) for fx, fy in mover.feet]
            top += [t] * len(mover.feet)
        heights = self._floor.heights(np.array(points), np.array(top))
        return heights.reshape(len(movers), -1).max(axis=1)

    def _robots_xy(self) -> list[tuple[int, float, float]]:
        return [(m.robot.body, m.x, m.y) for m in self._order]

    def _count(self) -> None:
        """One contact sample from the touches the robots' last queries found (and the movers' bodies)."""
        met = self._mover_touches() if self._stage is not None else set()
        if any(mover.touches for mover in self._order):
            met = touched_pairs(self._order, self._by_body) | met
        elif not met:
            self._idle += 1  # told to the counter before the next sample with touches
            return
        if self._idle:
            self._contacts.idle(self._idle)
            self._idle = 0
        self._contacts.record(met)

    def _mover_touches(self) -> set:
        """(robot, ("body", mover body)) of the robots touching a mover's body now."""
        from mobot_cli.sim.pb import p

        placed = self._stage.placed_bodies()
        if not placed:
            return set()
        self._sync_all()
        found = set()
        for mover in self._order:
            for uid in placed:
                if p.getClosestPoints(mover.robot.body, uid, CONTACT_SLOP, physicsClientId=self._cid):
                    found.add((mover.robot, ("body", uid)))
        return found

    def _sync_all(self, full: bool = False) -> None:
        # Every body was put where its robot is at this step already (a fleet's spawns): a spawn
        # would otherwise look at every robot again, N^2 looks for a fleet.
        if not full and self._all_synced == self._steps:
            return
        for mover in self._movers.values():
            mover.sync(full)
        self._all_synced, self._epoch = self._steps, self._epoch + full  # full: wheels turned

    def sense(self, due: list[tuple[str, str]]) -> list[object]:
        """Readings due now: the robots' bodies are put where they are first."""
        self._sync_all(full=True)
        self._robot_boxes.forget()  # wheels turned: boxes may have changed
        rigs = self._sensors().rigs
        if any(rigs[robot][sensor].spec.kind == "contact" for robot, sensor in due):
            from mobot_cli.sim.pb import p

            p.performCollisionDetection(physicsClientId=self._cid)  # contact sensors read its points
        return super().sense(due)

    def states(self, names) -> dict[str, RobotState]:
        """``read`` of each robot named, by name."""
        if self._clearance:
            return super().states(names)
        movers = self._movers
        try:
            states = {name: movers[name].state() for name in names}  # a log row: this is hot
        except KeyError:  # one of them is not a Mover (yet): read() it
            return super().states(names)
        if self._stage is not None:
            for name, state in states.items():
                self._stage.social(movers[name].robot, state, False)  # no clearance watched
        return states

    def read(self, name: str) -> RobotState:
        """The robot's command, odometry and ground truth now (and its clearance when watched)."""
        state = self._movers[name].state() if name in self._movers else self._robot(name).state()
        if self._clearance and name in self._clearance:
            self._sync_all()
            state.clearance, state.nearest = self._nearest(name)
        if self._stage is not None:
            self._stage.social(self._robot(name), state, name in self._clearance)
        return state


def _still(movers: list[Mover], since: int) -> bool:
    """None of ``movers`` has moved after ``since`` (a tick of KinematicWorld._clock)."""
    for mover in movers:
        if mover.moved > since:
            return False
    return True
