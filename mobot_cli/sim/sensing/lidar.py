"""Lidar rays: beam directions as Gazebo lays them out, and one batched cast for every scan due.

Every scan due at a step is cast together: all their rays against the static world in one
Embree call (sim/sensing/raycast.py), then, up to their static hits, at the other robots' collision
triangles where they are now, a second Embree scene made for the cast (sim/sensing/robot_scene.py).
A robot whose shapes cannot be made into triangles (and every robot when the static world has
no Embree scene) is left to PyBullet's ``rayTestBatch``: the rays that pass through its bounding
box (in front of the hits so far) go to it, in batches as large as it allows, with its worker
threads on. A robot never sees itself: a ray that meets its own links is cast on from just
beyond the hit, so links in front of the sensor are transparent, as they are to a real sensor
mounted clear of its robot.

Scans that only the static world can be in the way of (one robot in the world) may also be
cast later, many at once (``cast_scans``): the same numbers as one by one.

As Gazebo's ray sensor, rays start ``range_min`` from the sensor (nothing closer is seen) and
end at ``range_max``; a ray with no return reads +inf (REP 117).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mobot_cli.plan import RayAxis, SensorSpec
from mobot_cli.sim.pb import p
from mobot_cli.sim.sensing.raycast import StaticScene
from mobot_cli.sim.sensing.robot_scene import RobotRays

# PyBullet refuses larger batches ("Number of rays exceed the maximum batch size"): measured,
# 16383 rays come back and 16384 give an empty answer.
MAX_BATCH = 16383
ROBOT_GROUP = 1  # PyBullet's collision filter group of dynamic bodies; static ones are 2
# m: a ray that met its own robot goes on from this far beyond the hit. A ray starting within
# a shape's collision margin is reported as hitting it at once (measured: up to ~4 mm inside
# a cylinder, ~1 mm inside a box); from deeper inside, a convex shape is not reported.
STEP_PAST = 0.005
MAX_PASSES = 8  # own links a single ray may pass through
BOX_MARGIN = 0.01  # m added around robots' bounding boxes (AABBs are tight to the shapes)
REACH_MARGIN = 0.1  # m: a box this much beyond range_max is still ray-tested (float32 origins)
HEIGHT_PAD = 0.001  # m added to the heights rays reach: float32 origins and directions round


def axis_angles(axis: RayAxis | None) -> np.ndarray:
    """The beam angles of one axis, as Gazebo spaces them: ``min + i * (max - min) / (n - 1)``."""
    if axis is None or axis.samples <= 1:
        return np.array([axis.min_angle if axis is not None else 0.0])
    step = (axis.max_angle - axis.min_angle) / (axis.samples - 1)
    return axis.min_angle + step * np.arange(axis.samples)


def angle_step(axis: RayAxis | None) -> float:
    """Angle between two beams (0 for a single beam), as LaserScan's ``angle_increment``."""
    if axis is None or axis.samples <= 1:
        return 0.0
    return (axis.max_angle - axis.min_angle) / (axis.samples - 1)


@dataclass(frozen=True)
class Beams:
    """A lidar's beams in its own frame: (vertical, horizontal) grid, x forward, z up."""

    horizontal: np.ndarray  # (H,) azimuths, rad
    vertical: np.ndarray  # (V,) elevations, rad
    directions: np.ndarray  # (V * H, 3) unit vectors, vertical-major
    directions32: np.ndarray  # the same in float32, as the ray engine takes them
    lengths32: np.ndarray  # (V * H,) float32: range_max - range_min, each ray's length
    flat: float = 1.0  # the longest level part of a beam (of directions32), for ``heights``
    rise: float = 1.0  # the largest vertical part of a beam

    @classmethod
    def of(cls, spec: SensorSpec) -> "Beams":
        h, v = axis_angles(spec.horizontal), axis_angles(spec.vertical)
        el, az = np.meshgrid(v, h, indexing="ij")
        d = np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], axis=-1).reshape(-1, 3)
        d32 = d.astype(np.float32)
        return cls(h, v, d, d32, np.full(len(d), spec.range_max - spec.range_min, np.float32),
                   float(np.sqrt(d32[:, 0] ** 2 + d32[:, 1] ** 2).max()), float(np.abs(d32[:, 2]).max()))

    @property
    def shape(self) -> tuple[int, int]:
        return len(self.vertical), len(self.horizontal)


@dataclass
class ScanJob:
    """One scan to cast: the sensor's world pose, its beams and whose robot it rides on."""

    spec: SensorSpec
    beams: Beams
    position: np.ndarray  # (3,)
    rotation: np.ndarray  # (3, 3) sensor frame -> world (float32 saves a conversion a scan)
    own_body: int


