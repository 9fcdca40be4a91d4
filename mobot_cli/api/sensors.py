"""Sensor readings from Python: the latest reading of every sensor, lidar scans as arrays.

A ``Simulation`` keeps the last ``Reading`` of each sensor as the timeline hands it out (the
same records the run folder's sensor files are written from), ``Scan`` is a lidar's
reading as arrays: the beam angles and the ranges, +inf where a beam had no return, and
``Range`` a range sensor's one distance with what sensor_msgs/Range says of it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping

import numpy as np
from pydantic import ValidationError

from mobot_cli.errors import UsageError
from mobot_cli.plan import RobotPlan, SensorSpec
from mobot_cli.scenario.model import RobotSpec
from mobot_cli.scenario.robots import RobotResolver
from mobot_cli.sim.sensing.lidar import axis_angles
from mobot_cli.sim.sensing.readings import ScanData
from mobot_cli.timeline.records import Deleted, Reading

NO_END = 2**62  # a spawned robot's commands come from your code, not a script


@dataclass(frozen=True)
class Scan:
    """One lidar scan, as a row of the run folder's ``sensors/<robot>/<sensor>.npy`` holds it."""

    robot: str
    sensor: str
    step: int  # taken after this many physics steps
    t: float  # s
    angles: np.ndarray = field(repr=False)  # (H,) azimuths in the sensor frame, rad, ccw from x forward
    elevations: np.ndarray = field(repr=False)  # (V,) beam elevations, rad; one 0 for a 2D lidar
    ranges: np.ndarray = field(repr=False)  # float32 m, (H,) 2D or (V, H) 3D; +inf: no return
    range_min: float
    range_max: float
    frame: str  # the frame the scan is stamped with

    def finite(self) -> np.ndarray:
        """The ranges with no return (+inf) as ``range_max``: every value finite, in [0, range_max]."""
        return np.minimum(self.ranges, np.float32(self.range_max))

    def toward(self, angle: float) -> float:
        """The range of the beam nearest to ``angle`` (rad, sensor frame) in the middle row."""
        wrapped = np.angle(np.exp(1j * (self.angles - angle)))
        row = self.ranges if self.ranges.ndim == 1 else self.ranges[len(self.ranges) // 2]
        return float(row[int(np.argmin(np.abs(wrapped)))])


@dataclass(frozen=True)
class Range:
    """One range sensor reading, as sensor_msgs/Range and ``sensors/<robot>/<sensor>.csv`` carry it."""

    robot: str
    sensor: str
    step: int  # taken after this many physics steps
    t: float  # s
    range: float  # m, in [min_range, max_range]; max_range when nothing is in its field of view
    min_range: float
    max_range: float
    field_of_view: float  # rad, as its plugin reports it
    radiation: str  # "ultrasound" | "infrared"
    frame: str  # the frame the reading is stamped with


def range_of(reading: Reading, rate_hz: int) -> Range:
    """A range sensor's reading as a ``Range``."""
    spec = reading.sensor
    return Range(reading.robot, spec.name, reading.step, reading.step / rate_hz, reading.data.range,
                 spec.range_min, spec.range_max, spec.field_of_view, spec.radiation, spec.frame_id or spec.link)


def scan_of(reading: Reading, rate_hz: int) -> Scan:
    """A lidar reading as a ``Scan``."""
    spec, data = reading.sensor, reading.data
    assert isinstance(data, ScanData)
    ranges = (data.ranges[0] if data.ranges.shape[0] == 1 else data.ranges).view()
    ranges.flags.writeable = False  # shared by every call until the next reading
    return Scan(reading.robot, spec.name, reading.step, reading.step / rate_hz, axis_angles(spec.horizontal),
                axis_angles(spec.vertical), ranges, spec.range_min, spec.range_max, spec.frame_id or spec.link)


def pick(name: str, sensors: tuple[SensorSpec, ...], sensor: str | None, kind: str | None) -> SensorSpec:
    """The sensor called ``sensor``, or the robot's only one of ``kind``; UsageError otherwise."""
    if sensor is not None:
        for spec in sensors:
            if spec.name == sensor and (kind is None or spec.kind == kind):
                return spec
        known = ", ".join(s.name for s in sensors if kind is None or s.kind == kind) or "none"
        raise UsageError(f"robot '{name}' has no {kind or 'sensor'} named '{sensor}'", hint=f"It has: {known}.")
    of_kind = [spec for spec in sensors if kind is None or spec.kind == kind]
    if not of_kind:
        raise UsageError(f"robot '{name}' has no {kind or 'sensor'}",
                         hint="The bundled mobot has one with args={'lidar': 'true'} (an IMU with 'imu').")
    if len(of_kind) > 1:
        raise UsageError(f"robot '{name}' has {len(of_kind)} {kind or 'sensor'}s: name the one you mean",
                         hint="It has: " + ", ".join(s.name for s in of_kind) + ".")
    return of_kind[0]


class Latest:
    """The latest reading of every sensor, from the timeline's records (a consumer)."""

    def __init__(self, rate_hz: int):
        self.rate_hz = rate_hz
        self.readings: dict[str, dict[str, Reading]] = {}  # robot -> sensor name -> its last reading
        self._scans: dict[tuple[str, str], Scan] = {}  # the last reading as a Scan, made once when asked

    def __call__(self, record) -> None:
        if isinstance(record, Reading):
            self.readings.setdefault(record.robot, {})[record.sensor.name] = record
            self._scans.pop((record.robot, record.sensor.name), None)
        elif isinstance(record, Deleted):
            for sensor in self.readings.pop(record.name, {}):
                self._scans.pop((record.name, sensor), None)

    def get(self, robot: str, sensor: str) -> Reading | None:
        return self.readings.get(robot, {}).get(sensor)

    def scan(self, robot: str, sensor: str) -> Scan | None:
        """The lidar's last reading as a Scan (the same read-only object until the next reading)."""
        scan = self._scans.get((robot, sensor))
        if scan is None:
            reading = self.get(robot, sensor)
            if reading is None:
                return None
            scan = self._scans[robot, sensor] = scan_of(reading, self.rate_hz)
        return scan


def robot_plan(name: str, description: str, *, rate_hz: int = 240, x: float = 0.0, y: float = 0.0,
               z: float | None = None, yaw: float = 0.0, args: Mapping[str, str] | None = None,
               namespace: str | None = None, base_dir: Path | None = None, hold=None) -> RobotPlan:
    """A robot resolved as a live spawn resolves it (description expanded, drive and sensors found);
    ``hold``: "all" or {joint: position}, as a scenario's robot's ``hold:``."""
    pose = {"x": x, "y": y, "yaw": yaw, "z": "auto" if z is None else z}
    try:
        spec = RobotSpec(name=name, description=description, args=dict(args or {}), pose=pose, hold=hold,
                         **({"namespace": namespace} if namespace is not None else {}))
    except ValidationError as exc:
        first = exc.errors()[0]
        key = ".".join(str(part) for part in first["loc"])
        raise UsageError(f"spawn '{name}': {key}: {first['msg']}") from None
    resolver = RobotResolver(rate_hz, 0, NO_END, base_dir=base_dir or Path.cwd())
    (plan,) = resolver.plans(spec, ())
    return plan
