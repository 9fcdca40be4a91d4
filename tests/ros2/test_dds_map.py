"""``ros2: {map: true}``: the world's grid on /map, as another DDS participant (a late joiner) takes it."""

from __future__ import annotations

import numpy as np
import pytest

from mobot_cli.cli import invoke
from tests.live.live_server import LiveProcess
from tests.ros.nav2_map import load_map
from tests.ros2.test_dds import cache, peer, ros_env  # noqa: F401 - fixtures

pytest.importorskip("cyclonedds")

HOUSE = """version: 1
name: ros2_map
world: house
duration: 1.0
log: {rate_hz: 24}
robots:
  - {name: r1, description: mobot, pose: {x: -3.0, y: -2.5}}
ros2: {map: MAP}
"""


def serve(tmp_path, cache, on: bool) -> LiveProcess:  # noqa: F811 - the fixture's value
    scenario = tmp_path / "world.yaml"
    scenario.write_text(HOUSE.replace("MAP", "true" if on else "false"))
    return LiveProcess(str(scenario), "--ros2", cache_dir=cache)


def test_map_is_latched_and_is_what_mobot_map_writes(tmp_path, cache):  # noqa: F811
    live = serve(tmp_path, cache, True)
    try:
        seen = peer("graph", "2")
        maps = peer("take", "rt/map", "nav_msgs/msg/OccupancyGrid", "2", "latched")
    finally:
        live.signal()
        live.kill()
    (pub,) = [p for p in seen["publications"] if p["topic"] == "rt/map"]
    assert (pub["type"], pub["durability"], pub["reliability"], pub["depth"]) == (
        "nav_msgs::msg::dds_::OccupancyGrid_", "transient_local", "reliable", 1)
    assert len(maps) == 1  # sent once, taken by a subscriber that joined afterwards
    message = maps[0]
    info = message["info"]
    assert message["header"]["frame_id"] == "world"
    done = invoke(["map", "house", "--out", tmp_path / "files"])
    assert done.exit_code == 0, done.stderr
    data, resolution, origin = load_map(tmp_path / "files" / "map.yaml")
    assert (info["width"], info["height"]) == (data.shape[1], data.shape[0])
    assert info["resolution"] == pytest.approx(resolution)
    assert (info["origin"]["position"]["x"], info["origin"]["position"]["y"]) == pytest.approx(origin[:2])
    assert info["origin"]["orientation"]["w"] == 1.0
    published = np.array(message["data"], dtype=np.int8).reshape(data.shape)
    assert (published == data).all() and (published == 100).sum() > 5000


def test_no_map_unless_asked(tmp_path, cache):  # noqa: F811
    live = serve(tmp_path, cache, False)
    try:
        seen = peer("graph", "2")
    finally:
        live.signal()
        live.kill()
    assert "rt/r1/odom" in {p["topic"] for p in seen["publications"]}
    assert "rt/map" not in {p["topic"] for p in seen["publications"]}
