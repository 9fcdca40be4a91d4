"""Sensor readings: lidar scans, IMU and contact (bumper) readings, computed when they are due.

The World owns one ``Sensing`` once a robot with sensors arrives; the timeline asks it for
the readings due at a step (each sensor at its own rate), and every lidar due at that step
is cast in one batch (sim/sensing/lidar.py). With one robot in the world only the static world can
be in a scan's way: the scan keeps its pose and waits, and the waiting scans are cast
together when one of them is first read (``ScanData.ranges``) or 50 wait. Noise comes from a
generator per sensor, seeded by the run's seed and the robot's and sensor's names.

* lidar: ranges (m, float32) on Gazebo's beam grid, +inf for no return, with gaussian noise
  and range quantisation as the ``<ray>`` block asks, clamped to [range_min, range_max];
* range: one distance, the nearest of its rays (each noised as a lidar's), then the plugin's
  own gaussian noise (from a generator of its own, so that batching never changes the
  numbers), clamped to [range_min, range_max]; range_max when no ray returns, as Gazebo's
  range plugins publish. Cast at the step they are due (they have few rays), never batched;
* imu: orientation of the sensor frame in the world (REP 145), angular velocity in the sensor
  frame, and linear acceleration as a real IMU measures it (specific force: +9.81 m/s^2 up at
  rest), averaged over the time since the previous reading;
* camera, depth, rgbd: an ImageData rendered when first read (sim/sensing/camera.py);
* contact: PyBullet's contact points of the sensor's link with anything but what the robot
  stands on (a contact whose normal points steeply up into the link, as sim/contacts.py).
"""

from __future__ import annotations

import hashlib
import threading
from dataclasses import dataclass
from typing import Callable

import numpy as np

from mobot_cli.common.transforms import quat_matrix
from mobot_cli.errors import SpawnError
from mobot_cli.plan import SensorSpec, WorldPlan
from mobot_cli.sim.contacts import CONTACT_SLOP, SUPPORT_NORMAL_Z
from mobot_cli.sim.pb import p
from mobot_cli.sim.sensing import lidar
from mobot_cli.sim.sensing.readings import Contact, ContactData, ImuData, RangeData, ScanData

KINDS = ("lidar", "range", "imu", "contact", "camera", "depth", "rgbd")
# Scans waiting to be cast (ScanData): at most this many, and this many rays (a VLP-16 scan
# has 30,000), so readers that never read still see memory stay flat.
MAX_WAITING_SCANS = 50  # a chunk of the .npy (record/sensor_files.py) reads them all at once
MAX_WAITING_RAYS = 65536


@dataclass
class _Rig:
    """A sensor as mounted on one spawned robot."""

    spec: SensorSpec
    body: int
    link: int  # PyBullet link index, -1 for the base
    rng: np.random.Generator
    beams: lidar.Beams | None = None
    rays: int = 0  # a lidar's rays a scan
    at_link: bool = True  # the sensor sits at its link's frame (no pose of its own)
    last: tuple[int, np.ndarray] | None = None  # imu: (step, world velocity) of the last reading
    to_link: tuple | None = None  # on the base: PyBullet's base (inertial) frame -> the URDF link frame
    reading_rng: np.random.Generator | None = None  # range: the plugin's noise on the reading


class _Waiting:
    """Scans of the static world taken but not cast yet (each knows its pose); cast a sensor's
    scans in one call when one is read or too many wait, then noised in the order they were
    taken (so each sensor's noise is drawn as if they came one by one)."""

    def __init__(self, scene):
        self.scene = scene
        self.items: list[tuple[_Rig, ScanData]] = []
        self.rays = 0
        self.lock = threading.Lock()  # a live world's scan op may read from another thread

    def add(self, scans: list[tuple[_Rig, ScanData]]) -> None:
        """The scans taken at one step."""
        with self.lock:
            self.items += scans
            for rig, data in scans:
                data._waiting = self  # noqa: SLF001 - ScanData's lazy state is this module's to fill
                self.rays += rig.rays
            full = len(self.items) >= MAX_WAITING_SCANS or self.rays >= MAX_WAITING_RAYS
        if full:
            self.cast()

    def cast(self) -> None:
        """Cast every waiting scan, one call per sensor."""
        with self.lock:
            items, self.items, self.rays = self.items, [], 0
            by_rig: dict[int, list[tuple[_Rig, ScanData]]] = {}
            for item in items:
                by_rig.setdefault(id(item[0]), []).append(item)
            for scans in by_rig.values():
                rig = scans[0][0]
                positions = np.array([data.position for _, data in scans], dtype=np.float32)
                rotations = np.array([p.getMatrixFromQuaternion(data.quat) for _, data in scans],
                                     dtype=np.float32).reshape(-1, 3, 3)
                ranges = lidar.cast_scans(self.scene, rig.spec, rig.beams, positions, rotations)
                for (_, data), values in zip(scans, ranges):
                    _see_movers(rig, data, values)
                ranges = _lidar_noise(rig, ranges)
                for (_, data), values in zip(scans, ranges):
                    data._ranges = values  # noqa: SLF001 - behind ScanData.ranges, filled by this module