def cast(cid: int, scene: StaticScene | None, jobs: list[ScanJob],
         robot_boxes: dict[int, tuple[np.ndarray, np.ndarray]], robots: RobotRays | None = None) -> list[np.ndarray]:
    """Ranges (float32, (V, H), +inf for no return) of every job, cast in one batch: ``robots``
    (with the static scene) are cast at with Embree, the robots of ``robot_boxes`` by PyBullet."""
    # float32 throughout, as the ray engine and LaserScan take them (10 um at 100 m): a 360-beam
    # scan must cost far less than the physics between two scans, so a lone scan (the usual
    # case) goes through without joining or splitting arrays.
    rays = [_rays(job) for job in jobs]
    if len(jobs) == 1:
        (origins, dirs), lengths = rays[0], jobs[0].beams.lengths32
    else:
        origins, dirs = np.concatenate([o for o, _ in rays]), np.concatenate([d for _, d in rays])
        lengths = np.concatenate([job.beams.lengths32 for job in jobs])
    if scene is not None and scene.complete:
        t = scene.cast(origins, dirs, lengths)
        if robots is not None and robots.bodies:
            sensors = np.array([job.position for job in jobs], dtype=float)
            ranges = np.array([job.spec.range_max for job in jobs], dtype=float)
            np.minimum(t, robots.cast(origins, dirs, np.minimum(t, lengths), _owners(jobs), sensors, ranges), out=t)
        boxes = _within_reach(robot_boxes, jobs)
        candidates = _near_robots(origins, dirs, np.minimum(t, lengths), _owners(jobs), boxes) if boxes else ()
        mask = ROBOT_GROUP
    else:  # no Embree scene: PyBullet casts every ray at everything
        t = np.full(len(dirs), np.inf, dtype=np.float32)
        candidates, mask = np.arange(len(dirs)), -1
    if len(candidates):
        reach = np.minimum(t, lengths)
        hit = _bullet(cid, origins[candidates].astype(float), dirs[candidates].astype(float),
                      reach[candidates].astype(float), _owners(jobs)[candidates], mask)
        t[candidates] = np.minimum(t[candidates], hit)
    if len(jobs) == 1:  # t is a fresh array: the range_min is added in place
        t += np.float32(jobs[0].spec.range_min)
        return [t.reshape(jobs[0].beams.shape)]
    return [(part + np.float32(job.spec.range_min)).reshape(job.beams.shape)
            for job, part in zip(jobs, _split(t, jobs))]


def cast_scans(scene: StaticScene, spec: SensorSpec, beams: Beams, positions: np.ndarray,
               rotations: np.ndarray) -> np.ndarray:
    """Ranges (float32, (k, V, H), +inf for no return) of k scans of one lidar that only the
    static world can be in the way of (no other robot in the world), at k poses (float32
    positions (k, 3), rotations (k, 3, 3)): one call for all, the same numbers ``cast`` gives
    each scan alone (the beams are turned by one small matmul a scan, as there)."""
    dirs = np.matmul(beams.directions32, rotations.transpose(0, 2, 1))
    origins = dirs * np.float32(spec.range_min)
    for axis in range(3):  # a column at a time: 3x faster than broadcasting (k, 1, 3) over (k, n, 3)
        origins[:, :, axis] += positions[:, axis, None]
    t = scene.cast(origins.reshape(-1, 3), dirs.reshape(-1, 3), np.tile(beams.lengths32, len(positions)),
                   heights(beams, spec.range_max, positions, rotations))
    t += np.float32(spec.range_min)
    return t.reshape((len(positions), *beams.shape))


def heights(beams: Beams, reach: float, positions: np.ndarray, rotations: np.ndarray) -> tuple[float, float]:
    """Bounds on the z that rays of these beams reach from sensors at these poses (a little
    wide, never narrow): a beam's rise in the world is at most its level part times how far
    the sensor's z axis leans plus its vertical part (0 for a 2D lidar), from k poses at once."""
    up = rotations[:, 2].astype(float)  # the world z row of each sensor's rotation
    climb = (np.hypot(up[:, 0], up[:, 1]) * beams.flat + np.abs(up[:, 2]) * beams.rise) * reach + HEIGHT_PAD
    z = positions[:, 2].astype(float)
    return float((z - climb).min()), float((z + climb).max())


def _rays(job: ScanJob) -> tuple[np.ndarray, np.ndarray]:
    """A job's ray origins and directions in the world (float32): its beams turned by one matmul."""
    dirs = job.beams.directions32 @ job.rotation.T.astype(np.float32, copy=False)
    origins = dirs * np.float32(job.spec.range_min)
    origins += job.position.astype(np.float32, copy=False)
    return origins, dirs


