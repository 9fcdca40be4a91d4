"""Drive wheels that cannot push: Gazebo friction 0 on a wheel the drive turns.

Robotnik's summit_xl with ``omni_wheels:=true`` gives its wheels ``mu1`` and ``mu2`` 0: in Gazebo
a planar-move plugin moves the body and the wheels only carry it. Without that plugin the wheels
are found as a skid-steer drive; they spin and the robot stands still, in mobot's physics engine
as in Gazebo, while the kinematic engine (which ignores friction) drives it. One notice says so.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from mobot_cli.errors import Location, Notice
from mobot_cli.plan import DriveSpec

# Friction at or below this cannot push a robot (Gazebo's default is 1).
NO_GRIP = 1e-3


def slipping_wheels(robot: ET.Element, drive: DriveSpec | None, friction: dict[str, float],
                    source: Path | None) -> Notice | None:
    """One notice naming the driven wheels whose Gazebo friction (``friction``: link -> mu, as
    process.apply_friction gives it) is ~0, for drives that push through their wheels."""
    if drive is None or drive.kind in ("mecanum", "omni"):  # those move the body, rollers are frictionless
        return None
    children = {j.get("name", ""): (j.find("child").get("link", "") if j.find("child") is not None else "")
                for j in robot.findall("joint")}
    slipping = [name for name in (*drive.left_joints, *drive.right_joints)
                if friction.get(children.get(name, ""), 1.0) <= NO_GRIP]
    if not slipping:
        return None
    return Notice(f"drive wheels {', '.join(slipping)} have Gazebo friction 0 (<mu1>, <mu2>): they cannot "
                  "push the robot, which stands still in the physics engine as in Gazebo (the kinematic engine "
                  "ignores friction); a base that a planar-move plugin moves is driven with drive: {type: holonomic}",
                  Location(file=source))
