"""Movers on ROS 2: each one a frame ``movers/<name>`` under ``world`` on /tf, as another DDS
participant in a process of its own sees them (tests/ros2/dds_peer.py)."""

from __future__ import annotations

import pytest

from tests.live.live_server import LiveProcess
from tests.ros2.test_dds import peer, ros_env  # noqa: F401 - the fixture the peer needs

pytest.importorskip("cyclonedds")

WORLD = """version: 1
name: ros2_movers
world: empty
duration: 1.0
robots:
  - {name: r1, description: mobot, pose: {x: 0.0, y: 0.0}}
movers:
  - {name: pacer, path: [[2.0, -1.0], [2.0, 1.0]], mode: pingpong, speed: 0.5}
"""


def test_movers_are_frames_on_tf(tmp_path, tmp_path_factory):
    scenario = tmp_path / "world.yaml"
    scenario.write_text(WORLD)
    live = LiveProcess(str(scenario), "--ros2", cache_dir=tmp_path_factory.mktemp("cache"))
    try:
        tf = peer("take", "rt/tf", "tf2_msgs/msg/TFMessage", "2")
    finally:
        live.signal()
        live.kill()
    movers = [t for message in tf for t in message["transforms"] if t["child_frame_id"] == "movers/pacer"]
    assert len(movers) >= 10  # 20 Hz updates for 2 s, in real time
    assert all(t["header"]["frame_id"] == "world" and t["transform"]["translation"]["x"] == 2.0 for t in movers)
    ys = [t["transform"]["translation"]["y"] for t in movers]
    assert max(ys) - min(ys) > 0.2 and all(-1.0 <= y <= 1.0 for y in ys)
