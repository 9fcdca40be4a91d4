"""What a robot looks like from outside at one instant: its odometry and the ground truth."""

from __future__ import annotations

import math
import operator
from dataclasses import dataclass, field


# Not frozen: one is built per robot per log row, and a frozen dataclass's __init__ costs
# 3.3 us against 0.7 us with slots (measured). Treat it as read-only all the same.
@dataclass(slots=True)
class RobotState:
    """One robot's command, odometry (odom frame = spawn pose) and world-frame truth.

    Velocities are in the robot's own frame and signed: driving backwards gives negative
    ``odom_vx`` and ``true_vx``. Angles are radians wrapped to [-pi, pi).
    """

    cmd_linear: float
    cmd_angular: float
    odom_x: float
    odom_y: float
    odom_yaw: float
    odom_vx: float
    odom_wz: float
    true_x: float
    true_y: float
    true_z: float
    true_roll: float
    true_pitch: float
    true_yaw: float
    true_vx: float
    true_wz: float
    joint_positions: dict[str, float] = field(default_factory=dict, compare=True)
    collisions: int = 0  # collision events so far (sim/contacts.py); not a CSV column
    joint_velocities: dict[str, float] = field(default_factory=dict)  # rad/s or m/s; for joint_states
    # Distance to the nearest world geometry or robot (sim/clearance.py) and what it is, for a
    # robot whose clearance is watched; +inf otherwise or when nothing is that near. Not columns.
    clearance: float = math.inf
    nearest: str = ""
    cmd_linear_y: float = 0.0  # m/s, the sideways part of the command (holonomic drives); not a column
    # Sideways velocities in the robot's frame, reported for holonomic drives (0 for the others,
    # whose wheels cannot give one); the odom message carries odom_vy. Not columns.
    odom_vy: float = 0.0
    true_vy: float = 0.0
    hit: str = ""  # what its last collision was with, as messages name it ("static body 'box'"); not a column
    # With people in the world (movers of shape person, actors: docs/movers.md): collision events
    # with them (also counted in ``collisions``) and the distance in the plane from the root
    # link's origin to the nearest person's axis (+inf: no person; measured, as clearance, for a
    # robot whose clearance is watched: its goals' metrics read it). Not columns.
    people_collisions: int = 0
    people_distance: float = math.inf

    # Column order of the odom CSV (DESIGN.md), without the leading time column.
    CSV_FIELDS = (
        "cmd_linear", "cmd_angular", "odom_x", "odom_y", "odom_yaw", "odom_vx", "odom_wz",
        "true_x", "true_y", "true_z", "true_roll", "true_pitch", "true_yaw", "true_vx", "true_wz",
    )

    def row(self) -> tuple[float, ...]:
        """The CSV columns of this state, in DESIGN.md's order."""
        return _CSV_GETTER(self)


_CSV_GETTER = operator.attrgetter(*RobotState.CSV_FIELDS)  # one C call per row: this is hot
