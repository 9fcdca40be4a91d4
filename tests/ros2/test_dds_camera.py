"""A camera's topics from `mobot serve --ros2` reach another DDS participant (tests/ros2/dds_peer.py, on
loopback): <ns>/<camera>/image_raw, depth/image_raw and camera_info, with ROS 2's types and hashes, at the
camera's rate, the image seeing the room's east wall at its distance."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mobot_cli.ros.definitions import CAMERA_INFO, IMAGE, MESSAGES
from tests.live.live_server import LiveProcess
from tests.ros2.test_dds import ros_env  # noqa: F401 - ros_env: the peer imports this checkout
from tests.ros2.test_dds_sensors import peers, stamps
from tests.sim.sensor_world import HALF_X, ROOM_SDF

pytest.importorskip("cyclonedds")

SCENARIO = """version: 1
name: ros2_camera
world: room.sdf
duration: 30.0
log: {rate_hz: 48}
robots:
  - name: r1
    description: mobot
    pose: {x: 0.0, y: 0.0}
    sensors:
      front: {type: rgbd_camera, link: base_link, rate_hz: 5, width: 16, height: 12, horizontal_fov: 1.0,
              clip_far: 10.0, pose: {xyz: [0.0, 0.0, 0.5]}}
"""


@pytest.fixture(scope="module")
def received(tmp_path_factory):
    folder = tmp_path_factory.mktemp("ros2-camera")
    (folder / "room.sdf").write_text(ROOM_SDF)
    (folder / "world.yaml").write_text(SCENARIO)
    live = LiveProcess(str(folder / "world.yaml"), "--ros2", cache_dir=tmp_path_factory.mktemp("cache"))
    try:
        return peers(("graph", "3"), ("take", "rt/r1/front/image_raw", IMAGE, "3"),
                     ("take", "rt/r1/front/depth/image_raw", IMAGE, "3"),
                     ("take", "rt/r1/front/camera_info", CAMERA_INFO, "3"))
    finally:
        live.signal()
        live.kill()


def test_camera_topics_are_in_the_graph_with_their_types_and_hashes(received):
    pubs = {p["topic"]: p for p in received[0]["publications"] if p["topic"].startswith("rt/r1/front/")}
    assert {t: p["type"] for t, p in pubs.items()} == {
        "rt/r1/front/image_raw": "sensor_msgs::msg::dds_::Image_",
        "rt/r1/front/depth/image_raw": "sensor_msgs::msg::dds_::Image_",
        "rt/r1/front/camera_info": "sensor_msgs::msg::dds_::CameraInfo_"}
    assert pubs["rt/r1/front/camera_info"]["userdata"].startswith(f"typehash={MESSAGES[CAMERA_INFO][1]}")
    assert pubs["rt/r1/front/image_raw"]["userdata"].startswith(f"typehash={MESSAGES[IMAGE][1]}")


def test_images_depth_and_camera_info_come_at_5_hz_and_agree(received):
    images, depths, infos = received[1:]
    assert len(images) >= 5 and len(depths) >= 5 and len(infos) >= 5  # 3 s at 5 Hz in real time
    for messages in (images, depths, infos):
        times = stamps(messages)
        assert all(abs(b - a - 0.2) < 1e-6 for a, b in zip(times, times[1:]))
    image, depth, info = images[-1], depths[-1], infos[-1]
    assert (image["encoding"], image["width"], image["height"], image["step"]) == ("rgb8", 16, 12, 48)
    assert (depth["encoding"], depth["step"]) == ("32FC1", 64)
    fx = 16 / (2 * math.tan(0.5))
    assert np.allclose(info["k"], [fx, 0, 7.5, 0, fx, 5.5, 0, 0, 1])
    assert info["header"]["frame_id"] == image["header"]["frame_id"] == "r1/base_link_front_optical"
    metres = np.frombuffer(bytes(depth["data"]), "<f4").reshape(12, 16)
    # The middle of the image is the east wall, straight ahead (the camera 0.5 m up, the robot at x = 0).
    assert metres[5:7, 7:9] == pytest.approx(HALF_X, abs=0.05)
