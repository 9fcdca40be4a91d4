"""expect: makes a run a test: exit 1 naming robot, expectation and outcome; results in summary.json."""

from __future__ import annotations

import json
import math
from dataclasses import astuple
from pathlib import Path

import pytest

from mobot_cli.cli import invoke
from mobot_cli.plan import Expectation, Physics, Plan, WorldPlan
from mobot_cli.scenario.prepare import prepare
from mobot_cli.sim.state import RobotState
from mobot_cli.timeline.expect import Checker
from mobot_cli.timeline.records import Sample

REPO = Path(__file__).resolve().parents[2]
CHECKED = REPO / "scenarios" / "expectations.yaml"


def test_bundled_expectations_pass_and_are_in_the_summary(tmp_path):
    code, out, err = astuple(invoke(["run", CHECKED, "--out", tmp_path / "r"]))
    assert code == 0, err
    block = json.loads((tmp_path / "r" / "summary.json").read_text())["expectations"]
    assert (block["passed"], block["failed"]) == (6, 0)
    assert [r["kind"] for r in block["results"]] == ["within", "within", "distance", "collisions", "upright",
                                                     "odom_error"]
    assert block["results"][0]["expected"] == "be inside x 0.95..1.05, y -0.05..0.05 at 4.5 s"
    assert "pass  mobot: expected to travel 1.7..1.85 m by the end; it travelled 1.7" in out
    assert err == ""


def test_a_failed_expectation_exits_1_and_says_robot_expected_and_happened(tmp_path):
    code, out, err = astuple(invoke(["run", CHECKED, "--out", tmp_path / "r", "--quiet",
                                     "--set", "expect.1.within.x=2.0"]))
    assert code == 1
    assert out == ""
    assert err.startswith("mobot: expectation failed: robot 'mobot' was expected to be within 0.05 m of (2, 0.75) "
                          "at the end; it was at (1.0")
    assert err.count("\n") == 1  # only the failed one
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert summary["status"] == "ok"  # the run itself finished
    assert summary["expectations"]["failed"] == 1
    failed = summary["expectations"]["results"][1]
    assert failed["passed"] is False and failed["robot"] == "mobot"
    assert 0.95 < float(failed["happened"].split(", ")[-1].split(" m")[0]) < 1.05  # 1 m short of x = 2


def test_checks_after_a_shortened_run_fail_saying_so(tmp_path):
    code, out, err = astuple(invoke(["run", CHECKED, "--out", tmp_path / "r", "--quiet", "--duration", "3"]))
    assert code == 1 and out == ""
    assert ("robot 'mobot' was expected to be inside x 0.95..1.05, y -0.05..0.05 at 4.5 s; "
            "it was not checked: the run ended at 3 s") in err


def test_collisions_between_robots_are_counted_and_expected(tmp_path):
    scenario = tmp_path / "meet.yaml"
    scenario.write_text("""version: 1
name: meet
duration: 4
robots:
  - name: a
    commands: [{at: 0.5, linear: 0.3}]
  - name: b
    pose: {x: 1.0, yaw: 3.141592653589793}
    commands: [{at: 0.5, linear: 0.3}]
expect:
  - {robot: all, collisions: 0}
""")
    code, out, err = astuple(invoke(["run", scenario, "--out", tmp_path / "r", "--quiet"]))
    assert code == 1 and out == ""
    assert err.splitlines() == [
        "mobot: expectation failed: robot 'a' was expected to have at most 0 collisions by the end; it had 1 collision",
        "mobot: expectation failed: robot 'b' was expected to have at most 0 collisions by the end; it had 1 collision"]
    robots = json.loads((tmp_path / "r" / "summary.json").read_text())["robots"]
    assert robots["a"]["collisions"] == 1 and robots["b"]["collisions"] == 1


def test_times_go_to_log_rows_fleets_expand_and_the_document_round_trips(tmp_path):
    scenario = tmp_path / "s.yaml"
    scenario.write_text("""version: 1
duration: 6
log: {rate_hz: 48}
robots:
  - name: "r_{i}"
    count: 2
    poses: [[0, 0, 0], [0, 1, 0]]
expect:
  - {robot: "r_{i}", distance: {max: 0.01}, at: 2.51}
  - {robot: all, upright: {max_tilt: 0.3}}
""")
    first = prepare(scenario)
    assert first.plan.expectations == (
        Expectation("r_0", "distance", (("max", 0.01),), step=600),
        Expectation("r_1", "distance", (("max", 0.01),), step=600),
        Expectation("all", "upright", (("max_tilt", 0.3),), step=None))
    assert any("expectation at 2.51 s is checked on the nearest log row, 2.5 s" in n for n in first.plan.notices)
    resolved = tmp_path / "resolved.yaml"
    resolved.write_text(first.resolved_yaml)
    again = prepare(resolved)
    assert again.plan.expectations == first.plan.expectations
    assert again.resolved_yaml == first.resolved_yaml


