"""The World: the only owner of a PyBullet client. Spawns robots, drives them, steps, reports.

Everything is headless (``pybullet.DIRECT``) and every call names its client, so several
Worlds can live in one process (tests, sweeps in threads).
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from mobot_cli.common.streams import silenced
from mobot_cli.errors import SimulationFault, SpawnError, did_you_mean
from mobot_cli.plan import Physics, RobotPlan, SpawnPose, WorldPlan
from mobot_cli.sim import clearance, entity, placement
from mobot_cli.sim.broadphase import RobotBoxes
from mobot_cli.sim.bullet import kept_body, statics
from mobot_cli.sim.bullet.clients import Stage, connect, release
from mobot_cli.sim.bullet.faults import Health
from mobot_cli.sim.bullet.holonomic import HolonomicDrive
from mobot_cli.sim.bullet.joints import set_initial_positions
from mobot_cli.sim.bullet.placing import Placing
from mobot_cli.sim.bullet.robot import SimRobot
from mobot_cli.sim.bullet.settled import Settling
from mobot_cli.sim.bullet.steered import drive_class
from mobot_cli.sim.bullet.urdf_file import pybullet_file
from mobot_cli.sim.contacts import CONTACT_RATE_HZ, ContactCounter
from mobot_cli.sim.movers.door import MoversDoor
from mobot_cli.sim.pb import p
from mobot_cli.sim.state import RobotState

if TYPE_CHECKING:
    from mobot_cli.sim.movers.stage import MoverStage
    from mobot_cli.sim.sensing.rig import Sensing

__all__ = ["World", "RobotState"]

# Encoder odometry is folded in at this rate (diff_drive_controller's default update rate);
# reads bring it up to date as well, so no reader sees stale odometry.
ODOMETRY_RATE_HZ = 50
# Robots are checked for faults (sim/bullet/faults.py) and stalls at this rate: a fault is
# caught within 0.1 s of simulated time, and the check costs little per step.
HEALTH_RATE_HZ = 10
# Inertia as written (not recomputed from collision shapes), and cylinders as true cylinders:
# PyBullet's default 40-sided hulls rolled 1 mm (3 %) too large on turtlebot3's 33 mm wheels.
# URDF_MERGE_FIXED_LINKS would halve the step time (burger 54 -> 21 us, husky 62 -> 38 us) but
# welds casters into the chassis, and linorobot2 2wd then rested on its two casters with its
# wheels unloaded (it could not move); it also loses per-link <contact> friction.
URDF_FLAGS = p.URDF_USE_INERTIA_FROM_FILE | p.URDF_USE_IMPLICIT_CYLINDER


class World(MoversDoor, Settling, Placing):
    """A headless physics world built from a plan; robots come and go by name (and movers: MoversDoor;
    a kept settle: Settling; a spawn's placement and its checks: Placing)."""

    def __init__(self, physics: Physics, world: WorldPlan, seed: int = 0, fresh: bool = False):
        self.physics = physics
        self.plan = world
        self.seed = seed  # handed in like every source of randomness; PyBullet itself draws none
        self._cid, stage = connect((physics, world), fresh)
        # The static world stays for the next World only when nothing but this run's robots
        # came and went: a body removed on the way, or a fault, and the client is reset instead.
        self._pristine = True
        self._steps = 0
        self._robots: dict[str, SimRobot] = {}
        self._ramping: list[SimRobot] = []
        self._sprung: list[SimRobot] = []  # robots with springs: torques before every step
        self._pushed: list[HolonomicDrive] = []  # holonomic drives: a base force every step
        self._odom_every = max(1, round(physics.rate_hz / ODOMETRY_RATE_HZ))
        self._check_every = max(1, round(physics.rate_hz / HEALTH_RATE_HZ))
        self._contacts = ContactCounter(name_of=self._hit_name, person=self._is_person)
        self._contact_every = max(1, round(physics.rate_hz / CONTACT_RATE_HZ))
        self._sensing: Sensing | None = None  # made when the first robot with sensors arrives
        self._stage: MoverStage | None = None  # the movers (sim/movers/stage.py), made with the first
        self._clearance: dict[str, float] = {}  # robot -> how far its clearance is measured (m)
        self._clearance_tops: clearance.Tops | None = None  # the static bodies' highest points, for clearance
        self._health = Health(self._cid, physics.faults, physics.rate_hz)
        self._robot_boxes = RobotBoxes()  # the robots' boxes, for spawn checks (sim/broadphase.py)
        self._files: dict[str, Path] = {}  # URDF text -> the file PyBullet loads it from (_load)
        # Said once during the run (a stalled robot, a clamped car turn); a Timeline hands them on to summary.json.
        self.notices: list[str] = []
        # A robot's body kept for the same first spawn (sim/bullet/kept_body.py); until it is taken it waits.
        self._kept, self._kept_waits = (stage.body, stage.body is not None) if stage is not None else (None, False)
        if stage is not None:
            self._probes, self._statics, self._solids, self._ground, self._names, self._meshes = \
                stage.probes, stage.statics, stage.solids, stage.ground, stage.names, stage.meshes
        else:
            self._probes = placement.Probes(self._cid)
            try:
                self._build(world)
            except BaseException:
                self._pristine = False
                self.close()
                raise
        self._add_actors()
        if physics.renderer != "tiny":  # EGL draws only the bodies made after its plugin loads: the robots
            from mobot_cli.sim.sensing.render import preload

            preload(self._cid, physics.renderer)

    def reset(self) -> None:
        """Back to the world as built, at step 0, with no robots: PyBullet's own reset, then the
        same static bodies in the same order (so the same ids), as if the world were new."""
        for name in list(self._robots):
            self.remove(name)
        p.resetSimulation(physicsClientId=self._cid)
        self._probes = placement.Probes(self._cid)  # the reset removed its shapes too
        self._pristine = False  # not a client to keep its static world for another run
        self._steps = 0
        self._ramping = []
        self._sprung = []
        self._pushed = []
        self._contacts = ContactCounter(name_of=self._hit_name, person=self._is_person)
        self._sensing = None  # rebuilt with the first robot with sensors: its noise restarts too
        self._stage = None  # the reset removed the movers' bodies: the world's actors come back
        self._clearance = {}
        self._health = Health(self._cid, self.physics.faults, self.physics.rate_hz)
        self._robot_boxes.forget()
        self._kept, self._kept_waits = None, False
        self._build(self.plan)
        self._add_actors()

    def _build(self, world: WorldPlan) -> None:
        self._statics, self._names, self._solids, self._ground, self._meshes = statics.build(
            self._cid, self.physics, world, self._load)

    def _load(self, urdf: str, xyz, quat, fixed: bool = False) -> int:
        """Load URDF text (in lines PyBullet reads whole: urdf_file.pybullet_text); -1 when PyBullet
        refuses it."""
        path = pybullet_file(urdf, self._files)
        try:
            with silenced(1):  # the importer prints its warnings to stdout
                return p.loadURDF(str(path), xyz, quat, useFixedBase=fixed,
                                  flags=URDF_FLAGS, physicsClientId=self._cid)
        except p.error:
            return -1

    def _load_robot(self, urdf: str, pose: SpawnPose) -> int:
        """The first robot at step 0: the kept body (kept_body.py) or loaded and saved; else loaded."""
        key, first, self._kept_waits = kept_body.body_key(urdf, pose.xyz, pose.quat), self._kept_waits, False
        first = first or (not self._robots and self._steps == 0 and self._kept is None)
        uid = kept_body.take(self._cid, self._kept, key) if first else None
        if uid is None:
            self._kept = None
            uid = self._load(urdf, pose.xyz, pose.quat)
            self._kept = kept_body.save(self._cid, key, uid) if first and uid >= 0 else None
        return uid

    def _drop_kept(self) -> None:
        """A kept body no first spawn took leaves before the world moves."""
        kept_body.forget(self._cid, self._kept)
        self._kept, self._kept_waits = None, False

    @property
    def step_count(self) -> int:
        """Whole physics steps taken since the world was built."""
        return self._steps

    @property
    def client_id(self) -> int:
        """The PyBullet client id, for code that queries PyBullet directly."""
        return self._cid

    def names(self) -> list[str]:
        """Names of the robots in the world, in spawn order."""
        return list(self._robots)

    def body_id(self, name: str) -> int:
        """The PyBullet body of a robot."""
        return self._robot(name).body

    def has_drive(self, name: str) -> bool:
        """True when the robot takes velocity commands."""
        return self._robot(name).drive is not None

    def spawn(self, robot: RobotPlan) -> None:
        """Load a robot at its pose, checked: unique name, on the floor, not inside things."""
        if robot.name in self._robots:
            raise SpawnError(f"a robot named '{robot.name}' already exists",
                             hint="Robot names must be unique; pick another name.")
        cid, pose = self._cid, robot.pose
        norm = math.sqrt(sum(q * q for q in pose.quat))
        if not norm > 1e-9:
            raise SpawnError(f"robot '{robot.name}' has a zero orientation quaternion",
                             hint="Give the pose a unit quaternion (x, y, z, w) or rpy angles.")
        pose = replace(pose, quat=tuple(q / norm for q in pose.quat))
        robot = replace(robot, pose=pose)
        uid = self._load_robot(robot.urdf, pose)
        if uid < 0:
            raise SpawnError(f"PyBullet could not load robot '{robot.name}' "
                             f"({robot.source or 'URDF text'})",
                             hint="Run `mobot check` on its description.")
        try:
            set_initial_positions(cid, uid, robot.holds)
            self._settle_in(uid, robot)
            sim_robot = SimRobot(cid, uid, robot, self.physics.dt, self.notices, drive_class(robot.drive))
            if robot.sensors:
                self._sensors().add(robot.name, uid, sim_robot.links, robot.sensors)
        except BaseException:
            p.removeBody(uid, physicsClientId=cid)
            self._pristine = False
            raise
        self._robots[robot.name] = sim_robot
        if sim_robot.holds.spring_joints:
            self._sprung.append(sim_robot)
        if isinstance(sim_robot.drive, HolonomicDrive):
            self._pushed.append(sim_robot.drive)
        self._health.watch(sim_robot, self._steps)

    def kinematics(self, name: str) -> entity.Kinematics:
        """The root link's world pose and velocity (of its origin) now."""
        return entity.kinematics(self._robot(name))

    def teleport(self, name: str, pose: SpawnPose, linear=(0.0, 0.0, 0.0), angular=(0.0, 0.0, 0.0)) -> None:
        """Move a robot to ``pose`` (world frame; z: auto rests it on the floor) with this twist
        (world frame, of its root link's origin), checked like a spawn: SpawnError leaves it where it was."""
        robot = self._robot(name)
        saved = entity.saved(robot)
        self._robot_boxes.forget()  # it moves, whether it stays there or not
        try:
            if pose.z_auto:
                self._rest(robot.body, pose, name)
            else:
                entity.place(robot, pose.xyz, pose.quat)
            self._check_placed(robot.body, name, pose.z_auto)
        except BaseException:
            entity.restore(robot, saved)
            self._robot_boxes.forget()
            raise
        entity.set_twist(robot, linear, angular)
        self._health.moved(robot, self._steps)

    def remove(self, name: str) -> None:
        """Delete a robot from the world."""
        robot = self._robot(name)
        p.removeBody(robot.body, physicsClientId=self._cid)
        self._pristine = False
        self._robot_boxes.forget()
        del self._robots[name]
        self._contacts.forget(name)
        if self._sensing is not None:
            self._sensing.forget(name, robot.body)
        self._clearance.pop(name, None)
        self._health.forget(name)
        if self._stage is not None:
            self._stage.forget_robot(robot.body)
        if robot in self._ramping:
            self._ramping.remove(robot)
        if robot in self._sprung:
            self._sprung.remove(robot)
        if robot.drive in self._pushed:
            self._pushed.remove(robot.drive)

    def set_command(self, name: str, linear: float, angular: float, linear_y: float = 0.0) -> None:
        """Command a body twist (m/s, rad/s; ``linear_y`` sideways, holonomic drives only);
        ValueError for a robot without a drive, or a sideways command to one that is not holonomic."""
        robot = self._robot(name)
        robot.set_command(linear, angular, linear_y)
        self._health.commanded(name, math.hypot(linear, linear_y))
        if robot.drive.ramping and robot not in self._ramping:
            self._ramping.append(robot)

    def step(self) -> None:
        """Advance one physics step; SimulationFault when a robot's state goes bad."""
        if self._kept_waits:
            self._drop_kept()
        if self._ramping:
            for robot in self._ramping:
                robot.drive.ramp_step()
            self._ramping = [r for r in self._ramping if r.drive.ramping]
        for robot in self._sprung:
            robot.holds.apply_springs()
        if self._pushed:
            for drive in self._pushed:
                drive.push(self.physics.dt)
        p.stepSimulation(physicsClientId=self._cid)
        self._steps += 1
        if self._stage is not None and self._steps % self._stage.every == 0:
            self._stage.update(self._steps, self._robots_xy())
        if self._steps % self._odom_every == 0:
            for robot in self._robots.values():
                if robot.drive is not None:
                    robot.drive.integrate()
                    robot.drive.integrated_at = self._steps
                    if robot.drive.trim is not None:
                        robot.drive.trim_step(self._odom_every * self.physics.dt)
        if self._steps % self._check_every == 0:
            self._check()
        if self._steps % self._contact_every == 0:
            self._contacts.sample(self._cid, self._robots.values())

    def _check(self) -> None:
        """Faults end the run (SimulationFault); a stall is said once (``notices``)."""
        health, step = self._health, self._steps
        try:
            for robot in self._robots.values():
                health.check(robot, step)
                if robot.drive is not None:
                    notice = health.stall(robot, step)
                    if notice:
                        self.notices.append(notice)
        except SimulationFault:
            self._pristine = False  # a faulted world is not kept for the next run
            raise

    def sense(self, due: list[tuple[str, str]]) -> list[object]:
        """Readings of the (robot, sensor name) pairs due now, computed together (sim/sensing/rig.py)."""
        return (self._sensing or self._sensors()).read(self._steps, due)

    def _sensors(self) -> Sensing:
        if self._sensing is None:
            from mobot_cli.sim.sensing.rig import Sensing  # worlds without sensors never load it

            self._sensing = Sensing(self._cid, self.plan, self.seed, self.physics.dt, self.physics.gravity,
                                    self.label, lambda: [r.body for r in self._robots.values()],
                                    self.physics.renderer, self.notices, lambda: self._steps,
                                    lambda: self._stage.snapshot() if self._stage is not None else None)
        return self._sensing

    def _hit_name(self, other) -> str:
        """How records name what a robot collided with (a ContactCounter key): the other robot's
        name, or the world body's."""
        kind, what = other
        if kind != "robot" and self._stage is not None and what in self._stage.names:
            return self._stage.names[what]
        return what if kind == "robot" else self._names.get(what, f"body {what}")

    def label(self, body: int) -> str:
        """What messages call a body: "robot 'NAME'" or the static body's label."""
        for name, robot in self._robots.items():
            if robot.body == body:
                return f"robot '{name}'"
        if self._stage is not None and body in self._stage.names:
            return f"mover '{self._stage.names[body]}'"
        return self._statics.get(body, f"body {body}")
    def odom_origin(self, name: str) -> tuple[float, float, float]:
        """Where the robot's odometry started: its odom frame's x, y, yaw in the world."""
        return self._robot(name).spawn_xy_yaw

    def read(self, name: str) -> RobotState:
        """The robot's command, odometry and ground truth now (and its clearance when watched)."""
        robot = self._robot(name)
        state = robot.state(self._steps)
        if self._clearance and name in self._clearance:
            state.clearance, state.nearest = self._nearest(name)
        if self._stage is not None:
            self._stage.social(robot, state, name in self._clearance)
        return state

    def _nearest(self, name: str) -> tuple[float, str]:
        """A watched robot's clearance and what it is to (sim/clearance.py)."""
        tops = self._clearance_tops
        if tops is None or tops.statics is not self._statics:  # the statics are made again by a reset
            tops = self._clearance_tops = clearance.Tops(self._statics)
        return clearance.nearest(self._cid, self._robot(name).body, self._clearance[name],
                                 [r.body for r in self._robots.values()], self.label, self._meshes, tops)

    def states(self, names) -> dict[str, RobotState]:
        """``read`` of each robot named, by name."""
        return {name: self.read(name) for name in names}

    def watch_clearance(self, name: str, reach: float) -> None:
        """Measure the robot's clearance (up to ``reach`` m) whenever its state is read."""
        self._clearance[name] = max(reach, self._clearance.get(name, 0.0))

    def _robots_xy(self) -> list[tuple[int, float, float]]:
        """Each robot's body and x, y now (what walkers keep away from)."""
        cid = self._cid
        return [(r.body, *p.getBasePositionAndOrientation(r.body, physicsClientId=cid)[0][:2])
                for r in self._robots.values()]

    def _robot(self, name: str) -> SimRobot:
        try:
            return self._robots[name]
        except KeyError:
            hint = did_you_mean(name, self._robots)
            raise KeyError(f"no robot named '{name}'. {hint}".strip()) from None

    def close(self) -> None:
        """Let go of the PyBullet client (see clients.keep_clients); the world is unusable afterwards."""
        if self._cid >= 0:
            if self._sensing is not None and self._sensing.release():
                self._pristine = False  # the renderer's bodies (sim/sensing/render.py) are in it
            if self.physics.renderer != "tiny":
                from mobot_cli.sim.sensing.render import discard

                self._pristine = not discard(self._cid) and self._pristine
            stage = Stage((self.physics, self.plan), self._statics, self._solids, self._ground, self._probes,
                          self._names, meshes=self._meshes) if self._pristine else None
            release(self._cid, *kept_body.leave(self._cid, stage, self._kept, self._kept_waits,
                                                [robot.body for robot in self._robots.values()]))
            self._cid = -1

    def __enter__(self) -> World:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
