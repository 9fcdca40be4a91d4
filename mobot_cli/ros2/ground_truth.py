"""``<ns>/odom/ground_truth``: where a robot really is, as nav stacks and evaluation tools expect it.

A nav_msgs/Odometry of the base link in the ``world`` frame (the frame /map and every robot's
odom hang from), from the simulator's state, not the wheels': full 3D pose, the twist in the
base link's axes (forward, sideways, yaw rate), zero covariance. Published at the log rate,
built only while someone reads it (gazebo's p3d plugin and Isaac Sim's ground-truth odometry
give the same).
"""

from __future__ import annotations

from mobot_cli.common.transforms import quat_from_rpy
from mobot_cli.ros.cdr import Layout, Packer
from mobot_cli.ros.messages import Stamp
from mobot_cli.sim.state import RobotState

TOPIC = "odom/ground_truth"  # under the robot's namespace
FRAME = "world"
_ZERO = (0.0,) * 36


def packer(base_frame: str) -> Packer:
    """The Odometry layout: world -> ``base_frame``, stamp, pose and twist variable."""
    return (Layout().header(FRAME).string(base_frame).var("d", 7).doubles(_ZERO).var("d", 6).doubles(_ZERO)).build()


def message(pack: Packer, stamp: Stamp, s: RobotState) -> bytes:
    """The robot's ground truth at ``stamp`` as Odometry CDR."""
    qx, qy, qz, qw = quat_from_rpy(s.true_roll, s.true_pitch, s.true_yaw)
    return pack.pack((*stamp, s.true_x, s.true_y, s.true_z, qx, qy, qz, qw, s.true_vx, s.true_vy, 0.0, 0.0, 0.0,
                      s.true_wz))
