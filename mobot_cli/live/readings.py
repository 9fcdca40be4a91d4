"""The live world's latest sensor readings, kept as the timeline makes them, for the ``scan`` op.

A reply carries one reading as JSON: a lidar's angles, limits and ranges (``null`` where a
beam had no return: JSON has no infinity; rows of ranges for a 3D lidar), a range sensor's
range, limits, field of view and radiation type (as sensor_msgs/Range), an IMU's
orientation, angular velocity and linear acceleration, a contact sensor's contacts.
"""

from __future__ import annotations

from typing import Any

from mobot_cli.live.protocol import Refusal, Result
from mobot_cli.plan import RobotPlan
from mobot_cli.ros import sensor_topics
from mobot_cli.sim.sensing.lidar import angle_step
from mobot_cli.sim.sensing.render import intrinsics
from mobot_cli.timeline.records import Deleted, Reading, Record


class LatestReadings:
    """The last reading of every sensor of the robots in the world."""

    def __init__(self) -> None:
        self.latest: dict[str, dict[str, Reading]] = {}  # robot -> sensor -> its last reading

    def take(self, record: Record) -> None:
        """Keep a Reading; forget a deleted robot's."""
        if isinstance(record, Reading):
            self.latest.setdefault(record.robot, {})[record.sensor.name] = record
        elif isinstance(record, Deleted):
            self.latest.pop(record.name, None)

    def reply_fields(self, robot: RobotPlan, sensor: str | None, rate_hz: int) -> dict[str, Any]:
        """The reply's fields for ``robot``'s sensor (default: its first lidar, else its first
        sensor); Refusal when it has none or has not read yet."""
        specs = {spec.name: spec for spec in robot.sensors}
        if not specs:
            raise Refusal(Result.NOT_FOUND, f"robot '{robot.name}' has no sensors")
        if sensor is None:
            sensor = next((s.name for s in robot.sensors if s.kind == "lidar"), robot.sensors[0].name)
        if sensor not in specs:
            raise Refusal(Result.NOT_FOUND, f"robot '{robot.name}' has no sensor '{sensor}'; it has "
                          + ", ".join(specs))
        reading = self.latest.get(robot.name, {}).get(sensor)
        if reading is None:
            raise Refusal(Result.OPERATION_FAILED, f"sensor '{sensor}' of robot '{robot.name}' has not "
                          "read yet; ask again after its first period")
        return reading_fields(robot, reading, rate_hz)


def reading_fields(robot: RobotPlan, reading: Reading, rate_hz: int) -> dict[str, Any]:
    """One reading as JSON-ready fields."""
    spec, data = reading.sensor, reading.data
    fields: dict[str, Any] = {
        "name": robot.name, "sensor": spec.name, "kind": spec.kind, "topic": sensor_topics.topic(robot, spec),
        "frame_id": sensor_topics.sensor_frame(robot, spec).frame, "step": reading.step,
        "t": reading.step / rate_hz}
    if spec.kind == "lidar":
        ranges = [[None if r == float("inf") else float(r) for r in row] for row in data.ranges.tolist()]
        axis = spec.horizontal
        fields.update(angle_min=axis.min_angle if axis else 0.0, angle_max=axis.max_angle if axis else 0.0,
                      angle_increment=angle_step(axis), range_min=spec.range_min,
                      range_max=spec.range_max, ranges=ranges[0] if len(ranges) == 1 else ranges)
        if len(ranges) > 1:
            fields.update(vertical_angle_min=spec.vertical.min_angle, vertical_angle_max=spec.vertical.max_angle,
                          vertical_angle_increment=angle_step(spec.vertical))
    elif spec.kind == "range":
        fields.update(range=data.range, min_range=spec.range_min, max_range=spec.range_max,
                      field_of_view=spec.field_of_view, radiation_type=spec.radiation)
    elif spec.kind == "imu":
        fields.update(orientation=list(data.orientation), angular_velocity=list(data.angular_velocity),
                      linear_acceleration=list(data.linear_acceleration))
    elif spec.kind in ("camera", "depth", "rgbd"):  # the pixels go to ROS 2, the run folder and the API
        fx, fy, cx, cy = intrinsics(spec)
        fields.update(width=spec.width, height=spec.height, encoding=spec.encoding, fx=fx, fy=fy, cx=cx, cy=cy,
                      clip_near=spec.range_min, clip_far=spec.range_max)
    else:
        fields["contacts"] = [{"other": c.other, "position": list(c.position), "normal": list(c.normal),
                               "depth": c.depth, "force": c.force} for c in data.contacts]
    return fields
