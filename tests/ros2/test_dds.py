"""mobot's ROS 2 node on a real DDS domain, seen and driven by another DDS participant in a
process of its own (tests/ros2/dds_peer.py), all on loopback: no ROS install, no multicast."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mobot_cli.cli import invoke
from tests.live.live_server import LiveProcess

pytest.importorskip("cyclonedds")

REPO = Path(__file__).resolve().parents[2]
PEER = Path(__file__).with_name("dds_peer.py")
WORLD = """version: 1
name: ros2_world
world: empty
duration: 1.0
log: {{rate_hz: 48}}
robots:
  - {{name: r1, description: mobot, pose: {{x: 0.0, y: 0.0}}}}
{ros2}
"""


@pytest.fixture(autouse=True)
def ros_env(monkeypatch):
    """The peer imports mobot_cli.ros2.idl from this checkout (DDS stays on loopback: conftest)."""
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")])))


def peer(*args: str, timeout: float = 60) -> object:
    """Run tests/ros2/dds_peer.py VERB ARGS and return its JSON answer."""
    run = subprocess.run([sys.executable, str(PEER), *args], capture_output=True, text=True, timeout=timeout)
    assert run.returncode == 0, run.stderr
    return json.loads(run.stdout)


def serve(tmp_path, cache, ros2: str = "", *flags: str) -> LiveProcess:
    scenario = tmp_path / "world.yaml"
    scenario.write_text(WORLD.format(ros2=ros2))
    return LiveProcess(str(scenario), "--ros2", *flags, cache_dir=cache)


@pytest.fixture
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("cache")


def test_topics_types_qos_and_the_node_as_another_participant_sees_them(tmp_path, cache):
    live = serve(tmp_path, cache)
    try:
        seen = peer("graph", "3")
    finally:
        live.signal()
        live.kill()
    mine = {p["participant"] for p in seen["publications"] if p["topic"] == "rt/r1/odom"}
    assert len(mine) == 1
    (participant,) = mine
    pubs = {p["topic"]: p for p in seen["publications"] if p["participant"] == participant}
    subs = {p["type"]: p for p in seen["subscriptions"] if p["participant"] == participant}
    assert {t: (p["type"], p["durability"], p["reliability"], p["depth"]) for t, p in pubs.items()} == {
        "ros_discovery_info": ("rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_", "transient_local", "reliable", 1),
        "rt/clock": ("rosgraph_msgs::msg::dds_::Clock_", "volatile", "reliable", 10),
        "rt/tf": ("tf2_msgs::msg::dds_::TFMessage_", "volatile", "reliable", 10),
        "rt/tf_static": ("tf2_msgs::msg::dds_::TFMessage_", "transient_local", "reliable", 1),
        "rt/r1/odom": ("nav_msgs::msg::dds_::Odometry_", "volatile", "reliable", 10),
        "rt/r1/odom/ground_truth": ("nav_msgs::msg::dds_::Odometry_", "volatile", "reliable", 10),
        "rt/r1/joint_states": ("sensor_msgs::msg::dds_::JointState_", "volatile", "reliable", 10),
        "rt/r1/robot_description": ("std_msgs::msg::dds_::String_", "transient_local", "reliable", 1),
    }
    assert {(s["topic"], s["type"], s["reliability"]) for s in seen["subscriptions"]
            if s["participant"] == participant} == {  # Twist (Jazzy's nav2) and TwistStamped (Kilted's)
        ("rt/r1/cmd_vel", "geometry_msgs::msg::dds_::Twist_", "reliable"),
        ("rt/r1/cmd_vel", "geometry_msgs::msg::dds_::TwistStamped_", "reliable")}
    assert pubs["rt/r1/odom"]["userdata"] == ("typehash=RIHS01_3cc97dc7fb7502f8714462c526d369e35b603cfc34d946e3f2"
                                              "eda2766dfec6e0;")
    assert subs["geometry_msgs::msg::dds_::Twist_"]["userdata"].startswith("typehash=RIHS01_9c45bf16fe0983d8")
    assert subs["geometry_msgs::msg::dds_::TwistStamped_"]["userdata"].startswith("typehash=RIHS01_5f0fcd4f81d5d06a")
    assert {p["guid"]: p["userdata"] for p in seen["participants"]}[participant] == "enclave=/;"


def test_discovery_info_names_the_node_and_every_endpoint(tmp_path, cache):
    live = serve(tmp_path, cache, "ros2: {node: sim, namespace: /mobot_world, world_frame: false}")
    try:
        seen = peer("graph", "3")
        infos = peer("take", "ros_discovery_info", "rmw_dds_common/msg/ParticipantEntitiesInfo", "3", "latched")
        statics = peer("take", "rt/tf_static", "tf2_msgs/msg/TFMessage", "2", "latched")
    finally:
        live.signal()
        live.kill()
    (participant,) = {p["participant"] for p in seen["publications"] if p["topic"] == "rt/r1/odom"}
    info = [i for i in infos if bytes(i["gid"]["data"]).hex() == participant][-1]
    (node,) = info["node_entities_info_seq"]
    assert (node["node_namespace"], node["node_name"]) == ("/mobot_world", "sim")
    writers = {p["guid"] for p in seen["publications"] if p["participant"] == participant
               and p["topic"] != "ros_discovery_info"}
    readers = {s["guid"] for s in seen["subscriptions"] if s["participant"] == participant}
    assert {bytes(g["data"]).hex() for g in node["writer_gid_seq"]} == writers
    assert {bytes(g["data"]).hex() for g in node["reader_gid_seq"]} == readers
    assert len(writers) == 7 and len(readers) == 2  # cmd_vel as Twist and as TwistStamped
    # world_frame: false leaves r1/odom's parent to a localizer (slam_toolbox, AMCL: map -> odom)
    frames = {(t["header"]["frame_id"], t["child_frame_id"]) for t in statics[-1]["transforms"]}
    assert frames and all(parent != "world" for parent, _ in frames)


def test_messages_arrive_and_a_late_joiner_gets_the_description(tmp_path, cache):
    live = serve(tmp_path, cache)
    try:
        odom = peer("take", "rt/r1/odom", "nav_msgs/msg/Odometry", "2")
        clock = peer("take", "rt/clock", "rosgraph_msgs/msg/Clock", "1")
        description = peer("take", "rt/r1/robot_description", "std_msgs/msg/String", "2", "latched")
        statics = peer("take", "rt/tf_static", "tf2_msgs/msg/TFMessage", "2", "latched")
    finally:
        live.signal()
        live.kill()
    assert len(odom) >= 48  # 2 s at 48 Hz, real time
    stamps = [o["header"]["stamp"]["sec"] + o["header"]["stamp"]["nanosec"] * 1e-9 for o in odom]
    assert all(abs(b - a - 1 / 48) < 1e-6 for a, b in zip(stamps, stamps[1:]))  # no gaps, sim time
    assert (odom[0]["header"]["frame_id"], odom[0]["child_frame_id"]) == ("r1/odom", "r1/base_footprint")
    assert len(clock) >= 24
    assert len(description) == 1 and '<robot name="mobot">' in description[0]["data"]
    frames = {(t["header"]["frame_id"], t["child_frame_id"]) for t in statics[-1]["transforms"]}
    assert ("world", "r1/odom") in frames


def test_cmd_vel_from_another_process_drives_the_robot(tmp_path, cache):
    live = serve(tmp_path, cache)
    try:
        with live.client() as client:
            start = client.odom("r1")["truth"]
        sent = peer("drive", "rt/r1/cmd_vel", "0.3", "0.0", "2.0")
        with live.client() as client:
            moving = client.odom("r1")
        time.sleep(0.5)
        with live.client() as client:
            held = client.odom("r1")
    finally:
        live.signal()
        live.kill()
    assert sent["matched"] == 1
    assert moving["cmd"] == {"linear": 0.3, "angular": 0.0}
    assert held["cmd"] == {"linear": 0.3, "angular": 0.0}  # no timeout: it holds, as `mobot cmd` does
    assert math.hypot(moving["truth"]["x"] - start["x"], moving["truth"]["y"] - start["y"]) > 0.3


def test_twist_stamped_on_cmd_vel_drives_the_robot_as_a_twist_does(tmp_path, cache):
    """nav2 from Kilted on sends geometry_msgs/TwistStamped; no setting: the node reads both types."""
    live = serve(tmp_path, cache)
    try:
        sent = peer("drive", "rt/r1/cmd_vel", "0.25", "0.4", "1.5", "stamped")
        with live.client() as client:
            moving = client.odom("r1")
    finally:
        live.signal()
        live.kill()
    assert sent["matched"] == 1
    assert moving["cmd"] == {"linear": 0.25, "angular": 0.4}
    assert moving["truth"]["vx"] > 0.1 and moving["truth"]["wz"] > 0.1


def test_ground_truth_odometry_is_where_the_robot_really_is(tmp_path, cache):
    """<ns>/odom/ground_truth: the base link in the world frame, from the simulator, not the wheels."""
    live = serve(tmp_path, cache)
    try:
        with live.client() as client:
            client.set_state("r1", {"x": 1.5, "y": -2.0, "yaw": 0.5})
        truth = peer("take", "rt/r1/odom/ground_truth", "nav_msgs/msg/Odometry", "1")
        with live.client() as client:
            state = client.get_state("r1")["pose"]
            odom = client.odom("r1")["odom"]
    finally:
        live.signal()
        live.kill()
    last = truth[-1]
    assert (last["header"]["frame_id"], last["child_frame_id"]) == ("world", "r1/base_footprint")
    position, q = last["pose"]["pose"]["position"], last["pose"]["pose"]["orientation"]
    assert math.dist((position["x"], position["y"]), (state["x"], state["y"])) < 1e-3
    assert math.dist((position["x"], position["y"]), (1.5, -2.0)) < 0.01
    assert 2 * math.atan2(q["z"], q["w"]) == pytest.approx(0.5, abs=0.01)
    assert math.hypot(odom["x"], odom["y"]) < 0.01  # the wheels never saw the teleport: odom stays put


def test_after_a_step_returns_every_message_of_that_step_is_out(tmp_path, cache):
    """serve --ros2 --paused: /clock reaches the step the world stopped at, not one batch behind
    (records held for batching are sent before a step's reply and before the world waits)."""
    import struct

    from mobot_cli.ros2 import dds, idl
    from mobot_cli.ros2.names import discovery_config

    live = serve(tmp_path, cache, "", "--paused")
    participant = dds.Participant(int(os.environ["ROS_DOMAIN_ID"]), discovery_config(os.environ, True))
    clocks: list[tuple[int, int]] = []
    try:
        reader = participant.reader("rt/clock", idl.Clock, dds.DEFAULT, lambda data: clocks.append(
            struct.unpack_from("<iI", data, 4)))
        deadline = time.monotonic() + 60  # discovery; only catches a peer never found
        while not reader.dds.get_matched_publications() and time.monotonic() < deadline:
            time.sleep(0.05)
        seen = []
        with live.client() as client:
            rate = client.ping()["rate_hz"]
            for _ in range(4):
                step = client.step(steps=rate // 48 * 5, states=False)["step"]  # ends on a logged step
                expected = divmod(step * 1_000_000_000 // rate, 1_000_000_000)
                deadline = time.monotonic() + 30  # delivery on a busy machine; never reached when it works
                while (not clocks or clocks[-1] != expected) and time.monotonic() < deadline:
                    time.sleep(0.01)
                seen.append((clocks[-1] if clocks else None, expected))
    finally:
        participant.close()
        live.signal()
        live.kill()
    assert all(last == expected for last, expected in seen), seen


def test_cmd_vel_timeout_stops_a_robot_whose_commands_stop(tmp_path, cache):
    live = serve(tmp_path, cache, "ros2: {cmd_vel_timeout: 0.25}")
    try:
        peer("drive", "rt/r1/cmd_vel", "0.2", "0.5", "1.0")
        # 0.25 s of simulated time after the last command: however long a busy machine takes to
        # step that far, the robot stops (60 s only catches a robot that never does).
        deadline = time.monotonic() + 60
        with live.client() as client:
            after = client.odom("r1")
            while after["cmd"] != {"linear": 0.0, "angular": 0.0} and time.monotonic() < deadline:
                time.sleep(0.05)
                after = client.odom("r1")
    finally:
        live.signal()
        live.kill()
    assert after["cmd"] == {"linear": 0.0, "angular": 0.0}
    assert abs(after["truth"]["yaw"]) > 0.1  # it did turn while the commands came


def test_run_with_ros2_publishes_and_reports(tmp_path):
    scenario = REPO / "scenarios" / "quickstart.yaml"
    result = invoke(["run", str(scenario), "--ros2", "--duration", "2", "-o", str(tmp_path / "r")])
    assert result.exit_code == 0, result.stderr
    domain = os.environ["ROS_DOMAIN_ID"]
    assert f"mobot: ROS 2: node /mobot in domain {domain} (set use_sim_time:=true)" in result.stderr
    # Nobody listens: only the latched tf_static and robot_description are sent (once each).
    assert "mobot: ROS 2: 2 message(s) sent, 0 cmd_vel taken" in result.stderr


@pytest.mark.parametrize("command", ["run", "serve"])
def test_a_bad_domain_in_the_environment_is_bad_input(command, monkeypatch, tmp_path):
    monkeypatch.setenv("ROS_DOMAIN_ID", "seven")
    args = [command, str(REPO / "scenarios" / "quickstart.yaml"), "--ros2"]
    result = invoke(args + (["-o", str(tmp_path / "r")] if command == "run" else ["--endpoint", "tcp://127.0.0.1:0"]))
    assert result.exit_code == 2
    assert result.stderr == ("mobot: error: environment variable ROS_DOMAIN_ID='seven' is not a ROS 2 domain id. "
                             "Use a whole number from 0 to 232 (0 to 101 is safe everywhere), or unset it for "
                             "domain 0.\n")
    assert not (tmp_path / "r").exists()


def test_ros2_without_the_extra_is_bad_input(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "cyclonedds", None)  # what an install without the extra sees
    monkeypatch.setitem(sys.modules, "mobot_cli.ros2.dds", None)
    result = invoke(["run", str(REPO / "scenarios" / "quickstart.yaml"), "--ros2", "-o", str(tmp_path / "r")])
    assert result.exit_code == 2
    assert result.stderr.startswith("mobot: error: ROS 2 needs the cyclonedds package, which is not installed")
    assert result.stderr.endswith("Install the extra: pip install 'mobot-cli[ros2]'.\n")
    assert not (tmp_path / "r").exists()


def test_a_robot_namespace_ros_rejects_is_bad_input(tmp_path):
    scenario = tmp_path / "s.yaml"
    scenario.write_text(f"version: 1\nduration: 1\nrobots:\n  - {{name: r1, namespace: /{'a' * 240}}}\nros2: {{}}\n")
    result = invoke(["run", str(scenario), "-o", str(tmp_path / "r")])
    assert result.exit_code == 2
    assert result.stderr == ("mobot: error: key 'robots.r1.namespace': namespace '/aaaaaaaaaaaaaaaaaaaaaaa...' is "
                             "too long for ROS 2. Keep it under 229 characters: ROS 2 topic names have at most 247.\n")
    assert not (tmp_path / "r").exists()


def test_robots_spawned_and_deleted_live_join_and_leave_the_graph(tmp_path, cache):
    live = serve(tmp_path, cache)
    try:
        with live.client() as client:
            client.spawn("r2", description="mobot", pose={"x": 2.0, "y": 0.0})
        spawned = peer("graph", "2")
        with live.client() as client:
            client.delete("r1")
        deleted = peer("graph", "2")
        statics = peer("take", "rt/tf_static", "tf2_msgs/msg/TFMessage", "1", "latched")
    finally:
        live.signal()
        live.kill()

    def topics(seen):
        return {p["topic"] for p in seen["publications"] + seen["subscriptions"] if p["topic"].startswith("rt/r")}

    kinds = ("odom", "joint_states", "robot_description", "cmd_vel", "odom/ground_truth")
    assert topics(spawned) == {f"rt/{r}/{t}" for r in ("r1", "r2") for t in kinds}
    assert topics(deleted) == {f"rt/r2/{t}" for t in kinds}
    frames = {t["child_frame_id"] for t in statics[-1]["transforms"]}
    assert "r2/odom" in frames and "r1/odom" not in frames


def test_a_bridge_on_its_own_thread_publishes_the_same(tmp_path):
    from mobot_cli.plan import Ros2Settings
    from mobot_cli.ros2.bridge import Bridge
    from mobot_cli.run import execute
    from mobot_cli.scenario.prepare import prepare

    prepared = prepare(REPO / "scenarios" / "fleet.yaml", ["duration=1.0", "log.formats=[csv]"])
    counts = []
    for threaded in (True, False):
        bridge = Bridge(prepared.plan, Ros2Settings(), threaded=threaded)
        execute(prepared.plan, prepared.resolved_yaml, tmp_path / str(threaded), attachments=[bridge])
        assert bridge.stats.error is None and bridge.stats.dropped_samples == 0
        counts.append(bridge.stats.messages)
    # Nobody listens: each robot's description, and one /tf_static with every robot's frames for
    # the five that arrive in the same sample (ros2/publisher.py: not one per arrival).
    assert counts == [5 + 1, 5 + 1]


def test_a_live_robot_ros_cannot_name_is_left_out_and_the_world_goes_on(tmp_path, cache):
    live = serve(tmp_path, cache)
    try:
        with live.client() as client:
            client.spawn("long", description="mobot", namespace="/" + "n" * 240, pose={"x": 2.0, "y": 0.0})
            client.spawn("r3", description="mobot", pose={"x": -2.0, "y": 0.0})
        seen = peer("graph", "2")
        code = live.signal()
        output = live.output()
    finally:
        live.kill()
    assert code == 0
    assert {p["topic"] for p in seen["publications"]} >= {"rt/r1/odom", "rt/r3/odom"}
    assert not any(p["topic"].startswith("rt/nnn") for p in seen["publications"])
    assert "mobot: warning: robot 'long' is not on ROS 2: namespace '/nnnnnnnnnnnnnnnnnnnnnnn...' is too long" in output


def test_a_dds_configuration_cyclone_refuses_is_bad_input_before_any_output(monkeypatch, tmp_path):
    monkeypatch.setenv("CYCLONEDDS_URI", os.environ["CYCLONEDDS_URI"] + ",<CycloneDDS><Domain><General>"
                       "<AllowMulticast>maybe</AllowMulticast></General></Domain></CycloneDDS>")
    result = invoke(["run", str(REPO / "scenarios" / "quickstart.yaml"), "--ros2", "-o", str(tmp_path / "r")])
    assert result.exit_code == 2
    domain = os.environ["ROS_DOMAIN_ID"]
    assert result.stderr == (f"mobot: error: cannot join ROS 2 domain {domain}: [DDS_RETCODE_ERROR] Non specific "
                             "error. Occurred upon initialisation of a cyclonedds.domain.Domain. Check CYCLONEDDS_URI "
                             "and the ROS discovery variables (ROS_AUTOMATIC_DISCOVERY_RANGE, ROS_STATIC_PEERS).\n")
    assert not (tmp_path / "r").exists()


def test_a_lidar_scan_reaches_another_participant_as_the_bag_has_it(tmp_path, cache):
    """<ns>/scan (sensor_msgs/LaserScan) from the bundled robot's lidar, at its 10 Hz, stamped in sim time."""
    scenario = tmp_path / "world.yaml"
    scenario.write_text(WORLD.format(ros2="").replace("description: mobot,",
                                                      "description: mobot, args: {lidar: 'true'},"))
    live = LiveProcess(str(scenario), "--ros2", cache_dir=cache)
    try:
        scans = peer("take", "rt/r1/scan", "sensor_msgs/msg/LaserScan", "2")
    finally:
        live.signal()
        live.kill()
    assert len(scans) >= 10  # 2 s at 10 Hz, real time
    scan = scans[-1]
    assert scan["header"]["frame_id"] == "r1/lidar_link" and len(scan["ranges"]) == 360
    assert scan["range_min"] == pytest.approx(0.12) and scan["range_max"] == pytest.approx(12.0)
    stamps = [s["header"]["stamp"]["sec"] + s["header"]["stamp"]["nanosec"] * 1e-9 for s in scans]
    assert all(abs(b - a - 0.1) < 1e-6 for a, b in zip(stamps, stamps[1:]))  # every 24 steps, no gaps
