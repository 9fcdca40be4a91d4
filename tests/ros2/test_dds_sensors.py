"""Every sensor topic the bag has reaches another DDS participant from `mobot serve --ros2`:
<ns>/imu, <ns>/points, <ns>/bumper and a range sensor's, with ROS 2's type names, QoS and hashes, at the
sensor's rate, decoding to what the sensor reads (tests/ros2/dds_peer.py, on loopback)."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.live.live_server import LiveProcess
from tests.ros2.test_dds import PEER, ros_env  # noqa: F401 - ros_env: the peer imports this checkout
from tests.sim.sensor_world import HALF_X, ROOM_SDF

pytest.importorskip("cyclonedds")

# r1 stands in the middle of the room with its IMU and a 3D lidar that sees only the east
# wall (x = 3 m); r2 drives west into the west wall with a bumper on its base; r3, the range
# sensors' box (tests/assets/sensors/range.urdf), faces the east wall 1.9 m from its infrared ray.
SCENARIO = """version: 1
name: ros2_sensors
world: room.sdf
duration: 30.0
log: {rate_hz: 48}
robots:
  - name: r1
    description: mobot
    args: {imu: 'true'}
    pose: {x: 0.0, y: 0.0}
    sensors:
      points: {type: lidar, link: base_link, rate_hz: 10, samples: 21, min_angle: -0.5, max_angle: 0.5,
               vertical_samples: 3, vertical_min_angle: 0.0, vertical_max_angle: 0.2, range_max: 10.0}
  - name: r2
    description: mobot
    pose: {x: -1.2, y: 1.2, yaw: 3.14159}
    sensors:
      bumper: {type: contact, link: base_link, rate_hz: 20}
    commands:
      - {at: 0.5, linear: 0.5}
  - name: r3
    description: RANGER
    pose: {x: 1.0, y: -1.0}
