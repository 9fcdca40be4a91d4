"""Robot descriptions and the files they reference: resolving, xacro expansion, checks.

Imports here stay light: yourdfpy, trimesh and xacro load only when a description is
expanded or checked for the first time (a warm load reads the cache).
"""

from mobot_cli.assets.description import (JointInfo, LinkInfo, RobotDescription,
                                          bundled_robot_names, expand_to_text, inspect_summary,
                                          load_robot)
from mobot_cli.assets.drive_detect import detect_drive
from mobot_cli.assets.resources import ResourceResolver, bundled_dir

__all__ = ["JointInfo", "LinkInfo", "ResourceResolver", "RobotDescription", "bundled_dir",
           "bundled_robot_names", "detect_drive", "expand_to_text", "inspect_summary",
           "load_robot"]
