"""Units of the scenario format: seconds to whole steps, the three pose forms to a quaternion."""

from __future__ import annotations

import math

from mobot_cli.common.transforms import quat_from_rpy
from mobot_cli.plan import SpawnPose
from mobot_cli.scenario.model import PoseSpec


def steps(seconds: float, rate_hz: int) -> int:
    """Seconds to the nearest whole physics step (halves round up), computed once at load."""
    return int(math.floor(seconds * rate_hz + 0.5))


def spawn_pose(pose: PoseSpec) -> SpawnPose:
    """Any of the three pose forms to a SpawnPose; an omitted z means 'auto'."""
    if pose.xyz is not None:
        x, y, z = pose.xyz
        quat = pose.quat if pose.quat is not None else quat_from_rpy(*(pose.rpy or (0.0, 0.0, 0.0)))
    else:
        x, y, z = pose.x or 0.0, pose.y or 0.0, pose.z
        quat = quat_from_rpy(pose.roll or 0.0, pose.pitch or 0.0, pose.yaw or 0.0)
    auto = z is None or z == "auto"
    return SpawnPose(xyz=(float(x), float(y), 0.0 if auto else float(z)), quat=_normalized(quat), z_auto=auto)


def _normalized(q) -> tuple[float, float, float, float]:
    n = math.sqrt(sum(c * c for c in q))
    # Leave unit quaternions bit-for-bit alone so a resolved scenario reloads to the same plan.
    return tuple(float(c) for c in q) if abs(n - 1.0) < 1e-12 else tuple(float(c) / n for c in q)