"""
RANGER = Path(__file__).resolve().parents[1] / "assets" / "sensors" / "range.urdf"
TOPICS = {"rt/r1/imu": ("sensor_msgs::msg::dds_::Imu_", "RIHS01_7d9a00ff131080897a5ec7e26e315954b8eae3353c3f995c55"),
          "rt/r1/points": ("sensor_msgs::msg::dds_::PointCloud2_", "RIHS01_9198cabf7da3796ae6fe19c4cb3bdd352549"),
          "rt/r2/bumper": ("gazebo_msgs::msg::dds_::ContactsState_", "RIHS01_1dc585e627c16551e50102b983ec51321"),
          "rt/r3/ir/front": ("sensor_msgs::msg::dds_::Range_", "RIHS01_b42b62562e93cbfe9d42b82fe5994dfa3d63d7d5c90a3")}


def peers(*calls: tuple[str, ...], timeout: float = 90) -> list:
    """Run several tests/ros2/dds_peer.py verbs at once; their JSON answers in order."""
    runs = [subprocess.Popen([sys.executable, str(PEER), *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             text=True) for args in calls]
    out = []
    for run in runs:
        stdout, stderr = run.communicate(timeout=timeout)
        assert run.returncode == 0, stderr
        out.append(json.loads(stdout))
    return out


def stamps(messages: list) -> list[float]:
    return [m["header"]["stamp"]["sec"] + m["header"]["stamp"]["nanosec"] * 1e-9 for m in messages]


@pytest.fixture(scope="module")
def received(tmp_path_factory):
    folder = tmp_path_factory.mktemp("ros2-sensors")
    (folder / "room.sdf").write_text(ROOM_SDF)
    (folder / "world.yaml").write_text(SCENARIO.replace("RANGER", str(RANGER)))
    live = LiveProcess(str(folder / "world.yaml"), "--ros2", cache_dir=tmp_path_factory.mktemp("cache"))
    try:
        return peers(("graph", "3"), ("take", "rt/r1/imu", "sensor_msgs/msg/Imu", "3"),
                     ("take", "rt/r1/points", "sensor_msgs/msg/PointCloud2", "3"),
                     ("take", "rt/r2/bumper", "gazebo_msgs/msg/ContactsState", "8"),
                     ("take", "rt/r3/ir/front", "sensor_msgs/msg/Range", "3"))
    finally:
        live.signal()
        live.kill()


def test_sensor_topics_are_in_the_graph_with_types_qos_and_hashes(received):
    seen = received[0]
    pubs = {p["topic"]: p for p in seen["publications"] if p["topic"] in TOPICS}
    assert {t: (p["type"], p["durability"], p["reliability"], p["depth"]) for t, p in pubs.items()} == {
        t: (kind, "volatile", "reliable", 10) for t, (kind, _) in TOPICS.items()}
    for topic, (_, rihs01) in TOPICS.items():
        assert pubs[topic]["userdata"].startswith(f"typehash={rihs01}"), topic


def test_imu_at_rest_reads_gravity_at_120_hz(received):
    imus = received[1]
    assert len(imus) >= 120  # 3 s at 120 Hz in real time, less on a busy machine
    times = stamps(imus)
    assert all(abs(b - a - 2 / 240) < 1e-6 for a, b in zip(times, times[1:]))  # every 2nd step, no gaps
    accel = np.array([[m["linear_acceleration"][k] for k in "xyz"] for m in imus])
    assert np.mean(accel[:, 2]) == pytest.approx(9.81, abs=0.02)  # a real IMU at rest: +g up
    assert np.all(np.abs(np.mean(accel[:, :2], axis=0)) < 0.02)
    assert imus[-1]["header"]["frame_id"] == "r1/base_link"
    assert imus[-1]["linear_acceleration_covariance"][0] == pytest.approx(1.7e-2 ** 2)  # the xacro's noise
    assert abs(imus[-1]["orientation"]["w"]) == pytest.approx(1.0, abs=1e-3)


def test_points_lie_on_the_east_wall_at_10_hz(received):
    clouds = received[2]
    assert len(clouds) >= 10
    times = stamps(clouds)
    assert all(abs(b - a - 0.1) < 1e-6 for a, b in zip(times, times[1:]))
    cloud = clouds[-1]
    assert (cloud["height"], cloud["width"], cloud["point_step"], cloud["is_dense"]) == (1, 63, 16, True)
    assert [f["name"] for f in cloud["fields"]] == ["x", "y", "z", "intensity"]
    points = np.frombuffer(bytes(cloud["data"]), dtype="<f4").reshape(-1, 4)
    assert np.all(np.abs(points[:, 0] - HALF_X) < 0.02)  # r1 stands at the origin facing the wall
    assert np.max(np.abs(points[:, 1])) == pytest.approx(HALF_X * math.tan(0.5), abs=0.02)
    assert cloud["header"]["frame_id"] == "r1/base_link"


def test_bumper_feels_the_wall_it_drives_into(received):
    bumps = received[3]
    assert len(bumps) >= 60  # 8 s at 20 Hz in real time
    times = stamps(bumps)
    assert all(abs(b - a - 0.05) < 1e-6 for a, b in zip(times, times[1:]))
    touching = [b for b in bumps if b["states"]]
    assert touching  # it reaches the wall (1.2 s away: free before, the floor never counts)
    assert not any(b["states"] for b, t in zip(bumps, times) if t < 1.5)
    state = touching[-1]["states"][0]
    assert state["collision1_name"] == "r2::base_link::base_link" and "walls" in state["collision2_name"]
    assert all(n["x"] > 0.9 for n in state["contact_normals"])  # the west wall pushes back (+x)
    assert touching[-1]["header"]["frame_id"] == "world"


def test_range_reads_the_wall_at_20_hz_as_sensor_msgs_range(received):
    ranges = received[4]
    assert len(ranges) >= 20  # 3 s at 20 Hz in real time
    times = stamps(ranges)
    assert all(abs(b - a - 0.05) < 1e-6 for a, b in zip(times, times[1:]))
    last = ranges[-1]
    assert last["range"] == pytest.approx(HALF_X - 1.1, abs=0.01)
    assert (last["radiation_type"], last["min_range"], last["max_range"]) == (1, pytest.approx(0.02), 4.0)
    assert last["header"]["frame_id"] == "r3/base_link_ir_front"
