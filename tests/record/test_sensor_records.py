"""Sensor records: the bag's sensor messages, the run folder's files, summary.json, determinism."""

from __future__ import annotations

import json
import math
import os
import signal
import struct
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from mobot_cli.cli import invoke
from mobot_cli.plan import CommandStep, RayAxis, SensorSpec
from mobot_cli.record.sensor_files import FLUSH_EVERY, read_header_rows
from mobot_cli.ros import sensor_cdr
from mobot_cli.ros.definitions import CONTACTS_STATE, MESSAGES
from mobot_cli.run import execute
from mobot_cli.sim.sensing.lidar import Beams
from mobot_cli.sim.sensing.readings import Contact
from tests.sim.sensor_world import lidar, one_robot, planned

REPO = Path(__file__).resolve().parents[2]


def _typestore():
    """rosbags' Humble typestore with gazebo_msgs registered from the embedded definitions."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    definition = MESSAGES[CONTACTS_STATE][0].split("=" * 80 + "\n")
    types = get_types_from_msg(definition[0], "gazebo_msgs/msg/ContactsState")
    for part in definition[1:]:
        head, body = part.split("\n", 1)
        package, name = head.removeprefix("MSG: ").split("/")
        if f"{package}/msg/{name}" not in store.types:
            types.update(get_types_from_msg(body, f"{package}/msg/{name}"))
    store.register(types)
    return store


def _sensors():
    velodyne = lidar("velodyne", samples=300, vertical=RayAxis(16, -0.2618, 0.2618), range_max=30.0,
                     xyz=(0.0, 0.0, 0.4), range_resolution=0.001)
    return (lidar(xyz=(0.0, 0.0, 0.3), range_max=3.0, noise_stddev=0.01), velodyne,
            SensorSpec(name="imu", kind="imu", link="base_link", every=4, noise_stddev=0.001,
                       accel_noise_stddev=0.01),
            SensorSpec(name="bumper", kind="contact", link="base_link", every=24))


@pytest.fixture(scope="module")
def sensor_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("sensor-run")
    plan, resolved = planned(one_robot(folder, x=2.2, y=0.0, yaw=0.0, duration=2.0), "mobot", *_sensors(),
                             formats=("csv", "mcap"))
    # It stands for a quarter second, then drives into the east wall 0.8 m ahead.
    robot = replace(plan.robots[0], commands=(CommandStep(step=60, linear=0.5, angular=0.0),))
    plan = replace(plan, robots=(robot,))
    return plan, execute(plan, resolved, folder / "out")


def test_packers_match_rosbags_serializer_byte_for_byte():
    store = _typestore()
    spec = lidar(samples=5, lo=-1.0, hi=1.0, vertical=RayAxis(3, -0.2, 0.2), noise_stddev=0.01,
                 accel_noise_stddev=0.2)
    ranges = np.array([[1, 2, np.inf, 3, 4], [1.5, 2, 3, 4, np.inf], [1, 1, 1, 1, 1]], np.float32)
    contacts = [Contact("wall", (1, 2, 3), (0, 1, 0), 0.001, 5.0), Contact("wall", (1, 2, 3.1), (0, 1, 0), 0.0, 2.0),
                Contact("robot 'b'", (1, 2, 3), (1, 0, 0), 0.002, 1.0)]
    messages = {
        "sensor_msgs/msg/LaserScan": sensor_cdr.laser_scan((3, 500), "m/l", spec, sensor_cdr.scan_row(ranges)),
        "sensor_msgs/msg/PointCloud2": sensor_cdr.point_cloud2((3, 500), "m/l", ranges, Beams.of(spec)),
        "sensor_msgs/msg/Imu": sensor_cdr.imu((3, 500), "m/i", spec, (0, 0, 0.1, 0.995), (0.1, 0.2, 0.3),
                                              (0, 0, 9.81)),
        "gazebo_msgs/msg/ContactsState": sensor_cdr.contacts_state((3, 500), "world", "m::l::c", contacts),
    }
    for msgtype, data in messages.items():
        message = store.deserialize_cdr(data, msgtype)
        assert store.serialize_cdr(message, msgtype) == data, msgtype
    empty = sensor_cdr.contacts_state((1, 0), "world", "m::l::c", [])
    assert store.deserialize_cdr(empty, "gazebo_msgs/msg/ContactsState").states == []
    scan = store.deserialize_cdr(messages["sensor_msgs/msg/LaserScan"], "sensor_msgs/msg/LaserScan")
    assert list(scan.ranges) == [1.5, 2.0, 3.0, 4.0, math.inf]  # the middle vertical row, as gazebo_ros
    assert scan.angle_increment == np.float32(0.5) and list(scan.intensities) == [0.0] * 5
    cloud = store.deserialize_cdr(messages["sensor_msgs/msg/PointCloud2"], "sensor_msgs/msg/PointCloud2")
    assert (cloud.height, cloud.width, cloud.point_step, cloud.is_dense) == (1, 13, 16, True)


def test_range_packer_matches_rosbags_serializer_byte_for_byte():
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)  # Range's variance is Jazzy's
    spec = SensorSpec(name="ir", kind="range", link="l", every=1, range_min=0.02, range_max=4.0, noise_stddev=0.01,
                      radiation="ultrasound", field_of_view=0.3, reading_noise_stddev=0.02)
    data = sensor_cdr.range_message((3, 500), "m/ir", spec, 1.25)
    msg = store.deserialize_cdr(data, "sensor_msgs/msg/Range")
    assert store.serialize_cdr(msg, "sensor_msgs/msg/Range") == data
    assert (msg.header.frame_id, msg.radiation_type, msg.range, msg.min_range, msg.max_range) == \
        ("m/ir", 0, 1.25, np.float32(0.02), 4.0)
    assert (msg.field_of_view, msg.variance) == (np.float32(0.3), np.float32(0.01 ** 2 + 0.02 ** 2))


def test_a_scan_keeps_the_sign_of_a_zero_angle_after_a_sensor_equal_but_for_it():
    """-0.0 == 0.0, so two specs that differ only there are equal: the scan's cached bytes must not
    be shared between them (hypothesis found it: the second scan carried the first one's angle)."""
    ranges = np.array([1.0, 2.0], np.float32)
    minus, plus = (sensor_cdr.laser_scan((0, 0), "l", lidar(samples=2, lo=lo, hi=1.0), ranges) for lo in (-0.0, 0.0))
    assert minus != plus
    assert struct.unpack_from("<f", plus, 20) == (0.0,) and str(struct.unpack_from("<f", minus, 20)[0]) == "-0.0"


def _messages(bag: Path):
    """(topic, message) of a bag, decoded by the independent mcap + mcap-ros2-support readers."""
    import mcap.reader as mcap_reader
    import mcap_ros2.decoder as mcap_ros2

    with bag.open("rb") as f:
        reader = mcap_reader.make_reader(f, decoder_factories=[mcap_ros2.DecoderFactory()])
        for _, channel, _, message in reader.iter_decoded_messages():
            yield channel.topic, message


def test_bag_sensor_messages_decode_and_agree_with_the_run_folder(sensor_run):
    plan, result = sensor_run
    out = result.out_dir
    scan = np.load(out / "sensors/mobot/scan.npy")
    velodyne = np.load(out / "sensors/mobot/velodyne.npy", mmap_mode="r")
    imu = np.genfromtxt(out / "sensors/mobot/imu.csv", delimiter=",", names=True)
    scans, clouds, imus, bumps, statics = [], [], [], [], []
    for topic, msg in _messages(out / "bag" / "bag.mcap"):
        if topic == "/mobot/scan":
            scans.append(msg)
        elif topic == "/mobot/points":
            clouds.append(msg)
        elif topic == "/mobot/imu":
            imus.append(msg)
        elif topic == "/mobot/bumper":
            bumps.append(msg)
        elif topic == "/tf_static":
            statics.extend((t.header.frame_id, t.child_frame_id, t.transform.translation.z) for t in msg.transforms)
    assert len(scans) == len(scan) == 21 and len(clouds) == len(velodyne) == 21
    assert len(imus) == len(imu) == 121 and len(bumps) == 21
    step = 2 * math.pi / 359
    for msg, row in zip(scans, scan):
        assert msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9 == pytest.approx(row["t"], abs=1e-9)
        assert np.array_equal(np.array(msg.ranges, dtype=np.float32), row["ranges"])
        assert (msg.angle_min, msg.angle_max) == (np.float32(-math.pi), np.float32(math.pi))
        assert msg.angle_increment == np.float32(step)
        assert (msg.time_increment, msg.scan_time, msg.range_min, msg.range_max) == (0.0, 0.0, np.float32(0.1), 3.0)
        assert msg.header.frame_id == "mobot/base_link_scan" and list(msg.intensities) == [0.0] * 360
    assert np.isinf(scan["ranges"]).any() and np.isfinite(scan["ranges"]).any()
    beams = Beams.of(plan.robots[0].sensors[1])
    for msg, row in zip(clouds, velodyne):
        finite = np.isfinite(row["ranges"].reshape(-1))
        points = np.frombuffer(bytes(msg.data), dtype="<f4").reshape(-1, 4)
        assert msg.width == finite.sum() == len(points)
        expected = beams.directions[finite] * row["ranges"].reshape(-1)[finite, None]
        assert np.max(np.abs(points[:, :3] - expected)) < 1e-5
    assert [round(m.linear_acceleration.z, 6) for m in imus] == [round(v, 6) for v in imu["az"]]
    assert ("mobot/base_link", "mobot/base_link_scan", pytest.approx(0.3)) in statics
    assert ("mobot/base_link", "mobot/base_link_velodyne", pytest.approx(0.4)) in statics
    touching = [b for b in bumps if b.states]
    assert touching and all(s.collision2_name.startswith("world model 'walls'") for b in touching for s in b.states)
    assert bumps[0].header.frame_id == "world" and not bumps[0].states


def test_summary_lists_each_sensor_with_its_readings(sensor_run):
    _, result = sensor_run
    summary = json.loads((result.out_dir / "summary.json").read_text())
    sensors = {s["name"]: s for s in summary["robots"]["mobot"]["sensors"]}
    assert list(sensors) == ["scan", "velodyne", "imu", "bumper"]
    assert sensors["scan"] == {"name": "scan", "kind": "lidar", "topic": "/mobot/scan",
                               "frame_id": "mobot/base_link_scan", "rate_hz": 10.0, "readings": 21,
                               "file": "sensors/mobot/scan.npy"}
    assert (sensors["velodyne"]["topic"], sensors["imu"]["rate_hz"], sensors["imu"]["readings"]) == \
        ("/mobot/points", 60.0, 121)
    assert sensors["bumper"]["file"] == "sensors/mobot/bumper.csv"
    described = json.loads((result.out_dir / "sensors/mobot/velodyne.json").read_text())
    assert len(described["angles"]) == 300 and len(described["vertical_angles"]) == 16
    assert described["angle_increment"] == pytest.approx(2 * math.pi / 299)


def test_same_seed_gives_byte_identical_sensor_records(sensor_run, tmp_path):
    plan, first = sensor_run
    again = execute(plan, (first.out_dir / "scenario.yaml").read_text(), tmp_path / "again")
    for name in ("scan.npy", "velodyne.npy", "imu.csv", "bumper.csv", "scan.json"):
        assert (first.out_dir / "sensors/mobot" / name).read_bytes() == \
            (again.out_dir / "sensors/mobot" / name).read_bytes(), name
    assert (first.out_dir / "bag/bag.mcap").read_bytes() == (again.out_dir / "bag/bag.mcap").read_bytes()


def test_a_run_without_sensors_writes_no_sensor_files(tmp_path):
    plan, resolved = planned(one_robot(tmp_path), "mobot")
    result = execute(plan, resolved, tmp_path / "out")
    assert not (result.out_dir / "sensors").exists()
    assert json.loads((result.out_dir / "summary.json").read_text())["robots"]["mobot"]["sensors"] == []


KILLED_RUN = """
import sys
sys.path.insert(0, {repo!r})
from pathlib import Path
from mobot_cli.run import execute
from tests.sim.sensor_world import lidar, one_robot, planned
folder = Path({folder!r})
plan, resolved = planned(one_robot(folder, duration=600.0), "mobot", lidar(every=2), formats=("csv", "mcap"))
execute(plan, resolved, folder / "out")
"""


def test_a_killed_run_keeps_every_complete_chunk_of_its_scans(tmp_path):
    """SIGKILL mid-run: the .npy loads, its rows are whole chunks and their times are in order."""
    script = tmp_path / "run.py"
    script.write_text(KILLED_RUN.format(repo=str(REPO), folder=str(tmp_path)))
    process = subprocess.Popen([sys.executable, str(script)], cwd=REPO, env={**os.environ, "PYTHONPATH": str(REPO)})
    npy = tmp_path / "out/sensors/mobot/scan.npy"
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and (not npy.exists() or read_header_rows(npy) < 3 * FLUSH_EVERY):
            time.sleep(0.05)
        assert process.poll() is None, "the run ended before it could be killed"
    finally:
        process.send_signal(signal.SIGKILL)
        process.wait()
    rows = read_header_rows(npy)
    scans = np.load(npy)
    assert rows >= 3 * FLUSH_EVERY and len(scans) == rows and rows % FLUSH_EVERY == 0
    assert np.allclose(np.diff(scans["t"]), 2 / 240) and scans["t"][0] == 0.0
    assert np.isfinite(scans["ranges"]).sum(axis=1).min() > 100  # whole scans, not zeros
    assert not (tmp_path / "out/summary.json").exists()
    checked = invoke(["check", tmp_path / "out"])
    assert checked.exit_code == 2 and "incomplete" in checked.stdout
    last = scans["t"][-1]
    assert f"  sensors/mobot/scan.npy: {rows} whole rows, up to t = {last:g} s\n" in checked.stdout


def test_sensors_do_not_change_the_physics(sensor_run, tmp_path):
    """The same drive without its sensors writes the same odometry, byte for byte."""
    plan, with_sensors = sensor_run
    bare = replace(plan, robots=(replace(plan.robots[0], sensors=()),))
    without = execute(bare, (with_sensors.out_dir / "scenario.yaml").read_text(), tmp_path / "bare")
    assert (without.out_dir / "odom/mobot.csv").read_bytes() == (with_sensors.out_dir / "odom/mobot.csv").read_bytes()