# Narrow unit tests of the checks on made-up samples (the physics is tested above).

def state(x=0.0, y=0.0, yaw=0.0, odom=(0.0, 0.0, 0.0), roll=0.0, collisions=0) -> RobotState:
    return RobotState(0.0, 0.0, odom[0], odom[1], odom[2], 0.0, 0.0, x, y, 0.0, roll, 0.0, yaw, 0.0, 0.0,
                      collisions=collisions)


def check(expectations, samples, rate=10):
    plan = Plan(name="t", physics=Physics(rate_hz=rate), world=WorldPlan(), robots=(), total_steps=100,
                settle_steps=0, log_every=1, expectations=tuple(expectations))
    checker = Checker(plan)
    seen: set[str] = set()
    for step, states in samples:
        for name in sorted(seen - states.keys()):  # a robot missing from a row was deleted
            checker.deleted(step, name)
            seen.discard(name)
        for name in sorted(states.keys() - seen):
            checker.spawned(step, name, None)
            seen.add(name)
        checker.write(Sample(step, states))
    return [(r.robot, r.passed, r.happened) for r in checker.results()]


def test_distance_drift_tilt_and_collisions_are_judged_on_the_whole_span():
    samples = [(0, {"a": state()}),
               (1, {"a": state(x=3.0, y=4.0, odom=(3.0, 4.2, 0.0), roll=0.5, collisions=1)}),
               (2, {"a": state(x=3.0, y=4.0, odom=(3.0, 4.0, 0.0), collisions=1)})]
    results = check([Expectation("a", "distance", (("min", 5.0), ("max", 5.0))),
                     Expectation("a", "odom_error", (("position", 0.1),)),
                     Expectation("a", "upright", (("max_tilt", 0.4),)),
                     Expectation("a", "collisions", (("max", 1.0),)),
                     Expectation("a", "within", (("x", 3.0), ("y", 4.0), ("radius", 0.01)), step=1)], samples)
    assert results == [
        ("a", True, "travelled 5.000 m"),
        ("a", False, "drifted at most 0.200 m (at 0.1 s)"),  # the worst moment, not the last
        ("a", False, f"tilted at most 0.500 rad ({math.degrees(0.5):.1f} deg) (at 0.1 s)"),
        ("a", True, "had 1 collision"),
        ("a", True, "was at (3.000, 4.000), 0.000 m from the centre")]


def test_odometry_is_compared_in_the_spawn_frame():
    # Spawned at (1, 1) facing +y: odom x = 1 is world (1, 2).
    samples = [(0, {"a": state(x=1.0, y=1.0, yaw=math.pi / 2)}),
               (1, {"a": state(x=1.0, y=2.0, yaw=math.pi / 2, odom=(1.0, 0.0, 0.0))})]
    assert check([Expectation("a", "odom_error", (("position", 1e-9), ("yaw", 1e-9)))], samples)[0][1] is True


def test_all_checks_each_robot_and_a_deleted_robot_is_not_within():
    samples = [(0, {"a": state(), "b": state(x=5.0)}), (1, {"a": state(x=0.1)})]  # b deleted after step 0
    box = (("xmin", -1.0), ("xmax", 1.0), ("ymin", -1.0), ("ymax", 1.0))
    assert check([Expectation("all", "within", box), Expectation("all", "collisions", (("max", 0.0),)),
                  Expectation("b", "within", box)], samples) == [
        ("a", True, "was at (0.100, 0.000)"),
        ("a", True, "had 0 collisions"), ("b", True, "had 0 collisions"),
        ("b", False, "was deleted (last seen at 0 s)")]


@pytest.mark.parametrize("text, message", [
    ("{robot: mobot, at: soon, collisions: 0}", "'at' is 'end' or a time in seconds, e.g. 5.0; got 'soon'"),
    ("{robot: mobot, upright: false}", "'upright: false' checks nothing"),
    ("{robot: mobot}", "needs one check: within, collisions, distance, upright, odom_error"),
    ("{robot: mobot, within: {x: 1, y: 2}}", "give a circle {x, y, radius} or a box {xmin, xmax, ymin, ymax}"),
    ("{robot: mobot, distance: {}}", "give 'min', 'max' or both"),
    ("{robot: mobot, colisions: 0}", "unknown key 'colisions'. Did you mean 'collisions'?"),
    ("{robot: mobot, odom_error: -1}", "key 'expect[0].odom_error'"),
])
def test_bad_expectations_are_located_errors(text, message, tmp_path):
    scenario = tmp_path / "bad.yaml"
    scenario.write_text(f"version: 1\nduration: 2\nrobots:\n  - name: mobot\nexpect:\n  - {text}\n")
    code, out, err = astuple(invoke(["check", scenario]))
    assert code == 2 and out == ""
    assert err.startswith(f"mobot: error: {scenario}:6, key 'expect[0]")
    assert message in err
