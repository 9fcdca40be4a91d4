"""Sensor readings in the view: lidar scans and point clouds, drawn on the link that took them.

The hook for the sensors work. A reading becomes a ``Cloud``: points in the frame of one link of
one robot, which the page hangs under that link's node, so it moves with the robot.

* Live (`run --view`, `serve --view`): any timeline record that is not a Sample, Spawned or
  Deleted goes through ``cloud_of``. A record is drawn when it has ``robot`` (the robot's name),
  ``sensor`` (its SensorSpec, kind "lidar") and either ``ranges`` (metres: shape (samples,) for a
  2D scan, (vertical samples, horizontal samples) for 3D, laid out over the spec's angles as
  Gazebo does) or ``points`` ((n, 3) in the sensor's frame). Other records are ignored.
* Replay (`mobot view`): the bag's sensor_msgs/LaserScan and sensor_msgs/PointCloud2 topics of
  each robot (``<ns>/scan``, ``<ns>/points``), stamped with ``<frame prefix><link>``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from mobot_cli.plan import SensorSpec
from mobot_cli.view.geometry import matrix, matrix_wxyz

HIT_COLOR = (230, 40, 40)
POINT_SIZE = 0.03  # m
MAX_POINTS = 50_000  # per reading: a denser cloud is thinned for the page


@dataclass(frozen=True)
class Cloud:
    """What one sensor saw at one instant: points in ``link``'s frame of robot ``robot``."""

    robot: str
    sensor: str
    link: str
    points: np.ndarray  # (n, 3) float32


def cloud_of(record: Any) -> Cloud | None:
    """The points of a live sensor record (see the module's docstring), or None if it is none."""
    robot, spec = getattr(record, "robot", None), getattr(record, "sensor", None)
    if not isinstance(robot, str) or not isinstance(spec, SensorSpec) or spec.kind != "lidar":
        return None
    points = getattr(record, "points", None)
    if points is None:
        ranges = getattr(record, "ranges", None)
        if ranges is None:
            return None
        points = spec_points(spec, np.asarray(ranges, float))
    pose = matrix(spec.xyz, spec.quat)
    points = np.asarray(points, float).reshape(-1, 3) @ pose[:3, :3].T + pose[:3, 3]
    return Cloud(robot, spec.name, spec.link, _thin(points))


def spec_points(spec: SensorSpec, ranges: np.ndarray) -> np.ndarray:
    """Hits in the sensor frame for a lidar's ranges laid out over its spec's angles."""
    h = spec.horizontal
    v = spec.vertical if spec.vertical is not None and spec.vertical.samples > 1 else None
    yaw = np.linspace(h.min_angle, h.max_angle, h.samples) if h is not None else np.zeros(ranges.shape[-1])
    pitch = np.linspace(v.min_angle, v.max_angle, v.samples) if v is not None else np.zeros(1)
    r = ranges.reshape(len(pitch), len(yaw))
    keep = np.isfinite(r) & (r >= spec.range_min) & ((r <= spec.range_max) if spec.range_max > 0 else True)
    r = np.where(keep, r, 0.0)  # no hit: inf or NaN must not reach the products
    cp, sp = np.cos(pitch)[:, None], np.sin(pitch)[:, None]
    xyz = np.stack([r * cp * np.cos(yaw), r * cp * np.sin(yaw), r * sp * np.ones_like(yaw)], axis=-1)
    return xyz[keep]


def draw(server: Any, cloud: Cloud, link_pose: np.ndarray) -> Any:
    """Add (or replace) the cloud's points, placed at its link's world pose (4x4)."""
    return server.scene.add_point_cloud(f"/readings/{cloud.robot}/{cloud.sensor}", cloud.points.astype(np.float32),
                                        colors=HIT_COLOR, point_size=POINT_SIZE, point_shape="circle",
                                        position=tuple(link_pose[:3, 3].tolist()), wxyz=matrix_wxyz(link_pose))


def _thin(points: np.ndarray) -> np.ndarray:
    step = max(1, len(points) // MAX_POINTS + (len(points) % MAX_POINTS > 0))
    return points[::step].astype(np.float32)
