"""CDR bytes of the sensor messages: LaserScan, PointCloud2, Range, Imu and gazebo_msgs/ContactsState.

Fields are filled as Gazebo's ROS plugins fill them for the same ``<sensor>`` (gazebo_ros's
LaserScan and PointCloud2 conversions, ros_gz_bridge's): LaserScan carries ``angle_min``,
``angle_max`` and ``angle_increment = (max - min) / (samples - 1)``, ``time_increment`` and
``scan_time`` 0, the sensor's range limits, one range per beam (+inf: no return, REP 117) and
as many intensities, all 0; a 3D lidar's LaserScan would be its middle vertical row.
PointCloud2 is unordered (height 1) and dense: x, y, z, intensity float32 (16 bytes a point),
vertical rows outer, beams inner, points without a return left out. Imu covariances are the
noise variances on the diagonal (0 without noise). Range carries the radiation type
(ULTRASOUND 0, INFRARED 1), field of view and limits its plugin reports, and as ``variance`` the
noise variance of one reading (0, "unknown", without noise). Every packer is independent of the bag, so
a live ROS 2 publisher can send the same bytes. tests/record/test_sensor_records.py checks each
against rosbags' serializer.
"""

from __future__ import annotations

import struct
from functools import lru_cache

import numpy as np

from mobot_cli.plan import SensorSpec
from mobot_cli.ros.cdr import ENCAPSULATION
from mobot_cli.sim.sensing.lidar import Beams, angle_step

FLOAT32 = 7  # sensor_msgs/PointField datatype
CLOUD_FIELDS = (("x", 0), ("y", 4), ("z", 8), ("intensity", 12))
POINT_STEP = 16


class CdrWriter:
    """A CDR (little endian) message written field by field, aligned as the payload requires."""

    def __init__(self) -> None:
        self.parts: list[bytes] = [ENCAPSULATION]
        self.size = 0  # payload bytes so far: CDR aligns relative to the payload

    def put(self, data: bytes, align: int) -> "CdrWriter":
        """Bytes after the padding that aligns them to ``align`` in the payload."""
        pad = -self.size % align
        if pad:
            self.parts.append(b"\0" * pad)
        self.parts.append(data)
        self.size += pad + len(data)
        return self

    def pack(self, fmt: str, *values) -> "CdrWriter":
        """Fixed-size numbers, aligned to the size of the first one ("7f", "iI", "B")."""
        return self.put(struct.pack("<" + fmt, *values), struct.calcsize("<" + fmt.lstrip("0123456789")[0]))

    def u32(self, value: int) -> "CdrWriter":
        return self.put(struct.pack("<I", value), 4)

    def string(self, text: str) -> "CdrWriter":
        data = text.encode("utf-8") + b"\0"
        return self.u32(len(data)).put(data, 1)

    def header(self, stamp: tuple[int, int], frame_id: str) -> "CdrWriter":
        return self.pack("iI", *stamp).string(frame_id)

    def sequence(self, array: np.ndarray, align: int) -> "CdrWriter":
        """A sequence of numbers: its length, then the array's bytes (little endian)."""
        self.u32(len(array))
        return self.put(array.tobytes(), align) if len(array) else self

    def bytes(self) -> bytes:
        return b"".join(self.parts)


def laser_scan(stamp: tuple[int, int], frame_id: str, spec: SensorSpec, ranges: np.ndarray) -> bytes:
    """sensor_msgs/LaserScan of one row of ranges (float32)."""
    row = np.ascontiguousarray(ranges, dtype="<f4").reshape(-1)
    middle, tail = _scan_parts(frame_id, _scan_numbers(spec), len(row))
    return b"".join((ENCAPSULATION, _STAMP.pack(*stamp), middle, row.tobytes(), tail))


_STAMP = struct.Struct("<iI")
_SCAN_NUMBERS = struct.Struct("<7f")


def _scan_numbers(spec: SensorSpec) -> bytes:
    """A LaserScan's angles, times and range limits as they go on the wire. The scan's cache is
    keyed on these bytes, not on ``spec``: -0.0 equals 0.0, but its bytes differ."""
    axis = spec.horizontal
    lo = axis.min_angle if axis is not None else 0.0
    hi = axis.max_angle if axis is not None else 0.0
    return _SCAN_NUMBERS.pack(lo, hi, angle_step(axis), 0.0, 0.0, spec.range_min, spec.range_max)


