"""What a sensor reading holds: a lidar scan (cast when first read), a range, an IMU reading and
a contact sensor's contacts. Made by the sensors (sim/sensing/rig.py), read by the timeline, the
records, the Python API and ROS 2."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mobot_cli.common.transforms import quat_matrix
from mobot_cli.sim.sensing import lidar


class ScanData:
    """One lidar scan: ranges on the (vertical, horizontal) beam grid and where it was taken.

    A scan that can meet only the static world (no other robot in the world) waits to be cast
    until its ranges are first read, together with every scan taken since (rig.py's ``_Waiting``): the
    same rays and noise, but cast and noised a few scans at once instead of between physics
    steps that leave the CPU caches cold."""

    __slots__ = ("beams", "position", "quat", "_ranges", "_waiting", "movers")

    def __init__(self, ranges: np.ndarray | None, beams: lidar.Beams, position: tuple[float, float, float],
                 quat: tuple[float, float, float, float]):
        self._ranges: np.ndarray | None = ranges
        self._waiting = None  # rig.py's batch it waits in, until it is cast
        self.beams = beams
        self.position = position  # the sensor's origin in the world
        self.quat = quat  # the sensor frame's orientation in the world
        self.movers = None  # the movers' shapes when it was taken (sim/movers/shapes.py), if any

    @property
    def ranges(self) -> np.ndarray:
        """float32 (V, H); +inf where a beam had no return."""
        if self._ranges is None:
            self._waiting.cast()
        return self._ranges

    @property
    def nbytes(self) -> int:
        """Bytes of the ranges (known before they are cast)."""
        rows, beams = self.beams.shape
        return 4 * rows * beams

    def world_points(self) -> np.ndarray:
        """Every return as a world-frame point (n, 3)."""
        local = lidar.to_points(self.ranges, self.beams).astype(float)
        return local @ np.array(quat_matrix(self.quat)).T + np.array(self.position)


@dataclass(frozen=True)
class RangeData:
    """One range reading, as sensor_msgs/Range's ``range`` carries it."""

    range: float  # m, in [range_min, range_max]; range_max when nothing is in its field of view


@dataclass(frozen=True)
class ImuData:
    """One IMU reading (SI units), as sensor_msgs/Imu carries it."""

    orientation: tuple[float, float, float, float]  # sensor frame in the world, (x, y, z, w)
    angular_velocity: tuple[float, float, float]  # rad/s, sensor frame
    linear_acceleration: tuple[float, float, float]  # m/s^2, sensor frame, gravity included


@dataclass(frozen=True)
class Contact:
    """One contact point of a contact sensor's link."""

    other: str  # what it touches, e.g. "robot 'r2'" or "world model 'Wall_3' at (...)"
    position: tuple[float, float, float]  # on the sensor's link, world frame
    normal: tuple[float, float, float]  # world frame, from the other body into the link
    depth: float  # m, >= 0
    force: float  # normal force, N


@dataclass(frozen=True)
class ContactData:
    """The contacts of one reading (empty: nothing touches)."""

    contacts: tuple[Contact, ...] = ()
