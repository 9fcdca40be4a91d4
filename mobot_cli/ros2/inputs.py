"""What DDS delivers comes from anyone on the domain: checked like a live request before the world sees it.

One NaN ``cmd_vel`` used to reach PyBullet, which lost the robot, and the run then ended in a
traceback; ``(0, inf)`` left odometry that could no longer be read. A sample that is not a
little-endian CDR Twist, not finite, or beyond the scenario's limits (scenario/limits.py:
100 m/s, 100 rad/s) is dropped and counted per topic; the world goes on.
"""

from __future__ import annotations

import math
import threading

from mobot_cli.ros2.publisher import planar_twist
from mobot_cli.scenario.limits import MAX_ANGULAR_SPEED, MAX_SPEED

MALFORMED = "not a little-endian CDR Twist"
NOT_FINITE = "not finite"
TOO_FAST = f"beyond {MAX_SPEED:g} m/s or {MAX_ANGULAR_SPEED:g} rad/s"


def cmd_vel(data: bytes) -> tuple[float, float, float] | str:
    """(linear.x, angular.z, linear.y) of a sample the world may take, or why it is dropped."""
    try:
        linear, linear_y, angular = planar_twist(data)
    except ValueError:
        return MALFORMED
    if not (math.isfinite(linear) and math.isfinite(angular) and math.isfinite(linear_y)):
        return NOT_FINITE
    if abs(linear) > MAX_SPEED or abs(angular) > MAX_ANGULAR_SPEED or abs(linear_y) > MAX_SPEED:
        return TOO_FAST
    return linear, angular, linear_y


def sideways_ignored(name: str, kind: str) -> str:
    """The one warning for linear.y sent to a robot that cannot move sideways (it is dropped, as
    nav2 sends 0 there for such robots anyway)."""
    return (f"ROS 2: cmd_vel linear.y for robot '{name}' is ignored: it has a {kind} drive, and only "
            "holonomic (mecanum, omni) drives move sideways")


class Drops:
    """Samples dropped, per topic and why: counted on Cyclone's threads, said on the world's."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._counts: dict[str, dict[str, int]] = {}
        self._changed = False
        self._lines: dict[str, int] = {}  # topic -> its line in the notices

    def count(self, topic: str, why: str) -> None:
        with self._lock:
            reasons = self._counts.setdefault(topic, {})
            reasons[why] = reasons.get(why, 0) + 1
            self._changed = True

    def by_topic(self) -> dict[str, int]:
        """Samples dropped on each topic."""
        with self._lock:
            return {topic: sum(reasons.values()) for topic, reasons in self._counts.items()}

    def say(self, notices: list[str]) -> None:
        """Keep one line per topic in ``notices`` (summary.json's) up to date: added the first
        time, its count rewritten after."""
        if not self._changed:
            return
        with self._lock:
            self._changed = False
            counts = {topic: dict(reasons) for topic, reasons in self._counts.items()}
        for topic, reasons in counts.items():
            why = ", ".join(f"{n} {reason}" for reason, n in sorted(reasons.items()))
            line = f"ROS 2: {sum(reasons.values())} sample(s) on {topic} dropped ({why}); the world went on"
            if topic in self._lines:
                notices[self._lines[topic]] = line
            else:
                self._lines[topic] = len(notices)
                notices.append(line)
