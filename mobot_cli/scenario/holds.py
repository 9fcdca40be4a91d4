"""A robot's ``hold:``: joints a position controller holds, as a vendor's plugin holds an arm in
Gazebo (Fetch's arm, head and torso: left free in PyBullet, the arm swings and tips the robot)."""

from __future__ import annotations

import dataclasses

from mobot_cli.assets.description.joints import FREE, asked_holds
from mobot_cli.assets.description.robot import RobotDescription
from mobot_cli.errors import Location, ScenarioError, did_you_mean
from mobot_cli.plan import DriveSpec, JointHold
from mobot_cli.scenario.model import RobotSpec


def resolve_holds(spec: RobotSpec, desc: RobotDescription, drive: DriveSpec | None, where: Location | None,
                  notices: list[str]) -> tuple[JointHold, ...]:
    """The description's held joints and the scenario's ``hold:`` ("all", or {joint: position});
    the notice of the joints still left free goes to ``notices`` (said here, not when the
    description is loaded: ``hold:`` may take them)."""
    free_notices = [n for n in desc.notices if n.message.startswith(FREE)]
    if spec.hold is None:
        notices.extend(str(n) for n in free_notices)
        return desc.holds
    holds, unknown, free, holdable = asked_holds(desc.urdf, drive, desc.holds, spec.hold, desc.bottom_z)
    if unknown:
        shown = ", ".join(repr(n) for n in unknown[:5]) + (f" and {len(unknown) - 5} more" if len(unknown) > 5 else "")
        raise ScenarioError(f"hold names {shown}: no joint of "
                            f"'{spec.description}' a position controller can hold", location=where,
                            hint=f"{did_you_mean(unknown[0], holdable)} Name revolute, continuous or prismatic "
                                 "joints that are not drive wheels (mobot inspect lists the joints), or give "
                                 "hold: all.".lstrip())
    if free and free_notices:
        notices.append(str(dataclasses.replace(free_notices[0], message=FREE + ", ".join(free))))
    return holds
