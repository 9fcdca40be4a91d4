"""Navigation metrics on constructed runs with known answers, `metric` expectations and --junit.

The room (tests/sim/sensor_world.py) has inner wall faces at x = +-3 m and y = +-2 m; the bundled
robot's chassis reaches 0.17 m to each side of its centre line.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from lxml import etree

from mobot_cli.cli import invoke
from mobot_cli.sim.state import RobotState
from mobot_cli.timeline.metrics import Meter, failure, spl
from tests.sim.sensor_world import room_scenario

ROBOT = """  - name: mobot
    description: mobot
    pose: {x: -2.0, y: 1.5, yaw: 0.0}
    commands:
      - {at: 0.0, goto: {x: 2.0, y: 1.5}, localization: ground_truth, timeout: 30}
      - {at: 0.0, goto: {x: 4.0, y: 1.5}, localization: ground_truth, timeout: 30, stuck_time: 2.0}
"""
EXPECT = """expect:
  - {robot: mobot, metric: {name: spl, min: 0.9, command: 0}}
  - {robot: mobot, metric: {name: collisions, max: 0}}
"""


@pytest.fixture(scope="module")
def wall_run(tmp_path_factory):
    """Along the north wall 0.5 m off it, then on into the east wall (beyond the room)."""
    folder = tmp_path_factory.mktemp("metrics")
    path = room_scenario(folder, ROBOT, duration=25.0)
    path.write_text(path.read_text() + EXPECT)
    done = invoke(["run", path, "--out", folder / "out", "--quiet", "--junit", folder / "run.xml"])
    return folder, done, json.loads((folder / "out" / "summary.json").read_text())


def test_straight_goto_path_length_and_spl(wall_run):
    _, _, summary = wall_run
    straight = summary["robots"]["mobot"]["goals"][0]
    assert straight["status"] == "reached" and straight["success"] is True and straight["failure"] is None
    assert straight["optimal_length"] == pytest.approx(4.0, abs=1e-3)
    assert straight["path_length"] == pytest.approx(4.0, rel=0.01)
    assert straight["spl"] == pytest.approx(1.0, abs=0.01)
    assert straight["collisions"] == 0 and straight["collided_with"] == []


def test_known_clearance_beside_a_wall(wall_run):
    straight = wall_run[2]["robots"]["mobot"]["goals"][0]
    # 2.0 - 1.5 m to the wall's face less the chassis' half width
    assert straight["clearance_min"] == pytest.approx(0.33, abs=0.015)
    assert straight["clearance_mean"] == pytest.approx(0.33, abs=0.015)
    assert straight["danger_time"] == 0.0


def test_forced_collision_names_the_wall_and_fails_the_goal(wall_run):
    _, _, summary = wall_run
    into = summary["robots"]["mobot"]["goals"][1]
    assert into["status"] == "blocked" and into["success"] is False and into["failure"] == "collision"
    assert into["collisions"] >= 1 and into["collided_with"] == ["walls"]
    # the front (0.10 m ahead of the axle) meets the wall at x = 3: at 0.3 m/s from x ~ 2, about 3 s on
    log_period = 1 / summary["log_rate_hz"]
    assert into["started_at"] + 2.0 < into["collision_first"] < into["started_at"] + 5.0
    assert into["spl"] == 0.0
    # stuck_time 2 s: it ends within two such windows of touching
    assert 2.0 - log_period <= into["ended_at"] - into["collision_first"] <= 4.0 + log_period
    assert into["danger_time"] > 0.0 and into["clearance_min"] < 0.01
    metrics = summary["robots"]["mobot"]["metrics"]
    assert metrics["success"] is False and metrics["failure"] == "collision" and metrics["spl"] == 0.5


CRATE = """    <model name="crate">
      <static>true</static>
      <pose>1.0 1.0 0.25 0 0 0</pose>
      <link name="l"><collision name="c"><geometry><box><size>0.4 0.4 0.5</size></box></geometry></collision></link>
    </model>
