"""DIR/bag/: read back with an independent reader (mcap + mcap-ros2-support), not with rosbags."""

from __future__ import annotations

import csv
import io
import math
import os
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import mcap.reader as mcap_reader  # the independent reader: the `test` extra's mcap packages
import mcap_ros2.decoder as mcap_ros2
import pytest
import yaml

from mobot_cli.cli import CommandResult, invoke

DURATION, RATE, LOG_EVERY = 3.0, 240, 5  # log.rate_hz 48: every 5th step
SAMPLES = int(DURATION * RATE) // LOG_EVERY + 1
SCENARIO = f"""version: 1
name: bagtest
duration: {DURATION}
seed: 4
log: {{rate_hz: 48, formats: [csv, mcap]}}
robots:
  - name: alpha
    pose: {{x: 0.5, y: -1.0, yaw: 0.3}}
    commands: [{{at: 0.5, linear: 0.3, angular: 0.4}}]
  - name: beta
    namespace: /team/beta
    pose: {{x: -1.0, y: 1.0, yaw: -1.2}}
    drive: {{odometry: ground_truth}}
    commands: [{{at: 0.5, linear: -0.2, angular: -0.3}}]
"""
TOPICS = {
    "/clock": "rosgraph_msgs/msg/Clock", "/tf": "tf2_msgs/msg/TFMessage", "/tf_static": "tf2_msgs/msg/TFMessage",
    **{f"{ns}/{topic}": kind for ns in ("/alpha", "/team/beta") for topic, kind in (
        ("odom", "nav_msgs/msg/Odometry"), ("cmd_vel", "geometry_msgs/msg/Twist"),
        ("joint_states", "sensor_msgs/msg/JointState"), ("robot_description", "std_msgs/msg/String"))},
}
PREFIX = {"alpha": "alpha/", "beta": "team/beta/"}
NAMESPACE = {"alpha": "/alpha", "beta": "/team/beta"}


def run(scenario: Path, out: Path) -> Path:
    assert invoke(["run", str(scenario), "--out", str(out), "--quiet"]) == CommandResult(0, "", "")
    return out


def messages(bag: Path) -> list[tuple[str, str, int, object, bytes]]:
    """(topic, type, log time, decoded message, raw CDR) of every message, in file order."""
    out = []
    with (bag / "bag.mcap").open("rb") as f:
        reader = mcap_reader.make_reader(f, decoder_factories=[mcap_ros2.DecoderFactory()])
        for schema, channel, message, decoded in reader.iter_decoded_messages(log_time_order=False):
            out.append((channel.topic, schema.name, message.log_time, decoded, message.data))
    return out


def rows(path: Path) -> list[dict[str, float]]:
    with path.open() as f:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]


def yaw_of(q) -> float:
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


@pytest.fixture(scope="module")
def bag_run(tmp_path_factory):
    base = tmp_path_factory.mktemp("bag")
    (base / "s.yaml").write_text(SCENARIO)
    out = run(base / "s.yaml", base / "run")
    return out, messages(out / "bag")


def by_topic(msgs, topic):
    return [m for m in msgs if m[0] == topic]


