"""Robots and worlds as files: finding them, reading them, checking them.

``description/`` turns a robot description (URDF, xacro, an SDF model) into a checked
RobotDescription; ``world/`` turns an SDF world (its models, meshes and poses) into a
WorldPlan; ``resources.py`` finds packages, models and files for both.

Imports here stay light: yourdfpy, trimesh and xacro load only when a description is
expanded or checked for the first time (a warm load reads the cache).
"""

from mobot_cli.assets.description.describe import bundled_robot_names, expand_to_text, load_robot
from mobot_cli.assets.description.drive import detect_drive
from mobot_cli.assets.description.robot import JointInfo, LinkInfo, RobotDescription, inspect_summary
from mobot_cli.assets.resources import ResourceResolver, bundled_dir

__all__ = ["JointInfo", "LinkInfo", "ResourceResolver", "RobotDescription", "bundled_dir",
           "bundled_robot_names", "detect_drive", "expand_to_text", "inspect_summary",
           "load_robot"]
