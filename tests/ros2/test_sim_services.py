"""simulation_interfaces on ROS 2: a real rclpy client (Fast DDS with the community wheels) calls
every service and the SimulateSteps action of `mobot serve --ros2 --paused`.

The Python with rclpy is MOBOT_ROS_PYTHON, this one when it has rclpy, or else a venv the tests make
once and keep in ~/.cache/mobot-tests (tests/ros2/ros_python.py: the ros-jazzy wheels, simulation_interfaces
built from its definitions). Skips, saying why, only when the wheels cannot be installed or cmake or a
compiler is missing; a build that fails after the wheels installed fails the tests.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import time
from pathlib import Path

import pytest

from tests.live.live_server import LiveProcess
from tests.ros2 import ros_python

REPO = Path(__file__).resolve().parents[2]
CLIENT = Path(__file__).with_name("sim_client.py")
WORLD = """version: 1
name: sim_services
world: empty
duration: 1.0
robots:
  - {name: r1, description: mobot, pose: {x: 0.0, y: 0.0}}
"""
BOX = (REPO / "tests" / "data" / "box.urdf").read_text()
ROVER = REPO / "tests" / "data" / "sdf_models" / "rover"  # an SDF model folder (gz-sim's DiffDrive)
XACRO = """<?xml version="1.0"?>
<robot name="xcrate" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:property name="side" value="0.3"/>
  <xacro:macro name="block" params="name">
    <link name="${name}">
      <inertial><mass value="5"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial>
      <collision><geometry><box size="${side} ${side} ${side * 2}"/></geometry></collision>
    </link>
  </xacro:macro>
  <xacro:block name="base_link"/>