def noise_rng(seed: int, robot: str, sensor: str) -> np.random.Generator:
    """The noise generator of one sensor: the run's seed and the names, nothing else."""
    digest = hashlib.sha256(f"{robot}/{sensor}".encode()).digest()
    return np.random.default_rng([seed & 0xFFFFFFFFFFFFFFFF, int.from_bytes(digest[:8], "little")])


class Sensing:
    """Every sensor of the robots in one world; ``read`` computes the readings due."""

    def __init__(self, cid: int, world: WorldPlan, seed: int, dt: float, gravity: tuple[float, float, float],
                 label: Callable[[int], str], robot_bodies: Callable[[], list[int]],
                 renderer: str = "auto", notices: list[str] | None = None, step_now: Callable[[], int] | None = None,
                 movers: Callable[[], object] = lambda: None):
        self.cid, self.world, self.seed, self.dt = cid, world, seed, dt
        self.gravity = np.array(gravity, dtype=float)
        self.label = label  # body id -> what messages call it
        self.robot_bodies = robot_bodies  # the bodies of every robot in the world, sensors or not
        self.movers = movers  # the movers' shapes now (sim/movers/shapes.py Snapshot), None without movers
        self.rigs: dict[str, dict[str, _Rig]] = {}  # robot name -> sensor name -> rig
        self._scene = None
        self._scene_built = False
        self._waiting: _Waiting | None | bool = None  # False: no scene to wait for (PyBullet casts)
        self.renderer, self.notices, self.step_now = renderer, notices if notices is not None else [], step_now
        self._cameras = None  # sim/sensing/camera.py's Cameras, made for the first camera
        self._robot_shapes = None  # sim/sensing/robot_scene.py's RobotShapes, made for the first cast among robots

    def release(self) -> bool:
        """Let go of the renderer (the world is closing); True when it added bodies to the world."""
        cameras, self._cameras = self._cameras, None
        if cameras is not None:
            cameras.close()
        return cameras is not None and cameras.changed_scene  # the EGL plugin's visual twins

    @property
    def cameras(self):
        """What renders this world's camera images (made at the first camera reading)."""
        if self._cameras is None:
            from mobot_cli.sim.sensing.camera import Cameras  # worlds without cameras never load it
            self._cameras = Cameras(self.cid, self.world, self.renderer, self.notices, self.step_now or (lambda: -1))
        return self._cameras

    def add(self, name: str, body: int, links: dict[str, int], sensors: tuple[SensorSpec, ...]) -> None:
        """Mount a robot's sensors; SpawnError for a sensor on a link the robot lacks."""
        rigs = {}
        for spec in sensors:
            if spec.link not in links:
                raise SpawnError(f"robot '{name}': sensor '{spec.name}' is on link '{spec.link}', "
                                 "which its URDF does not have", hint="Put the sensor on one of its links.")
            if spec.kind not in KINDS:
                raise SpawnError(f"robot '{name}': sensor '{spec.name}' has unknown kind '{spec.kind}'",
                                 hint="Sensor kinds are " + ", ".join(KINDS) + ".")
            rig = _Rig(spec, body, links[spec.link], noise_rng(self.seed, name, spec.name),
                       at_link=spec.xyz == (0.0, 0.0, 0.0) and spec.quat == (0.0, 0.0, 0.0, 1.0))
            if rig.link < 0:
                inertial = p.getDynamicsInfo(body, -1, physicsClientId=self.cid)
                rig.to_link = p.invertTransform(inertial[3], inertial[4])
            if spec.kind in ("lidar", "range"):
                rig.beams = lidar.Beams.of(spec)
                rig.rays = len(rig.beams.directions)
            if spec.kind == "range":
                rig.reading_rng = noise_rng(self.seed, name, spec.name + "/reading")
            rigs[spec.name] = rig
        self.rigs[name] = rigs

    def forget(self, name: str, body: int | None = None) -> None:
        """A robot (its PyBullet body) left the world."""
        self.rigs.pop(name, None)
        if body is not None and self._robot_shapes is not None:
            self._robot_shapes.forget(body)

    @property
    def robot_shapes(self):
        """The robots' collision triangles (sim/sensing/robot_scene.py), made at the first cast among robots."""
        if self._robot_shapes is None:
            from mobot_cli.sim.sensing.robot_scene import RobotShapes

            self._robot_shapes = RobotShapes(self.cid)
        return self._robot_shapes

    @property
    def scene(self):
        """The static world's ray scene, built at the first scan (None without embreex)."""
        if not self._scene_built:
            from mobot_cli.sim.sensing.raycast import embree_available, static_scene

            self._scene = static_scene(self.world) if embree_available() else None
            self._scene_built = True
        return self._scene

    def read(self, step: int, due: list[tuple[str, str]]) -> list[object]:
        """The readings of ``(robot, sensor)`` pairs due at ``step``, in order."""
        out: list[object] = []
        scans: list[tuple[_Rig, ScanData]] = []
        ranges: list[tuple[int, _Rig, ScanData]] = []
        rigs = self.rigs
        movers = self.movers()
        for robot, sensor in due:
            rig = rigs[robot][sensor]
            position, quat = self._pose(rig)
            if rig.reading_rng is not None:  # a range sensor: cast below
                data = ScanData(None, rig.beams, position, quat)
                data.movers = movers
                ranges.append((len(out), rig, data))
            elif rig.beams is not None:  # a lidar
                data = ScanData(None, rig.beams, position, quat)
                data.movers = movers
                scans.append((rig, data))
            elif rig.spec.kind == "imu":
                data = self._imu(step, rig, position, quat)
            elif rig.spec.kind in ("camera", "depth", "rgbd"):
                from mobot_cli.sim.sensing.camera import ImageData
                data = ImageData(self.cameras, rig.spec, rig.rng, step, position, quat)
            else:
                data = self._contacts(rig)
            out.append(data)
        if scans:
            self._scans(scans)
        if ranges:
            self._cast_now([(rig, data) for _, rig, data in ranges])
            for index, rig, data in ranges:
                out[index] = _range_reading(rig, data.ranges)
        return out

    def _scans(self, scans: list[tuple[_Rig, ScanData]]) -> None:
        """Give the scans due their ranges: later, when only the static world can be in their
        way (one robot in the world), else now, robots and all."""
        # Runs once per lidar reading: whatever it spends, every scan of a run pays.
        waiting = self._waiting
        if waiting is None:
            scene = self.scene
            waiting = self._waiting = _Waiting(scene) if scene is not None and scene.complete else False
        bodies = self.robot_bodies()
        if waiting and len(bodies) <= 1:
            waiting.add(scans)
            return
        if waiting:
            waiting.cast()  # scans taken before come first: noise is drawn in order
        self._cast_now(scans, bodies)

    def _cast_now(self, scans: list[tuple[_Rig, ScanData]], bodies: list[int] | None = None) -> None:
        """Cast these scans now against the world and the other robots, noised."""
        bodies = self.robot_bodies() if bodies is None else bodies
        jobs = []
        for rig, data in scans:
            rotation = np.array(p.getMatrixFromQuaternion(data.quat), dtype=np.float32).reshape(3, 3)
            jobs.append(lidar.ScanJob(rig.spec, rig.beams, np.array(data.position), rotation, rig.body))
        boxes, robots = {}, None
        if len(bodies) > 1:
            if self.scene is not None and self.scene.complete:  # Embree casts at the robots it can
                robots = self.robot_shapes.rays(bodies)
                meshed = set(robots.bodies)
                bodies = [body for body in bodies if body not in meshed]
            boxes = {body: _aabb(self.cid, body) for body in bodies}
        ranges = lidar.cast(self.cid, self.scene, jobs, boxes, robots)
        for (rig, data), values in zip(scans, ranges):
            _see_movers(rig, data, values)
            data._ranges = _lidar_noise(rig, values)  # noqa: SLF001 - behind ScanData.ranges, filled here

    def _pose(self, rig: _Rig) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """The sensor frame's world pose: its link's URDF frame composed with the sensor pose."""
        # Once per reading: PyBullet answers tuples (kept as they are), a link's state at once.
        if rig.link >= 0:
            state = p.getLinkState(rig.body, rig.link, computeForwardKinematics=1, physicsClientId=self.cid)
            pos, orn = state[4], state[5]
        else:
            com, orn = p.getBasePositionAndOrientation(rig.body, physicsClientId=self.cid)
            pos, orn = p.multiplyTransforms(com, orn, rig.to_link[0], rig.to_link[1])
        if not rig.at_link:
            pos, orn = p.multiplyTransforms(pos, orn, rig.spec.xyz, rig.spec.quat)
        return tuple(pos), tuple(orn)

    def _velocity(self, rig: _Rig, position) -> tuple[np.ndarray, np.ndarray]:
        """World linear velocity of the sensor's origin and the link's angular velocity."""
        if rig.link >= 0:
            state = p.getLinkState(rig.body, rig.link, computeLinkVelocity=1, computeForwardKinematics=1,
                                   physicsClientId=self.cid)
            com, lin, ang = state[0], state[6], state[7]
        else:
            com = p.getBasePositionAndOrientation(rig.body, physicsClientId=self.cid)[0]
            lin, ang = p.getBaseVelocity(rig.body, physicsClientId=self.cid)
        ang = np.array(ang)
        return np.array(lin) + np.cross(ang, np.array(position) - np.array(com)), ang

    def _imu(self, step: int, rig: _Rig, position, quat) -> ImuData:
        velocity, omega = self._velocity(rig, position)
        accel = np.zeros(3)
        if rig.last is not None and step > rig.last[0]:
            accel = (velocity - rig.last[1]) / ((step - rig.last[0]) * self.dt)
        rig.last = (step, velocity)
        to_sensor = np.array(quat_matrix(quat)).T
        spec = rig.spec
        w = to_sensor @ omega
        f = to_sensor @ (accel - self.gravity)
        if spec.noise_stddev > 0.0 or spec.noise_mean != 0.0:
            w = w + rig.rng.normal(spec.noise_mean, spec.noise_stddev, 3)
        if spec.accel_noise_stddev > 0.0:
            f = f + rig.rng.normal(0.0, spec.accel_noise_stddev, 3)
        return ImuData(_unit(quat), tuple(float(v) for v in w), tuple(float(v) for v in f))

    def _contacts(self, rig: _Rig) -> ContactData:
        found = []
        for c in p.getContactPoints(bodyA=rig.body, linkIndexA=rig.link, physicsClientId=self.cid):
            other, normal = c[2], c[7]  # contactNormalOnB points from the other body into ours
            if other == rig.body or c[8] > CONTACT_SLOP:
                continue
            if normal[2] > SUPPORT_NORMAL_Z and other not in self.robot_bodies():
                continue  # what it stands on
            found.append(Contact(self.label(other), tuple(c[5]), tuple(normal), max(0.0, -c[8]), float(c[9])))
        return ContactData(tuple(found))