def _within_reach(boxes: dict[int, tuple[np.ndarray, np.ndarray]], jobs: list[ScanJob]) -> dict:
    """The robots' boxes that some job's rays can reach (a cheap distance test first: a robot
    beyond every sensor's range_max needs no ray test)."""
    out = {}
    for body, (lo, hi) in boxes.items():
        for job in jobs:
            gap = np.maximum(np.maximum(lo - job.position, job.position - hi), 0.0)
            if float(gap @ gap) <= (job.spec.range_max + REACH_MARGIN) ** 2:
                out[body] = (lo, hi)
                break
    return out


def _split(values: np.ndarray, jobs: list[ScanJob]) -> list[np.ndarray]:
    """``values`` cut back into each job's share."""
    if len(jobs) == 1:
        return [values]
    return np.split(values, np.cumsum([len(job.beams.directions) for job in jobs])[:-1])


def _owners(jobs: list[ScanJob]) -> np.ndarray:
    return np.repeat([job.own_body for job in jobs], [len(job.beams.directions) for job in jobs])


def _near_robots(origins: np.ndarray, dirs: np.ndarray, reach: np.ndarray, owners: np.ndarray,
                 boxes: dict[int, tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """Indices of rays whose segment passes through another robot's bounding box."""
    near = np.zeros(len(origins), dtype=bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        inverse = 1.0 / dirs
        for body, (lo, hi) in boxes.items():
            a, b = (lo - BOX_MARGIN - origins) * inverse, (hi + BOX_MARGIN - origins) * inverse
            # nanmax/nanmin over the three axes, column by column: fmax/fmin skip a NaN (0 * inf, a ray
            # parallel to a face through its plane) as they do, and this is ~3x faster than the
            # reductions along a 3-long axis, which a crowd of robots pays for every ray and box.
            low, high = np.minimum(a, b), np.maximum(a, b)
            enter = np.fmax(np.fmax(low[:, 0], low[:, 1]), low[:, 2])
            leave = np.fmin(np.fmin(high[:, 0], high[:, 1]), high[:, 2])
            near |= (enter <= leave) & (leave >= 0.0) & (enter <= reach) & (owners != body)
    return np.flatnonzero(near)


def _bullet(cid: int, origins: np.ndarray, dirs: np.ndarray, lengths: np.ndarray, owners: np.ndarray,
            mask: int) -> np.ndarray:
    """Distance to the first body (of the ``mask`` groups) not the ray's own robot; +inf if none."""
    out = np.full(len(origins), np.inf)
    done = np.zeros(len(origins))  # distance already travelled past own links
    live = np.arange(len(origins))
    start, left = origins.copy(), lengths.copy()
    for _ in range(MAX_PASSES):
        if not len(live):
            break
        ends = start[live] + dirs[live] * left[live, None]
        found = _batch(cid, start[live], ends, mask)
        body, fraction = found[:, 0].astype(int), found[:, 1]
        hit = body >= 0
        own = hit & (body == owners[live])
        other = live[hit & ~own]
        out[other] = done[other] + fraction[hit & ~own] * left[other]
        again = live[own]
        step = fraction[own] * left[again] + STEP_PAST
        start[again] += dirs[again] * step[:, None]
        done[again] += step
        left[again] -= step
        live = again[left[again] > 0.0]
    return out


def _batch(cid: int, starts: np.ndarray, ends: np.ndarray, mask: int) -> np.ndarray:
    """(body, hit fraction) per ray from rayTestBatch, MAX_BATCH rays a call."""
    rows = []
    for i in range(0, len(starts), MAX_BATCH):
        result = p.rayTestBatch(starts[i:i + MAX_BATCH], ends[i:i + MAX_BATCH], numThreads=0,
                                collisionFilterMask=mask, physicsClientId=cid)
        if len(result) != min(MAX_BATCH, len(starts) - i):
            raise RuntimeError(f"rayTestBatch answered {len(result)} of {min(MAX_BATCH, len(starts) - i)} rays")
        rows.extend((h[0], h[2]) for h in result)
    return np.array(rows, dtype=float).reshape(-1, 2)


def to_points(ranges: np.ndarray, beams: Beams) -> np.ndarray:
    """Cartesian points (n, 3) in the sensor frame of every finite range, vertical-major, as
    Gazebo's PointCloud2 conversion orders them."""
    flat = ranges.reshape(-1)
    keep = np.isfinite(flat)
    return (beams.directions[keep] * flat[keep, None]).astype(np.float32)
