"""How hard a robot's wheel motors may push: the torque limit of each driven wheel.

In order, the first given wins (docs/faults.md, "Wheel torque"):

1. the scenario's ``drive: {max_wheel_torque}`` (merged in scenario/robots.py);
2. the drive plugin's torque (``wheelTorque``, ``max_wheel_torque``, ``torque``): gazebo_ros's
   diff drive sets it as the wheel joints' motor limit, over any URDF limit;
3. the wheel joints' URDF ``<limit effort>`` (the smallest positive one; SDF's unlimited -1
   is none), which Gazebo applies to velocity commands when no plugin says otherwise;
4. a default that grows with the robot: the torque that accelerates the whole robot at
   ``DESIGN_ACCELERATION`` up a ``DESIGN_SLOPE`` slope with every driven wheel pushing,
   ``m * (a + g sin(slope)) * r / n`` (0.81 m g r / n), but never less than ``FLOOR_TORQUE``.

The default's design point, 1 m/s^2 up 45 deg, is 0.81 g: below the 1 g at which a wheel that
carries its share of the weight slips on friction-1 ground (more torque only spins wheels), and
above what a skid-steer base needs to turn in place, 0.5 * (wheelbase / track) * m g r / n with
mobot's sideways wheel friction of 0.5, for wheelbases up to 1.6 times the track. The 20 N*m
floor is mobot's old fixed default: robots up to about 50 kg (wheel radius 0.1 m, four wheels)
drive exactly as before.
"""

from __future__ import annotations

import dataclasses
import math
import xml.etree.ElementTree as ET

from mobot_cli.plan import DriveSpec

FLOOR_TORQUE = 20.0  # N*m per wheel: never less by default
DESIGN_ACCELERATION = 1.0  # m/s^2
DESIGN_SLOPE = math.radians(45.0)
GRAVITY = 9.81  # m/s^2: standard gravity (the description knows no scenario)
# An effort this large is no limit: SDF's -1 ("unlimited", also its default) becomes this in the
# URDF mobot writes for an SDF robot (assets/world/to_urdf.py); such wheels get the default.
UNLIMITED_EFFORT = 1e6  # N*m


def mass_torque(mass: float, radius: float, wheels: int) -> float:
    """The default torque per wheel (N*m) for a robot of ``mass`` kg on ``wheels`` driven wheels."""
    need = mass * (DESIGN_ACCELERATION + GRAVITY * math.sin(DESIGN_SLOPE)) * radius / max(1, wheels)
    return max(FLOOR_TORQUE, round(need, 3))


def robot_mass(robot: ET.Element) -> float:
    """The sum of the links' inertial masses (kg); unreadable values count as 0."""
    total = 0.0
    for mass in robot.findall("link/inertial/mass"):
        try:
            value = float(mass.get("value", "0"))
        except ValueError:
            continue
        if math.isfinite(value) and value > 0:
            total += value
    return total


def joint_effort(robot: ET.Element, joints: tuple[str, ...]) -> float | None:
    """The smallest positive ``<limit effort>`` below UNLIMITED_EFFORT among these joints, or None."""
    wanted, efforts = set(joints), []
    for joint in robot.findall("joint"):
        limit = joint.find("limit")
        if joint.get("name") not in wanted or limit is None:
            continue
        try:
            effort = float(limit.get("effort", ""))
        except ValueError:
            continue
        if 0 < effort < UNLIMITED_EFFORT:
            efforts.append(effort)
    return min(efforts) if efforts else None


def with_torque(robot: ET.Element, spec: DriveSpec | None) -> DriveSpec | None:
    """``spec`` with its torque limit chosen as the module says (a plugin's torque kept)."""
    if spec is None or spec.torque_source in ("plugin", "scenario"):
        return spec
    wheels = spec.left_joints + spec.right_joints
    effort = joint_effort(robot, wheels)
    if effort is not None:
        return dataclasses.replace(spec, max_wheel_torque=effort, torque_source="urdf")
    torque = mass_torque(robot_mass(robot), spec.wheel_radius, len(wheels))
    return dataclasses.replace(spec, max_wheel_torque=torque, torque_source="mass")