"""


def test_collisions_name_the_box_and_the_robot_hit(tmp_path):
    """One robot drives into a crate, another into a robot standing in its way."""
    robots = ("  - name: a\n    description: mobot\n    pose: {x: -1.0, y: 1.0, yaw: 0.0}\n    commands:\n"
              "      - {at: 0.0, goto: {x: 2.0, y: 1.0}, localization: ground_truth, timeout: 20}\n"
              "  - name: b\n    description: mobot\n    pose: {x: 1.0, y: -1.0, yaw: 1.57}\n"
              "  - name: c\n    description: mobot\n    pose: {x: -1.0, y: -1.0, yaw: 0.0}\n    commands:\n"
              "      - {at: 0.0, goto: {x: 2.0, y: -1.0}, localization: ground_truth, timeout: 20}\n")
    path = room_scenario(tmp_path, robots, duration=20.0)
    (tmp_path / "room.sdf").write_text((tmp_path / "room.sdf").read_text().replace("  </world>", CRATE + "  </world>"))
    done = invoke(["run", path, "--out", tmp_path / "out", "--quiet"])
    assert done.exit_code == 0, done.stderr
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    log_period = 1 / summary["log_rate_hz"]
    for name, hit in (("a", "crate"), ("c", "b")):
        (goal,) = summary["robots"][name]["goals"]
        assert goal["collided_with"] == [hit] and goal["collisions"] >= 1 and goal["failure"] == "collision"
        # the front (0.10 m ahead of the axle) meets the crate's face (x = 0.8), or b's side (x = 0.83)
        assert goal["status"] == "blocked" and goal["error"] == pytest.approx(3.0 - 1.7, abs=0.1)
        assert summary["robots"][name]["collisions"] == goal["collisions"]
        # when its front (0.10 m ahead of the axle) reaches the face (x = 0.8 for both) PyBullet reports a
        # contact within 1 mm, sampled at 50 Hz (sim/contacts.py): the robot bounces, and is counted at
        # the latest when it settles against the face
        rows = (tmp_path / "out" / "odom" / f"{name}.csv").read_text().splitlines()[1:]
        touching = next(float(r.split(",")[0]) for r in rows if float(r.split(",")[8]) + 0.10 >= 0.798)
        assert touching - log_period <= goal["collision_first"] <= touching + 0.2
    assert summary["robots"]["b"]["collisions"] >= 1 and "metrics" not in summary["robots"]["b"]


def test_metrics_are_deterministic_and_agree_on_the_kinematic_engine(wall_run, tmp_path):
    folder, _, physics = wall_run
    path = folder / "scenario.yaml"
    texts = []
    for k in range(2):
        invoke(["run", path, "--out", tmp_path / f"k{k}", "--quiet", "--set", "physics.engine=kinematic",
                "--junit", tmp_path / f"k{k}.xml"])
        summary = json.loads((tmp_path / f"k{k}" / "summary.json").read_text())
        del summary["wall_time"], summary["real_time_factor"]
        texts.append((json.dumps(summary), (tmp_path / f"k{k}.xml").read_bytes()))
    assert texts[0] == texts[1]
    kinematic = json.loads(texts[0][0])["robots"]["mobot"]["goals"]
    for ours, theirs in zip(kinematic, physics["robots"]["mobot"]["goals"]):
        assert (ours["status"], ours["failure"], ours["collided_with"]) == \
            (theirs["status"], theirs["failure"], theirs["collided_with"])
        assert ours["path_length"] == pytest.approx(theirs["path_length"], abs=0.02)
        assert ours["clearance_min"] == pytest.approx(theirs["clearance_min"], abs=0.01)


def test_no_progress_ends_stuck_after_stuck_time(tmp_path):
    """Creeping at 5 mm/s moves less than 2 cm in 2 s: no progress, nothing touched."""
    robot = ("  - name: mobot\n    description: mobot\n    pose: {x: 0.0, y: 0.0, yaw: 0.0}\n    commands:\n"
             "      - {at: 0.0, goto: {x: 1.0, y: 0.0}, max_linear: 0.005, stuck_time: 2.0, "
             "localization: ground_truth}\n")
    path = room_scenario(tmp_path, robot, duration=4.0)
    done = invoke(["run", path, "--out", tmp_path / "out", "--quiet"])
    assert done.exit_code == 0, done.stderr
    (goal,) = json.loads((tmp_path / "out" / "summary.json").read_text())["robots"]["mobot"]["goals"]
    assert (goal["status"], goal["failure"], goal["collisions"], goal["success"]) == ("blocked", "stuck", 0, False)
    assert goal["ended_at"] - goal["started_at"] == pytest.approx(2.0)
    assert goal["path_length"] < 0.02


def test_metric_expectations(wall_run):
    _, done, summary = wall_run
    assert done.exit_code == 1
    spl_check, collisions = summary["expectations"]["results"]
    assert spl_check["passed"] and spl_check["happened"] == "had spl 1"
    assert not collisions["passed"] and collisions["happened"].startswith("had collisions ")


SCHEMA = Path(__file__).parent.parent / "data" / "junit-10.xsd"  # Jenkins xunit-plugin's, which pytest follows


def junit(path: Path) -> etree._Element:
    """The report at ``path``, checked against junit-10.xsd."""
    document = etree.parse(str(path))
    schema = etree.XMLSchema(etree.parse(str(SCHEMA)))
    assert schema.validate(document), schema.error_log
    return document.getroot()


def properties(suite) -> dict[str, str]:
    return {p.get("name"): p.get("value") for p in suite.find("properties")}


def test_junit_of_a_run(wall_run):
    folder, _, summary = wall_run
    root = junit(folder / "run.xml")
    assert (root.tag, root.get("tests"), root.get("failures"), root.get("errors")) == ("testsuites", "2", "1", "0")
    (suite,) = root
    assert (suite.get("name"), suite.get("tests"), suite.get("failures"), suite.get("errors"), suite.get("time")) \
        == ("sensors", "2", "1", "0", "25.000")
    passed, failed = suite.findall("testcase")
    assert passed.get("name") == "mobot: metric: have spl at least 0.9 in goal command 0"
    assert passed.find("failure") is None and failed.find("failure") is not None
    assert failed.find("failure").get("message").startswith(
        "robot 'mobot' was expected to have collisions at most 0 over its goals; it had collisions ")
    props = properties(suite)
    assert props["seed"] == str(summary["seed"]) == "11" and props["mobot.goal0.spl"] == "1"
    assert props["mobot.failure"] == "collision" and props["mobot.goal1.status"] == "blocked"


def test_junit_of_a_fault_and_of_bad_input(tmp_path):
    (tmp_path / "flying.yaml").write_text("version: 1\nname: flying\nduration: 3\nphysics: {gravity: [0, 0, 2.0]}\n"
                                          "faults: {flying_time: 1.0}\nrobots:\n  - name: mobot\n")
    (tmp_path / "bad.yaml").write_text("version: 1\nname: bad\nduration: -1\nrobots:\n  - name: mobot\n")
    done = invoke(["run", tmp_path / "flying.yaml", tmp_path / "bad.yaml", "--out", tmp_path / "runs", "--quiet",
                   "--junit", tmp_path / "report.xml"])
    assert done.exit_code == 3
    flying, bad = junit(tmp_path / "report.xml")
    (case,) = flying.findall("testcase")
    assert (case.get("name"), case.find("error").get("type")) == ("run", "flying")
    assert "robot 'mobot' is flying at step 240" in case.find("error").get("message")
    assert (flying.get("errors"), properties(flying)["status"]) == ("1", "fault")
    (case,) = bad.findall("testcase")
    assert bad.get("name") == "bad" and "duration" in case.find("error").get("message")


def test_junit_of_a_sweep(tmp_path):
    path = room_scenario(tmp_path, ROBOT.replace(", stuck_time: 2.0", ""), duration=5.0)
    path.write_text(path.read_text() + "expect:\n  - {robot: mobot, metric: {name: path_length, min: 1.0}}\n")
    done = invoke(["sweep", path, "--grid", "duration=3,5", "--out", tmp_path / "sw", "--quiet", "-j", "1",
                   "--junit", tmp_path / "sweep.xml"])
    assert done.exit_code == 1, done.stderr
    root = junit(tmp_path / "sweep.xml")
    assert (root.get("tests"), root.get("failures"), root.get("errors")) == ("2", "1", "0")
    short, long = root
    assert (short.get("name"), long.get("name")) == ("sensors run 0", "sensors run 1")
    assert short.find("testcase/failure").get("message").startswith(
        "robot 'mobot' was expected to have path_length at least 1 over its goals; it had path_length 0.")
    assert long.find("testcase/failure") is None
    rows = (tmp_path / "sw" / "results.csv").read_text().splitlines()
    header, first = rows[0].split(","), dict(zip(rows[0].split(","), rows[1].split(",")))
    assert "mobot.spl" in header and "mobot.clearance_min" in header
    assert properties(short)["duration"] == "3" and properties(short)["seed"] == first["seed"]
    assert properties(short)["mobot.path_length"] == first["mobot.path_length"]


def _state(v: float, w: float = 0.0, x: float = 0.0, clearance: float = math.inf) -> RobotState:
    return RobotState(v, w, 0, 0, 0, v, w, x, 0, 0, 0, 0, 0, v, w, clearance=clearance)


def test_jerk_is_zero_at_constant_speed_and_positive_on_a_step():
    steady = Meter(_state(0.3), 0, 100, 0.3)
    for k in range(1, 50):
        steady.add(_state(0.3, x=0.003 * k), k * 5)
    assert steady.jerk_linear == 0.0 and steady.jerk_angular == 0.0
    step = Meter(_state(0.0), 0, 100, 0.3)
    for k in range(1, 50):
        step.add(_state(0.3 if k >= 25 else 0.0, 0.5 if k >= 25 else 0.0), k * 5)
    # one jump of 0.3 m/s between rows 0.05 s apart: jerk +-0.3 / 0.05^2 on two rows, squared times 0.05
    assert step.jerk_linear == pytest.approx(2 * (0.3 / 0.05 ** 2) ** 2 * 0.05)
    assert step.jerk_angular > 0.0


def test_first_collision_is_the_row_the_count_rose_on():
    meter = Meter(_state(0.1), 0, 240, 0.3)
    for k in range(1, 20):
        state = _state(0.1, x=0.01 * k)
        state.collisions, state.hit = (0, "") if k < 7 else (1, "crate") if k < 12 else (2, "b")
        meter.add(state, k * 5)
    assert meter.first_collision == 7 * 5 / 240 and meter.collisions == 2 and meter.hits == ["crate", "b"]


def test_danger_time_counts_the_periods_closer_than_the_danger_distance():
    meter = Meter(_state(0.0, clearance=1.0), 0, 100, 0.3)
    for k, c in enumerate([1.0, 0.25, 0.2, 0.29, 0.31, math.inf], start=1):
        meter.add(_state(0.0, clearance=c), k * 10)
    assert meter.danger_time == pytest.approx(0.3)
    assert meter.least_clearance == 0.2


def test_failure_and_spl_rules():
    assert failure("reached", 0) is None and failure("blocked", 0) == "stuck"
    assert failure("blocked", 2) == "collision" and failure("timed_out", 0) == "timeout"
    assert failure("failed", 0, "tipped_over") == "flipped" and failure("unreachable", 0) == "unreachable"
    assert spl(True, 4.0, 5.0) == 0.8 and spl(False, 4.0, 4.0) == 0.0 and spl(True, None, 1.0) is None