</robot>
"""
# xacro that runs code with stock xacro (tests/live/test_security.py has the whole family)
EVIL = ('<?xml version="1.0"?>\n<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">\n'
        """<xacro:property name="cmd" value="eval open('{marker}', 'w').write('owned')"/>\n"""
        '<link name="$(${{cmd}})"/>\n</robot>\n')
OK, NOT_FOUND, INCORRECT_STATE, OPERATION_FAILED, FEATURE_UNSUPPORTED = 1, 2, 3, 4, 0


@pytest.fixture(scope="session")
def ros_py() -> str:
    try:
        python, why = ros_python.provide()
    except ros_python.BuildFailed as exc:
        pytest.fail(f"the Python for the rclpy tests could not be made: {exc}")
    if python is None:
        pytest.skip(why)
    return python


def run_client(python: str, plan: list, tmp_path: Path) -> dict:
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(plan))
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "CYCLONEDDS"))}
    run = subprocess.run([python, str(CLIENT), str(path)], capture_output=True, text=True, timeout=600, env=env)
    assert run.returncode == 0, run.stderr[-3000:]
    return json.loads(run.stdout.strip().splitlines()[-1])


def code(reply: dict) -> tuple[int, str]:
    return reply["result"]["result"], reply["result"]["error_message"]


def steps_of(state: dict, rate: int) -> int:
    stamp = state["state"]["header"]["stamp"]
    return round((stamp["sec"] * 1_000_000_000 + stamp["nanosec"]) * rate / 1e9)


def test_a_real_rclpy_client_calls_every_service(ros_py, tmp_path, tmp_path_factory):
    scenario = tmp_path / "world.yaml"
    scenario.write_text(WORLD)
    xacro = tmp_path / "crate.urdf.xacro"
    xacro.write_text(XACRO)
    marker = tmp_path / "marker"
    pose = {"pose": {"position": {"x": 2.0, "y": 1.0}}}
    plan = [
        ["params", "parameters", {"node": "/mobot"}],
        ["features", "get_simulator_features", {}],
        ["state0", "get_simulation_state", {}],
        ["spawn_text", "spawn_entity", {"name": "crate", "resource_string": BOX, "initial_pose": pose}],
        ["spawn_dup", "spawn_entity", {"name": "crate", "resource_string": BOX}],
        ["spawn_renamed", "spawn_entity", {"name": "crate", "allow_renaming": True, "resource_string": BOX,
                                           "initial_pose": {"pose": {"position": {"x": -2.0}}}}],
        ["spawn_xacro", "spawn_entity", {"name": "xbox", "uri": f"file://{xacro}", "entity_namespace": "/xns",
                                         "initial_pose": {"header": {"frame_id": "crate"},
                                                          "pose": {"position": {"y": 1.5}}}}],
        ["spawn_evil", "spawn_entity", {"name": "evil", "resource_string": EVIL.format(marker=marker)}],
        ["spawn_sdf", "spawn_entity", {"name": "rover", "uri": f"file://{ROVER}",
                                       "initial_pose": {"pose": {"position": {"y": -3.0}}}}],
        ["spawn_world", "spawn_entity", {"name": "w", "resource_string": "<sdf version='1.9'><world name='w'/></sdf>"}],
        ["spawn_empty", "spawn_entity", {"name": "e"}],
        ["spawn_bad_ns", "spawn_entity", {"name": "n", "resource_string": BOX, "entity_namespace": "1bad"}],
        ["spawn_bad_name", "spawn_entity", {"name": "9x", "resource_string": BOX}],
        ["spawn_bad_quat", "spawn_entity", {"name": "q", "resource_string": BOX,
                                            "initial_pose": {"pose": {"orientation": {"w": 0.0}}}}],
        ["spawn_bad_frame", "spawn_entity", {"name": "f", "resource_string": BOX,
                                             "initial_pose": {"header": {"frame_id": "nobody"}}}],
        ["before", "get_entity_state", {"entity": "r1"}],
        ["step5", "step_simulation", {"steps": 5}],
        ["after5", "get_entity_state", {"entity": "r1"}],
        ["action", "simulate_steps", {"steps": 3}],
        ["after3", "get_entity_state", {"entity": "r1"}],
        ["teleport", "set_entity_state", {"entity": "crate", "state": {"pose": {
            "position": {"x": 3.0, "y": -1.0, "z": 0.35}, "orientation": {"z": 0.7071068, "w": 0.7071068}}}}],
        ["readback", "get_entity_state", {"entity": "crate"}],
        ["xbox", "get_entity_state", {"entity": "xbox"}],
        ["teleport_unknown", "set_entity_state", {"entity": "nope"}],
        ["info", "get_entity_info", {"entity": "rover"}],
        ["info_crate", "get_entity_info", {"entity": "xbox"}],
        ["info_unknown", "get_entity_info", {"entity": "nope"}],
        ["bounds", "get_entity_bounds", {"entity": "xbox"}],
        ["bounds_unknown", "get_entity_bounds", {"entity": "nope"}],
        ["spawnables", "get_spawnables", {"sources": ["/opt/models"]}],
        ["teleport_bad", "set_entity_state", {"entity": "crate", "state": {"pose": {"orientation": {"w": 0.0}}}}],
        ["entities", "get_entities", {}],
        ["entities_crate", "get_entities", {"filters": {"filter": "^crate"}}],
        ["entities_objects", "get_entities", {"filters": {"categories": [{"category": 0}]}}],
        ["entities_tags", "get_entities", {"filters": {"tags": {"tags": ["a"]}}}],
        ["entities_redos", "get_entities", {"filters": {"filter": "(a+)+$"}}],
        ["states", "get_entities_states", {"filters": {"filter": "^crate"}}],
        ["delete", "delete_entity", {"entity": "crate_0"}],
        ["delete_again", "delete_entity", {"entity": "crate_0"}],
        ["state_unknown", "get_entity_state", {"entity": "crate_0"}],
        ["play", "set_simulation_state", {"state": {"state": 1}}],
        ["play_again", "set_simulation_state", {"state": {"state": 1}}],
        ["step_playing", "step_simulation", {"steps": 1}],
        ["action_playing", "simulate_steps", {"steps": 2}],
        ["state_playing", "get_simulation_state", {}],
        ["pause", "set_simulation_state", {"state": {"state": 2}}],
        ["quit", "set_simulation_state", {"state": {"state": 3}}],
        ["reset_scope", "reset_simulation", {"scope": 1}],
        ["reset", "reset_simulation", {"scope": 255}],
        ["after_reset", "get_entities", {}],
        ["after_reset_r1", "get_entity_state", {"entity": "r1"}],
        ["step2", "step_simulation", {"steps": 2}],
        ["after_reset_step2", "get_entity_state", {"entity": "r1"}],
    ]
    live = LiveProcess(str(scenario), "--ros2", "--paused", "--out", str(tmp_path / "run"),
                       cache_dir=tmp_path_factory.mktemp("cache"), python=ros_py)
    try:
        with live.client() as client:
            rate = client.ping()["rate_hz"]
        out = run_client(ros_py, plan, tmp_path)
        with live.client() as client:
            alive = client.ping()
    finally:
        exit_code = live.signal()
        log = live.output()
        live.kill()
    assert exit_code == 0, log  # SIGTERM ends the world cleanly, rclpy's node and all
    assert json.loads((tmp_path / "run" / "summary.json").read_text())["status"] == "ok"
    assert out["rmw"] == "rmw_fastrtps_cpp"  # the ROS default, the client this is about
    assert "no simulation_interfaces services" not in log

    # `ros2 param get /mobot use_sim_time`: rclpy's parameter client on the node named as mobot's
    params = out["params"]
    assert "use_sim_time" in params["list"]["result"]["names"]
    assert [(v["type"], v["bool_value"]) for v in params["get"]["values"]] == [(1, True)]  # PARAMETER_BOOL
    assert params["set"]["results"][0]["successful"] is False and "sim time" in params["set"]["results"][0]["reason"]
    assert [v["bool_value"] for v in params["after_set"]["values"]] == [True]

    features = out["features"]["features"]
    assert set(features["features"]) == {0, 1, 5, 9, 10, 11, 12, 14, 20, 24, 25, 26, 31, 32, 33}
    assert features["spawn_formats"] == ["urdf", "xacro", "sdf"]
    assert out["state0"]["state"]["state"] == 2 and code(out["state0"])[0] == OK  # started --paused

    assert code(out["spawn_text"]) == (OK, "") and out["spawn_text"]["entity_name"] == "crate"
    result, message = code(out["spawn_dup"])
    assert result == 101 and "'crate' is already the name" in message  # NAME_NOT_UNIQUE
    assert code(out["spawn_renamed"])[0] == OK and out["spawn_renamed"]["entity_name"] == "crate_0"
    assert code(out["spawn_xacro"])[0] == OK and out["spawn_xacro"]["entity_name"] == "xbox"
    result, message = code(out["spawn_evil"])
    assert result == 106 and not marker.exists()  # RESOURCE_PARSE_ERROR, and the code never ran
    assert code(out["spawn_sdf"]) == (OK, "") and out["spawn_sdf"]["entity_name"] == "rover"  # a Gazebo model
    assert code(out["spawn_world"])[0] == 103  # UNSUPPORTED_FORMAT: a world is not an entity
    assert code(out["spawn_empty"])[0] == 104  # NO_RESOURCE
    assert code(out["spawn_bad_ns"])[0] == 105  # NAMESPACE_INVALID
    assert code(out["spawn_bad_name"])[0] == 102  # NAME_INVALID
    assert code(out["spawn_bad_quat"])[0] == 109  # INVALID_POSE
    result, message = code(out["spawn_bad_frame"])
    assert result == NOT_FOUND and "reference frame 'nobody'" in message

    # exactly N steps: the states' stamps are the world's sim time
    before, after5, after3 = (steps_of(out[k], rate) for k in ("before", "after5", "after3"))
    assert code(out["step5"]) == (OK, "") and after5 - before == 5
    action = out["action"]
    assert action["status"] == 4 and action["result"]["result"]["result"] == OK  # SUCCEEDED
    # Feedback after each step, in order, every one published (read off the action's feedback topic)
    assert action["feedback"] == [[1, 2], [2, 1], [3, 0]] and after3 - after5 == 3

    assert code(out["teleport"]) == (OK, "")
    pose = out["readback"]["state"]["pose"]
    assert math.dist((pose["position"]["x"], pose["position"]["y"]), (3.0, -1.0)) < 1e-6
    assert pose["position"]["z"] == pytest.approx(0.35, abs=1e-6)
    assert abs(pose["orientation"]["z"]) == pytest.approx(math.sqrt(0.5), abs=1e-5)
    assert out["readback"]["state"]["header"]["frame_id"] == "world"
    xbox = out["xbox"]["state"]["pose"]["position"]  # spawned 1.5 m along the crate's y, at (2, 1)
    assert math.dist((xbox["x"], xbox["y"]), (2.0, 2.5)) < 1e-3
    assert code(out["teleport_unknown"])[0] == NOT_FOUND
    info = out["info"]
    assert code(info) == (OK, "") and info["info"]["category"]["category"] == 1  # CATEGORY_ROBOT
    assert info["info"]["description"] == "a robot in namespace /rover" and info["info"]["tags"] == []
    assert out["info_crate"]["info"]["description"] == "a robot in namespace /xns (no drive: it does not take cmd_vel)"
    bounds = out["bounds"]  # the xacro crate: a 0.3 x 0.3 x 0.6 m box round its base link's origin
    assert code(bounds) == (OK, "") and bounds["bounds"]["type"] == 1  # TYPE_BOX
    corners = [(p["x"], p["y"], p["z"]) for p in bounds["bounds"]["points"]]
    assert corners == [pytest.approx((0.15, 0.15, 0.3)), pytest.approx((-0.15, -0.15, -0.3))]  # upper, lower
    assert code(out["bounds_unknown"])[0] == NOT_FOUND
    assert code(out["info_unknown"])[0] == NOT_FOUND
    spawnables = out["spawnables"]
    result, message = code(spawnables)
    assert result == OK and "sources not searched" in message and "/opt/models" in message
    assert {"mobot", "jackal_like"} <= {item["uri"] for item in spawnables["spawnables"]}
    assert code(out["teleport_bad"])[0] == 101  # SetEntityState's INVALID_POSE

    assert out["entities"]["entities"] == ["r1", "crate", "crate_0", "xbox", "rover"]
    assert out["entities_crate"]["entities"] == ["crate", "crate_0"]
    assert out["entities_objects"]["entities"] == []  # every entity mobot lists is a robot
    assert code(out["entities_tags"])[0] == FEATURE_UNSUPPORTED
    assert code(out["entities_redos"])[0] == OPERATION_FAILED
    assert out["states"]["entities"] == ["crate", "crate_0"] and len(out["states"]["states"]) == 2
    assert out["states"]["states"][0]["pose"]["position"]["x"] == pytest.approx(3.0, abs=1e-6)

    assert code(out["delete"]) == (OK, "")
    assert code(out["delete_again"])[0] == NOT_FOUND and "no robot named 'crate_0'" in code(out["delete_again"])[1]
    assert code(out["state_unknown"])[0] == NOT_FOUND

    assert code(out["play"]) == (OK, "") and code(out["play_again"])[0] == 101  # ALREADY_IN_TARGET_STATE
    result, message = code(out["step_playing"])
    assert result == INCORRECT_STATE and "the world is playing" in message
    assert out["action_playing"]["status"] == 6  # ABORTED
    assert out["action_playing"]["result"]["result"]["result"] == INCORRECT_STATE
    assert out["state_playing"]["state"]["state"] == 1
    assert code(out["pause"]) == (OK, "") and code(out["quit"])[0] == FEATURE_UNSUPPORTED
    assert code(out["reset_scope"])[0] == FEATURE_UNSUPPORTED
    assert code(out["reset"]) == (OK, "")
    assert out["after_reset"]["entities"] == ["r1"]  # spawned entities are gone
    assert code(out["step2"]) == (OK, "")
    assert steps_of(out["after_reset_step2"], rate) - steps_of(out["after_reset_r1"], rate) == 2
    assert alive["ok"] and alive["state"] == "paused"  # the world went on through every refusal

    history = [json.loads(line) for line in (tmp_path / "run" / "history.jsonl").read_text().splitlines()]
    spawned = [h["name"] for h in history if h.get("op") == "spawn" and h.get("result") == "OK"]
    assert spawned[:5] == ["r1", "crate", "crate_0", "xbox", "rover"]  # the same records as `mobot spawn`


def test_kilted_twist_stamped_drives_a_robot_as_jazzy_twist_does(ros_py, tmp_path, tmp_path_factory):
    """nav2 sends TwistStamped on cmd_vel from Kilted on, Twist before: an rclpy node (Fast DDS) sends
    each to one of two robots; both take the same command and move alike."""
    scenario = tmp_path / "world.yaml"
    scenario.write_text(WORLD + "  - {name: r2, description: mobot, pose: {x: 0.0, y: 3.0}}\n")
    live = LiveProcess(str(scenario), "--ros2", cache_dir=tmp_path_factory.mktemp("cache"), python=ros_py)
    try:
        with live.client() as client:
            start = {name: client.odom(name)["truth"] for name in ("r1", "r2")}
        out = run_client(ros_py, [
            ["twist", "publish", {"topic": "/r1/cmd_vel", "stamped": False, "linear": 0.3, "angular": 0.2,
                                  "seconds": 1.5}],
            ["stamped", "publish", {"topic": "/r2/cmd_vel", "stamped": True, "linear": 0.3, "angular": 0.2,
                                    "seconds": 1.5}]], tmp_path)
        with live.client() as client:  # the commands are held: each robot goes on until it has gone 0.3 m
            end = {name: _after_moving(client, name, start[name], 0.3) for name in ("r1", "r2")}
    finally:
        live.signal()
        live.kill()
    assert out["twist"]["matched"] == 1 and out["stamped"]["matched"] == 1
    for name in ("r1", "r2"):
        assert end[name]["cmd"] == {"linear": 0.3, "angular": 0.2}  # held, as a `mobot cmd` is
        moved = math.dist((end[name]["truth"]["x"], end[name]["truth"]["y"]), (start[name]["x"], start[name]["y"]))
        assert moved > 0.3, name
        assert end[name]["truth"]["vx"] == pytest.approx(0.3, abs=0.05)
        assert end[name]["truth"]["wz"] == pytest.approx(0.2, abs=0.05)


def _after_moving(client, name: str, start: dict, distance: float, patience: float = 60.0) -> dict:
    """The robot's odom once it is ``distance`` from ``start`` (a real-time world on a busy machine
    may take longer than the publisher's seconds), or when ``patience`` s of wall time ran out."""
    deadline = time.monotonic() + patience
    while True:
        odom = client.odom(name)
        if math.dist((odom["truth"]["x"], odom["truth"]["y"]), (start["x"], start["y"])) > distance or \
                time.monotonic() > deadline:
            return odom
        time.sleep(0.05)
