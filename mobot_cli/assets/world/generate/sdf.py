"""A generated world as an SDF 1.6 world file Gazebo opens, and as the WorldPlan that loading
that file gives (the same bodies, names, poses and labels, number for number)."""

from __future__ import annotations

from xml.sax.saxutils import quoteattr

from mobot_cli.assets.world.generate.shapes import Generated, Obstacle
from mobot_cli.plan import StaticBody, StaticShape, WorldPlan

HEAD = """<?xml version="1.0"?>
<!-- {comment} -->
<sdf version="1.6">
  <world name={name}>
    <light name="sun" type="directional">
      <cast_shadows>true</cast_shadows>
      <pose>0 0 10 0 0 0</pose>
      <diffuse>0.8 0.8 0.8 1</diffuse>
      <direction>-0.5 0.5 -1</direction>
    </light>
    <model name="ground_plane">
      <static>true</static>
      <link name="link">
        <collision name="collision">
          <geometry><plane><normal>0 0 1</normal><size>100 100</size></plane></geometry>
        </collision>
        <visual name="visual">
          <geometry><plane><normal>0 0 1</normal><size>100 100</size></plane></geometry>
        </visual>
      </link>
    </model>
"""
MODEL = """    <model name="{name}">
      <static>true</static>
      <pose>{pose}</pose>
      <link name="link">
        <collision name="collision">
          <geometry>{geometry}</geometry>
        </collision>
        <visual name="visual">
          <geometry>{geometry}</geometry>
        </visual>
      </link>
    </model>
"""
TAIL = """  </world>
</sdf>
"""


def _n(value: float) -> str:
    return f"{value:.6f}".rstrip("0").rstrip(".") if value else "0"


def _pose(o: Obstacle) -> str:
    return f"{_n(o.x)} {_n(o.y)} {_n(o.height / 2)} 0 0 {_n(o.yaw)}"


def _geometry(o: Obstacle) -> str:
    if o.kind == "box":
        return f"<box><size>{' '.join(_n(v) for v in o.size)}</size></box>"
    return f"<cylinder><radius>{_n(o.size[0])}</radius><length>{_n(o.size[1])}</length></cylinder>"


def to_sdf(world: Generated, comment: str) -> str:
    """The world file's text: a ground plane, a sun, one static model per obstacle."""
    parts = [HEAD.format(comment=comment.replace("--", "- -"), name=quoteattr(world.name))]
    parts += [MODEL.format(name=o.name, pose=_pose(o), geometry=_geometry(o)) for o in world.obstacles]
    parts.append(TAIL)
    return "".join(parts)


def to_plan(world: Generated) -> WorldPlan:
    """The WorldPlan that loading ``to_sdf(world)`` gives (its source aside)."""
    from mobot_cli.assets.world.pose import parse_pose, xyz_quat

    bodies = []
    for o in world.obstacles:
        xyz, quat = xyz_quat(parse_pose(_pose(o)))
        label = f"world model '{o.name}' at ({_cm(xyz[0])}, {_cm(xyz[1])}, {_cm(xyz[2])})"
        shape = StaticShape(kind=o.kind, size=tuple(float(_n(v)) for v in o.size), name="link::collision")
        bodies.append(StaticBody(name=o.name, xyz=xyz, quat=quat, shapes=(shape,), label=label))
    return WorldPlan(name=world.name, ground_plane=True, bodies=tuple(bodies))


def _cm(value: float) -> str:
    """As world loading labels a model: to the centimetre, never '-0.00'."""
    return f"{round(value, 2) + 0.0:.2f}"
