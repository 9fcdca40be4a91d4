"""A room with known walls and plans with sensors, shared by the sensor tests.

The room's walls are boxes whose inner faces lie at x = +-3 m and y = +-2 m, 2 m high, on
the ground plane. Sensors are given as SensorSpecs (what the description parser makes).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np

from mobot_cli.plan import Plan, RayAxis, SensorSpec
from mobot_cli.scenario.prepare import prepare

HALF_X, HALF_Y, WALL_HEIGHT = 3.0, 2.0, 2.0

ROOM_SDF = f"""<?xml version="1.0"?>
<sdf version="1.6">
  <world name="room">
    <include><uri>model://ground_plane</uri></include>
    <model name="walls">
      <static>true</static>
      <link name="walls">
        <collision name="north"><pose>0 {HALF_Y + 0.1} 1 0 0 0</pose>
          <geometry><box><size>6.4 0.2 {WALL_HEIGHT}</size></box></geometry></collision>
        <collision name="south"><pose>0 {-HALF_Y - 0.1} 1 0 0 0</pose>
          <geometry><box><size>6.4 0.2 {WALL_HEIGHT}</size></box></geometry></collision>
        <collision name="east"><pose>{HALF_X + 0.1} 0 1 0 0 0</pose>
          <geometry><box><size>0.2 4.4 {WALL_HEIGHT}</size></box></geometry></collision>
        <collision name="west"><pose>{-HALF_X - 0.1} 0 1 0 0 0</pose>
          <geometry><box><size>0.2 4.4 {WALL_HEIGHT}</size></box></geometry></collision>
      </link>
    </model>
  </world>
</sdf>
"""


def room_scenario(folder: Path, robots: str, duration: float = 1.0, world: str = "room.sdf",
                  extra: str = "") -> Path:
    """A scenario file in ``folder`` (with the room beside it) holding the ``robots:`` YAML."""
    (folder / "room.sdf").write_text(ROOM_SDF)
    path = folder / "scenario.yaml"
    path.write_text(f"version: 1\nname: sensors\nworld: {world}\nduration: {duration}\nseed: 11\n"
                    f"settle: 0.0\n{extra}robots:\n{robots}")
    return path


def one_robot(folder: Path, x: float = 0.5, y: float = 0.25, yaw: float = 0.3, duration: float = 1.0,
              world: str = "room.sdf", args: str = "") -> Path:
    return room_scenario(folder, f"  - name: mobot\n    description: mobot\n{args}"
                                 f"    pose: {{x: {x}, y: {y}, yaw: {yaw}}}\n", duration, world)


def lidar(name: str = "scan", link: str = "base_link", every: int = 24, samples: int = 360,
          lo: float = -math.pi, hi: float = math.pi, vertical: RayAxis | None = None, **fields) -> SensorSpec:
    """A lidar as the parser would make it from a <sensor type="ray">."""
    values = dict(range_min=0.1, range_max=8.0, topic="")
    values.update(fields)
    return SensorSpec(name=name, kind="lidar", link=link, every=every,
                      horizontal=RayAxis(samples, lo, hi), vertical=vertical, **values)


def with_sensors(plan: Plan, robot: str, *sensors: SensorSpec, **plan_fields) -> Plan:
    """The plan with ``robot``'s sensors replaced."""
    robots = tuple(dataclasses.replace(r, sensors=sensors) if r.name == robot else r for r in plan.robots)
    return dataclasses.replace(plan, robots=robots, **plan_fields)


def planned(path: Path, robot: str, *sensors: SensorSpec, **plan_fields) -> tuple[Plan, str]:
    """Prepare a scenario and give ``robot`` these sensors: the plan and its resolved YAML."""
    prepared = prepare(path)
    return with_sensors(prepared.plan, robot, *sensors, **plan_fields), prepared.resolved_yaml


def room_distance(origin, directions: np.ndarray) -> np.ndarray:
    """Exact distance from ``origin`` along unit ``directions`` to the room's walls or floor."""
    o = np.asarray(origin, dtype=float)
    t = np.full(len(directions), np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):
        for axis, bound in ((0, HALF_X), (0, -HALF_X), (1, HALF_Y), (1, -HALF_Y), (2, 0.0)):
            ts = (bound - o[axis]) / directions[:, axis]
            hit = o + ts[:, None] * directions
            inside = (ts > 0) & (np.abs(hit[:, 0]) <= HALF_X + 1e-9) & (np.abs(hit[:, 1]) <= HALF_Y + 1e-9) \
                & (hit[:, 2] >= -1e-9) & (hit[:, 2] <= WALL_HEIGHT)
            t = np.where(inside & (ts < t), ts, t)
    return t