def _see_movers(rig: _Rig, data: ScanData, ranges: np.ndarray) -> None:
    """The movers in the scan's way, where they were when it was taken (in place, before noise)."""
    if data.movers is not None:
        from mobot_cli.sim.movers.shapes import see

        see(data.movers, rig.spec.range_min, rig.beams, data.position, quat_matrix(data.quat), ranges)


def _aabb(cid: int, body: int) -> tuple[np.ndarray, np.ndarray]:
    """A robot's bounding box now: the union of its links' AABBs."""
    boxes = [p.getAABB(body, link, physicsClientId=cid)
             for link in range(-1, p.getNumJoints(body, physicsClientId=cid))]
    lo = np.min([b[0] for b in boxes], axis=0)
    hi = np.max([b[1] for b in boxes], axis=0)
    return lo, hi


def _lidar_noise(rig: _Rig, ranges: np.ndarray) -> np.ndarray:
    """Noise, quantisation and clamping as the sensor's <ray> block asks (float32, +inf kept).
    ``ranges`` is a fresh array of this scan: it is changed in place, a few small ufuncs a scan."""
    spec = rig.spec
    if spec.noise_stddev > 0.0 or spec.noise_mean != 0.0:
        returns = np.isfinite(ranges)
        ranges += rig.rng.normal(spec.noise_mean, spec.noise_stddev, ranges.shape).astype(np.float32)  # inf stays
        np.clip(ranges, spec.range_min, spec.range_max, out=ranges, where=returns)
    if spec.range_resolution > 0.0:  # +inf stays +inf
        step = np.float32(spec.range_resolution)
        returns = np.isfinite(ranges)
        ranges /= step
        np.round(ranges, out=ranges)
        ranges *= step
        # rounding never takes a return out of the sensor's span (create3's cliff sensors have a
        # 1 m resolution over 0.0001..0.15 m: their returns rounded to 0)
        np.clip(ranges, spec.range_min, spec.range_max, out=ranges, where=returns)
    return ranges.astype(np.float32, copy=False)


def _range_reading(rig: _Rig, ranges: np.ndarray) -> RangeData:
    """The nearest ray's range (rays noised and clamped already), with the plugin's noise on it,
    clamped to the sensor's limits; range_max when no ray returned."""
    spec = rig.spec
    nearest = float(ranges.min()) if ranges.size else np.inf
    if not np.isfinite(nearest) or nearest >= spec.range_max:
        return RangeData(spec.range_max)
    if spec.reading_noise_stddev > 0.0:
        nearest += float(rig.reading_rng.normal(0.0, spec.reading_noise_stddev))
    return RangeData(min(max(nearest, spec.range_min), spec.range_max))


def _unit(q) -> tuple[float, float, float, float]:
    n = float(np.sqrt(sum(v * v for v in q)))
    return tuple(float(v) / n for v in q)