@lru_cache(maxsize=256)
def _scan_parts(frame_id: str, numbers: bytes, rays: int) -> tuple[bytes, bytes]:
    """A LaserScan's fixed bytes around its ranges: from the frame id to the ranges' length, and
    the intensities (all 0). Made once per sensor: a scan is then one join (the bag and ROS 2
    send one per lidar reading, and building it field by field was most of its cost)."""
    w = CdrWriter().header((0, 0), frame_id)
    w.put(numbers, 4).u32(rays)
    middle = w.bytes()[len(ENCAPSULATION) + _STAMP.size:]  # ranges start 4-aligned: no padding after
    return middle, struct.pack("<I", rays) + bytes(4 * rays)


def scan_row(ranges: np.ndarray) -> np.ndarray:
    """The row a LaserScan carries: the only one, or the middle vertical row (as gazebo_ros)."""
    return ranges[ranges.shape[0] // 2] if ranges.ndim == 2 else ranges


def point_cloud2(stamp: tuple[int, int], frame_id: str, ranges: np.ndarray, beams: Beams) -> bytes:
    """sensor_msgs/PointCloud2 of a scan's returns in the sensor frame."""
    flat = ranges.reshape(-1)
    keep = np.isfinite(flat)
    points = np.zeros((int(keep.sum()), 4), dtype="<f4")
    points[:, :3] = beams.directions[keep] * flat[keep, None].astype(float)
    w = CdrWriter().header(stamp, frame_id).u32(1).u32(len(points))
    w.u32(len(CLOUD_FIELDS))
    for name, offset in CLOUD_FIELDS:
        w.string(name).u32(offset).pack("B", FLOAT32).u32(1)
    w.pack("B", 0)  # is_bigendian
    w.u32(POINT_STEP).u32(POINT_STEP * len(points))
    w.sequence(points.reshape(-1).view(np.uint8), 1)
    return w.pack("B", 1).bytes()  # is_dense


RADIATION = {"ultrasound": 0, "infrared": 1}  # sensor_msgs/Range's constants


def range_message(stamp: tuple[int, int], frame_id: str, spec: SensorSpec, value: float) -> bytes:
    """sensor_msgs/Range (Jazzy's layout, with ``variance``) of one reading."""
    variance = spec.noise_stddev ** 2 + spec.reading_noise_stddev ** 2
    w = CdrWriter().header(stamp, frame_id).pack("B", RADIATION.get(spec.radiation, 1))
    return w.pack("5f", spec.field_of_view, spec.range_min, spec.range_max, value, variance).bytes()


def imu(stamp: tuple[int, int], frame_id: str, spec: SensorSpec, orientation, angular_velocity,
        linear_acceleration) -> bytes:
    """sensor_msgs/Imu."""
    w = CdrWriter().header(stamp, frame_id)
    w.pack("4d", *orientation).pack("9d", *_diagonal(0.0))
    w.pack("3d", *angular_velocity).pack("9d", *_diagonal(spec.noise_stddev ** 2))
    w.pack("3d", *linear_acceleration).pack("9d", *_diagonal(spec.accel_noise_stddev ** 2))
    return w.bytes()


def contacts_state(stamp: tuple[int, int], frame_id: str, collision: str, contacts) -> bytes:
    """gazebo_msgs/ContactsState: one ContactState per body touched, as gazebo_ros_bumper
    groups them (positions and normals in the world frame, normals into the sensor's link)."""
    groups: dict[str, list] = {}
    for contact in contacts:
        groups.setdefault(contact.other, []).append(contact)
    w = CdrWriter().header(stamp, frame_id).u32(len(groups))
    for other, points in groups.items():
        w.string(f"{collision} touches {other}").string(collision).string(other)
        wrenches = [(*(f * n for n in c.normal), 0.0, 0.0, 0.0) for c in points for f in (c.force,)]
        w.u32(len(wrenches))
        for wrench in wrenches:
            w.pack("6d", *wrench)
        w.pack("6d", *np.sum(wrenches, axis=0).tolist())
        w.u32(len(points))
        for c in points:
            w.pack("3d", *c.position)
        w.u32(len(points))
        for c in points:
            w.pack("3d", *c.normal)
        w.sequence(np.array([c.depth for c in points], dtype="<f8"), 8)
    return w.bytes()


def _diagonal(value: float) -> tuple[float, ...]:
    return (value, 0.0, 0.0, 0.0, value, 0.0, 0.0, 0.0, value)