def test_rosbag2_folder_topics_types_and_counts(bag_run):
    out, msgs = bag_run
    assert sorted(p.name for p in (out / "bag").iterdir()) == ["bag.mcap", "metadata.yaml"]
    assert {(m[0], m[1]) for m in msgs} == set(TOPICS.items())
    counts = {topic: len(by_topic(msgs, topic)) for topic in TOPICS}
    once = {"/tf_static": 1, "/alpha/robot_description": 1, "/team/beta/robot_description": 1}
    assert counts == {topic: once.get(topic, SAMPLES) for topic in TOPICS}
    meta = yaml.safe_load((out / "bag" / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert meta["storage_identifier"] == "mcap" and meta["relative_file_paths"] == ["bag.mcap"]
    assert meta["message_count"] == len(msgs) and meta["duration"]["nanoseconds"] == int(DURATION * 1e9)
    latched = {t["topic_metadata"]["name"] for t in meta["topics_with_message_count"]
               if "durability: 1" in t["topic_metadata"]["offered_qos_profiles"]}  # transient local
    assert latched == {"/tf_static", "/alpha/robot_description", "/team/beta/robot_description"}


def test_clock_and_stamps_are_sim_time(bag_run):
    _, msgs = bag_run
    clocks = by_topic(msgs, "/clock")
    for k, (_, _, log_time, msg, _) in enumerate(clocks):
        step = k * LOG_EVERY
        assert log_time == step * 10**9 // RATE
        assert msg.clock.sec * 10**9 + msg.clock.nanosec == log_time


@pytest.mark.parametrize("robot", ["alpha", "beta"])
def test_odometry_equals_the_csv_rows(bag_run, robot):
    out, msgs = bag_run
    odom = by_topic(msgs, f"{NAMESPACE[robot]}/odom")
    data = rows(out / "odom" / f"{robot}.csv")
    assert len(odom) == len(data) == SAMPLES
    for (_, _, log_time, msg, _), row in zip(odom, data):
        assert msg.header.frame_id == f"{PREFIX[robot]}odom"
        assert msg.child_frame_id == f"{PREFIX[robot]}base_footprint"  # the URDF's root link
        assert msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9 == pytest.approx(row["t"], abs=1e-6)
        assert log_time == msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
        pose, twist = msg.pose.pose, msg.twist.twist
        assert (pose.position.x, pose.position.y, pose.position.z) == pytest.approx(
            (row["odom_x"], row["odom_y"], 0.0), abs=1e-6)
        assert math.remainder(yaw_of(pose.orientation) - row["odom_yaw"], math.tau) == pytest.approx(0, abs=1e-6)
        assert (twist.linear.x, twist.angular.z) == pytest.approx((row["odom_vx"], row["odom_wz"]), abs=1e-6)
    # gazebo_ros_diff_drive's covariance: x, y 1e-5, yaw 1e-3, z / roll / pitch unknown (1e12)
    cov = list(odom[-1][3].pose.covariance)
    assert [cov[i * 7] for i in range(6)] == [1e-5, 1e-5, 1e12, 1e12, 1e12, 1e-3]
    assert list(odom[-1][3].twist.covariance) == cov and sum(cov) == sum(cov[i * 7] for i in range(6))
    # beta drives backwards: a negative speed, as a real robot's odometry reports it.
    speeds = [m[3].twist.twist.linear.x for m in odom]
    assert (min(speeds) < -0.15) if robot == "beta" else (max(speeds) > 0.25)


@pytest.mark.parametrize("robot", ["alpha", "beta"])
def test_cmd_vel_and_joint_states(bag_run, robot):
    out, msgs = bag_run
    data = rows(out / "odom" / f"{robot}.csv")
    cmds = by_topic(msgs, f"{NAMESPACE[robot]}/cmd_vel")
    assert [(m[3].linear.x, m[3].angular.z) for m in cmds] == [(r["cmd_linear"], r["cmd_angular"]) for r in data]
    joints = by_topic(msgs, f"{NAMESPACE[robot]}/joint_states")
    last = joints[-1][3]
    assert list(last.name) == ["left_wheel_joint", "right_wheel_joint"]
    assert len(last.position) == len(last.velocity) == 2 and list(last.effort) == []
    # The wheels turned, and a wheel's speed is the change of its angle (48 Hz, 5 steps apart).
    before = joints[-2][3]
    dt = 5 / RATE
    for i in range(2):
        assert abs(last.position[i]) > 1.0
        assert (last.position[i] - before.position[i]) / dt == pytest.approx(last.velocity[i], abs=0.05)


def test_tf_links_every_urdf_link_to_its_odom_frame_and_the_world(bag_run):
    _, msgs = bag_run
    parent = {}
    for topic in ("/tf_static", "/tf"):
        for msg in (m[3] for m in by_topic(msgs, topic)):
            for t in msg.transforms:
                assert parent.setdefault(t.child_frame_id, t.header.frame_id) == t.header.frame_id
    for robot in ("alpha", "beta"):
        urdf = by_topic(msgs, f"{NAMESPACE[robot]}/robot_description")[0][3].data
        links = [link.get("name") for link in ET.fromstring(urdf).findall("link")]
        assert len(links) >= 5
        for link in links:
            chain, frame = [], PREFIX[robot] + link
            while frame in parent:
                frame = parent[frame]
                chain.append(frame)
            assert f"{PREFIX[robot]}odom" in chain and chain[-1] == "world", (link, chain)
    frames = [f for f in parent if f != "world"]
    assert all(f.startswith(("alpha/", "team/beta/")) for f in frames)  # no frame is shared


def test_world_to_base_through_tf_is_the_truth_with_ground_truth_odometry(bag_run):
    """beta's odometry is ground truth: world -> odom (static) -> base must land on true_x/y/yaw."""
    out, msgs = bag_run
    static = {t.child_frame_id: t for m in by_topic(msgs, "/tf_static") for t in m[3].transforms}
    origin = static["team/beta/odom"].transform
    ox, oy, oyaw = origin.translation.x, origin.translation.y, yaw_of(origin.rotation)
    data = rows(out / "odom" / "beta.csv")
    for msg, row in zip((m[3] for m in by_topic(msgs, "/tf")), data):
        t = next(t for t in msg.transforms if t.child_frame_id == "team/beta/base_footprint")
        assert t.header.frame_id == "team/beta/odom"
        x, y = t.transform.translation.x, t.transform.translation.y
        wx, wy = ox + math.cos(oyaw) * x - math.sin(oyaw) * y, oy + math.sin(oyaw) * x + math.cos(oyaw) * y
        assert (wx, wy) == pytest.approx((row["true_x"], row["true_y"]), abs=2e-6)
        yaw = math.remainder(oyaw + yaw_of(t.transform.rotation) - row["true_yaw"], math.tau)
        assert yaw == pytest.approx(0.0, abs=2e-6)


def test_messages_are_the_bytes_rosbags_serializer_writes(bag_run):
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    _, msgs = bag_run
    seen = set()
    for topic, kind, _, _, raw in msgs:
        if topic in seen:
            continue
        seen.add(topic)
        again = store.serialize_cdr(store.deserialize_cdr(raw, kind), kind)
        assert bytes(again) == bytes(raw), topic
    assert len(seen) == len(TOPICS)


def test_same_inputs_give_a_byte_identical_bag_and_a_rerun_replaces_it(bag_run, tmp_path):
    out, _ = bag_run
    scenario = out.parent / "s.yaml"
    again = run(scenario, tmp_path / "again")
    for name in ("bag.mcap", "metadata.yaml"):
        assert (again / "bag" / name).read_bytes() == (out / "bag" / name).read_bytes(), name
    assert (again / "odom" / "alpha.csv").read_bytes() == (out / "odom" / "alpha.csv").read_bytes()
    run(scenario, again)  # into the same folder: the old bag is replaced, not refused
    assert (again / "bag" / "bag.mcap").read_bytes() == (out / "bag" / "bag.mcap").read_bytes()


def test_robots_that_come_and_go_get_their_topics_from_their_first_sample(tmp_path):
    """scenarios/events.yaml: mobot_1 is deleted at 3 s, 'late' spawns at 3.5 s."""
    scenario = Path(__file__).resolve().parents[2] / "scenarios" / "events.yaml"
    out = tmp_path / "events"
    result = invoke(["run", scenario, "--out", out, "--quiet", "--set", "log.formats=[csv, mcap]"])
    assert result == CommandResult(0, "", "")
    msgs = messages(out / "bag")
    first = {}
    for topic, _, log_time, _, _ in msgs:
        first.setdefault(topic, log_time / 1e9)
    counts = {topic: len(by_topic(msgs, topic)) for topic in first}
    assert first["/late/odom"] == first["/late/robot_description"] == pytest.approx(3.5)
    assert counts["/late/odom"] == len(rows(out / "odom" / "late.csv")) == 121  # 3.5 .. 6.0 s at 48 Hz
    assert counts["/mobot_1/odom"] == len(rows(out / "odom" / "mobot_1.csv")) == 145  # 0 .. 3.0 s, its delete
    # every /tf_static message holds every present robot's frames: one at the start, one at the
    # delete (mobot_1's frames gone), one when 'late' arrives
    statics = [(m[2] / 1e9, sorted({t.child_frame_id for t in m[3].transforms if t.header.frame_id == "world"}))
               for m in by_topic(msgs, "/tf_static")]
    assert statics == [(0.0, ["mobot_0/odom", "mobot_1/odom"]), (3.0, ["mobot_0/odom"]),
                       (3.5, ["late/odom", "mobot_0/odom"])]
    children = [{t.child_frame_id for t in m[3].transforms} for m in by_topic(msgs, "/tf")]
    assert "mobot_1/base_footprint" in children[0] and "late/base_footprint" not in children[0]
    assert "mobot_1/base_footprint" not in children[-1] and "late/base_footprint" in children[-1]


def test_a_robot_is_recorded_under_the_plan_it_was_spawned_with(tmp_path):
    """A live world's spawns reach the bag with their own plan: their URDF's frames, their namespace."""
    import dataclasses

    from mobot_cli.record.bag import BagSink
    from mobot_cli.scenario.prepare import prepare
    from mobot_cli.timeline.loop import simulate
    from mobot_cli.timeline.records import Sample

    (tmp_path / "s.yaml").write_text(SCENARIO.replace(f"duration: {DURATION}", "duration: 0.5"))
    plan = prepare(tmp_path / "s.yaml").plan
    sink = BagSink(dataclasses.replace(plan, robots=()), tmp_path)
    alpha = plan.robots[0]
    sink.spawned(0, "ghost", dataclasses.replace(alpha, name="ghost", namespace="/ghost", frame_prefix="ghost/"))
    for record in simulate(plan):
        if isinstance(record, Sample):
            sink.write(Sample(record.step, {"ghost": record.states["alpha"]}))
    sink.close()
    msgs = messages(tmp_path / "bag")
    assert by_topic(msgs, "/ghost/odom")[0][3].child_frame_id == "ghost/base_footprint"
    children = {t.child_frame_id for m in by_topic(msgs, "/tf") for t in m[3].transforms}
    assert children == {"ghost/base_footprint", "ghost/left_wheel", "ghost/right_wheel"}
    statics = {t.child_frame_id for m in by_topic(msgs, "/tf_static") for t in m[3].transforms}
    assert statics >= {"ghost/odom", "ghost/base_link"}


def test_robot_description_has_file_uris_for_meshes():
    from mobot_cli.record.bag import file_uris

    urdf = '<robot><link name="a"><visual><geometry><mesh filename="/x/y.stl" scale="1 1 1"/></geometry></visual>' \
           '<collision><geometry><mesh filename="package://p/z.dae"/></geometry></collision></link></robot>'
    assert 'filename="file:///x/y.stl"' in file_uris(urdf) and 'filename="package://p/z.dae"' in file_uris(urdf)


def test_killed_run_keeps_whole_csv_rows_and_readable_chunks(tmp_path):
    """SIGKILL a real `mobot run` mid-way: rows up to the last flush, chunks up to the last one."""
    from mcap.exceptions import EndOfFile

    scenario = tmp_path / "long.yaml"
    scenario.write_text(SCENARIO.replace(f"duration: {DURATION}", "duration: 600"))
    out = tmp_path / "killed"
    proc = subprocess.Popen([sys.executable, "-m", "mobot_cli", "run", str(scenario), "--out", str(out), "-q"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    csv_path = out / "odom" / "alpha.csv"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and proc.poll() is None:
        if csv_path.is_file() and csv_path.stat().st_size > 160 * 130:  # > 2 flushes of 50 rows
            break
        time.sleep(0.05)
    assert proc.poll() is None, proc.stderr.read().decode()
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    proc.stderr.close()
    assert not (out / "summary.json").exists() and not (out / "bag" / "metadata.yaml").exists()
    lines = csv_path.read_text().splitlines()
    assert (len(lines) - 1) % 50 == 0 and len(lines) > 100  # header + whole flushes
    assert all(len(line.split(",")) == 16 for line in lines)
    # The MCAP file has no summary; a reader that scans it reads every chunk that was closed.
    odom, held, last_ns = [], {}, 0
    with (out / "bag" / "bag.mcap").open("rb") as f:
        reader = mcap_reader.NonSeekingReader(f, decoder_factories=[mcap_ros2.DecoderFactory()])
        with pytest.raises(EndOfFile):
            for _, channel, message, decoded in reader.iter_decoded_messages(log_time_order=False):
                held[channel.topic] = held.get(channel.topic, 0) + 1
                last_ns = max(last_ns, message.log_time)
                if channel.topic == "/alpha/odom":
                    odom.append(decoded)
    assert len(odom) >= 50 and len(odom) % 50 == 0
    assert odom[-1].header.stamp.sec >= 1
    # mobot check reports the folder as incomplete, with how far each file goes.
    check = subprocess.run([sys.executable, "-m", "mobot_cli", "check", str(out)], capture_output=True, text=True)
    assert check.returncode == 2, check.stderr
    assert check.stdout.startswith(f"incomplete: run in {out}: no summary.json: the run was killed")
    assert f"odom/alpha.csv: {len(lines) - 1} whole rows" in check.stdout
    assert f"bag/bag.mcap: not closed (no metadata.yaml); {len(odom) // 50} complete chunks" in check.stdout
    assert check.stdout.endswith(f"\n  bag can be repaired: mobot check {out} --repair\n")
    assert_repaired(out, held, last_ns, len(odom) // 50)


def assert_repaired(out: Path, held: dict[str, int], last_ns: int, chunks: int) -> None:
    """`mobot check --repair` keeps every message of the complete chunks (``held``, per topic),
    and rosbags and mcap's indexed reader read the bag as a closed one."""
    from rosbags.highlevel import AnyReader

    total = sum(held.values())
    repair = subprocess.run([sys.executable, "-m", "mobot_cli", "check", str(out), "--repair"],
                            capture_output=True, text=True)
    assert repair.returncode == 2, repair.stderr  # the run stays incomplete: it has no summary.json
    assert repair.stdout.startswith(f"repaired bag/bag.mcap: {total} messages from {chunks} complete chunks, "
                                    f"up to t = {last_ns / 1e9:g} s; metadata.yaml written\n")
    assert "bag can be repaired" not in repair.stdout and "bag/bag.mcap: closed;" in repair.stdout
    assert sorted(p.name for p in (out / "bag").iterdir()) == ["bag.mcap", "metadata.yaml"]
    assert [p.name for p in out.iterdir() if p.name.startswith(".")] == []  # no work folder left
    with AnyReader([out / "bag"]) as reader:  # metadata.yaml + the MCAP summary
        assert reader.message_count == total
        assert {c.topic: c.msgcount for c in reader.connections} == held
        stamps = [timestamp for _, timestamp, _ in reader.messages()]
        assert len(stamps) == total and max(stamps) == last_ns
        odom = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages()
                if c.topic == "/alpha/odom"]
    assert len(odom) == held["/alpha/odom"] and odom[-1].header.stamp.sec == last_ns // 1_000_000_000
    with (out / "bag" / "bag.mcap").open("rb") as f:  # the seeking reader: summary, index, footer
        reader = mcap_reader.make_reader(f, decoder_factories=[mcap_ros2.DecoderFactory()])
        assert reader.get_summary().statistics.message_count == total
        decoded = list(reader.iter_decoded_messages())
    assert len(decoded) == total and decoded[-1][2].log_time == last_ns
    topics = {}
    for _, channel, _, _ in decoded:
        topics[channel.topic] = topics.get(channel.topic, 0) + 1
    assert topics == held


@pytest.mark.parametrize("cut", [0.5, 0.02])
def test_repair_keeps_the_complete_chunks_of_a_bag_cut_anywhere(bag_run, tmp_path, cut):
    """A closed bag cut short (as a full disk or a kill leaves it): the repair keeps exactly the
    messages a front-to-back reader finds in its whole chunks; with none, it changes nothing."""
    import shutil

    from mcap.exceptions import EndOfFile

    from mobot_cli.record.folder import mcap_chunks

    out = tmp_path / "run"
    shutil.copytree(bag_run[0], out)
    (out / "summary.json").unlink()
    (out / "bag" / "metadata.yaml").unlink()
    mcap_path = out / "bag" / "bag.mcap"
    data = mcap_path.read_bytes()
    mcap_path.write_bytes(data[:int(len(data) * cut)])
    held, last_ns = {}, 0
    with mcap_path.open("rb") as f:
        reader = mcap_reader.NonSeekingReader(f)
        with pytest.raises(EndOfFile):
            for _, channel, message in reader.iter_messages(log_time_order=False):
                held[channel.topic] = held.get(channel.topic, 0) + 1
                last_ns = max(last_ns, message.log_time)
    chunks = mcap_chunks(mcap_path)["chunks"]
    assert bool(held) == (cut == 0.5)  # 2 % is inside the first chunk (it holds the descriptions)
    if held:
        assert_repaired(out, held, last_ns, chunks)
        return
    assert chunks == 0
    repair = subprocess.run([sys.executable, "-m", "mobot_cli", "check", str(out), "--repair"],
                            capture_output=True, text=True)
    assert repair.returncode == 2
    assert repair.stdout.startswith("nothing repaired: bag/bag.mcap holds no complete chunk: nothing to keep\n")
    assert mcap_path.read_bytes() == data[:int(len(data) * cut)]


def test_covariance_follows_the_urdf_diff_drive_plugin():
    from mobot_cli.ros.tf import RobotFrames

    urdf = ('<robot name="r"><link name="base"/><gazebo><plugin name="d" filename="libgazebo_ros_diff_drive.so">'
            '<covariance_x>0.5</covariance_x><covariance_yaw>0.25</covariance_yaw></plugin></gazebo></robot>')
    cov = RobotFrames(urdf, "r/").covariance
    assert [cov[i * 7] for i in range(6)] == [0.5, 1e-5, 1e12, 1e12, 1e12, 0.25]


@pytest.mark.parametrize("robot", ["turtlebot3/turtlebot3_description/urdf/turtlebot3_waffle_pi.urdf.xacro",
                                   "husky/husky_description/urdf/husky.urdf.xacro"])
def test_tf_transforms_match_yourdfpy_forward_kinematics(corpus, monkeypatch, robot):
    """robot_state_publisher's job, checked against an independent FK (yourdfpy) on real URDFs."""
    import numpy as np
    import yourdfpy

    from mobot_cli.assets.description.describe import load_robot
    from mobot_cli.ros.tf import RobotFrames

    monkeypatch.setenv("MOBOT_RESOURCE_PATH", ":".join(str(corpus / p) for p in ("turtlebot3", "husky")))
    desc = load_robot(str(corpus / robot), {"gazebo_controllers": "/dev/null"}, Path.cwd())
    frames = RobotFrames(desc.urdf, "r1/", desc.root_link)
    ref = yourdfpy.URDF.load(io.StringIO(desc.urdf), load_meshes=False, build_collision_scene_graph=False,
                             load_collision_meshes=False)
    rng = np.random.default_rng(3)
    config = {name: float(rng.uniform(-3, 3)) for name in ref.actuated_joint_names}
    ref.update_cfg(config)
    assert frames.moving and len(frames.moving) == len(ref.actuated_joint_names)
    transforms = [(j.parent, j.child, j.transform(config)) for j in frames.moving]
    transforms += [(t.parent, t.child, (*t.xyz, *t.quat)) for t in frames.static]
    assert len(transforms) == len(ref.robot.joints)
    for parent, child, (x, y, z, qx, qy, qz, qw) in transforms:
        expected = ref.get_transform(child.removeprefix("r1/"), parent.removeprefix("r1/"))
        rot = np.array([[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
                        [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
                        [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]])
        assert np.allclose(rot, expected[:3, :3], atol=1e-9), child
        assert np.allclose((x, y, z), expected[:3, 3], atol=1e-9), child


def test_the_latest_tf_static_holds_every_robots_static_frames(tmp_path):
    """Five robots, two of them spawned later: a player that joins late reads only the latest
    /tf_static message (transient local, depth 1), and it holds all five robots' frames."""
    robots = "".join(f"  - {{name: r{i}, description: mobot, pose: {{x: {i}.0, y: 0.0}}}}\n" for i in range(3))
    scenario = tmp_path / "five.yaml"
    scenario.write_text(f"""version: 1
name: five
duration: 1.0
log: {{rate_hz: 20, formats: [csv, mcap]}}
robots:
{robots}events:
  - {{at: 0.5, spawn: {{name: r3, description: mobot, pose: {{x: 3.0, y: 2.0}}}}}}
  - {{at: 0.7, spawn: {{name: r4, description: mobot, pose: {{x: 4.0, y: 2.0}}}}}}
""")
    out = tmp_path / "run"
    assert invoke(["run", scenario, "--out", out, "--quiet"]) == CommandResult(0, "", "")
    statics = by_topic(messages(out / "bag"), "/tf_static")
    assert [round(m[2] / 1e9, 3) for m in statics] == [0.0, 0.5, 0.7]
    worlds = [{t.child_frame_id: t.transform.translation.x for t in m[3].transforms if t.header.frame_id == "world"}
              for m in statics]
    assert worlds[-1] == pytest.approx({f"r{i}/odom": float(i) for i in range(5)}, abs=1e-3)
    assert list(worlds[0]) == ["r0/odom", "r1/odom", "r2/odom"]
    last = {(t.header.frame_id, t.child_frame_id) for t in statics[-1][3].transforms}
    for i in range(5):  # each robot's fixed joints, not only its odom frame
        assert (f"r{i}/base_footprint", f"r{i}/base_link") in last, i
    assert len(statics[-1][3].transforms) == 5 * len(statics[0][3].transforms) // 3
