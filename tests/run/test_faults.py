"""Runs that never lie: faults end a run with exit 3 and say so in summary.json; a goal that only
odometry saw reached says that; odometry far from the truth is a notice.

End to end through `mobot run`, on a four-wheel base of our own (robots/base.urdf.xacro): a tall
one that flips when it accelerates hard, one that gravity lifts off the floor, a car-sized one
whose wheel torque must scale with its mass.
"""

from __future__ import annotations

import json
import math
from dataclasses import astuple
from pathlib import Path

import pytest

from mobot_cli.cli import invoke

BASE = Path(__file__).parent / "robots" / "base.urdf.xacro"
TALL = "{wheelbase: 0.3, com_z: 1.0, mass: 20}"


def run(tmp_path: Path, body: str, name: str = "s") -> tuple[int, str, dict]:
    """`mobot run` of a scenario (``body`` after the version line): exit code, stderr, summary."""
    scenario = tmp_path / f"{name}.yaml"
    scenario.write_text(f"version: 1\nname: {name}\n{body}")
    code, out, err = astuple(invoke(["run", scenario, "--out", tmp_path / name, "--quiet"]))
    assert out == ""
    summary = tmp_path / name / "summary.json"
    return code, err, json.loads(summary.read_text()) if summary.exists() else {}


def robot(name: str, args: str, extra: str = "", commands: str = "") -> str:
    return (f"  - name: {name}\n    description: {BASE}\n    args: {args}\n{extra}"
            + (f"    commands:\n{commands}" if commands else ""))


def test_a_tall_robot_that_flips_under_hard_acceleration_ends_the_run_as_a_fault(tmp_path):
    code, err, summary = run(tmp_path, "duration: 4\nrobots:\n" + robot(
        "tall", TALL, "    drive: {max_wheel_torque: 200}\n", "      - {at: 0.5, linear: 3.0}\n"))
    assert code == 3
    step = summary["fault"]["step"]
    assert err.startswith(f"mobot: error: robot 'tall' tipped over at step {step}: tilted ")
    assert "beyond faults.max_tilt 60 deg" in err
    pitch = float(err.split("pitch ")[1].split(" deg")[0])
    assert abs(pitch) > 55  # it went over backwards: pitch, not roll
    assert summary["status"] == "fault" and summary["error"] == err[len("mobot: error: "):-1]
    assert summary["fault"] == {"robot": "tall", "step": step, "time": step / 240, "kind": "tipped_over"}
    assert 120 < step < 480  # within 1.5 s of the command at 0.5 s
    assert step - 24 < summary["steps"] <= step  # the last log row before it


def test_a_narrow_tall_robot_on_a_fast_arc_rolls_over(tmp_path):
    # a long wheelbase and gentle wheel acceleration keep it from pitching: the arc rolls it
    code, err, summary = run(tmp_path, "duration: 6\nrobots:\n" + robot(
        "narrow", "{wheelbase: 1.0, track: 0.3, com_z: 1.0}",
        "    drive: {max_wheel_torque: 200, max_wheel_acceleration: 20, twist_feedback: false}\n",
        "      - {at: 0.5, linear: 3.0, angular: 3.0}\n"))
    assert code == 3 and summary["fault"]["kind"] == "tipped_over"
    assert err.startswith(f"mobot: error: robot 'narrow' tipped over at step {summary['fault']['step']}: ")
    roll = float(err.split("(roll ")[1].split(" deg")[0])
    assert abs(roll) > 55


def test_the_same_command_on_a_low_robot_is_no_fault(tmp_path):
    code, err, summary = run(tmp_path, "duration: 3\nrobots:\n" + robot(
        "low", "{wheelbase: 0.3, com_z: 0.0, mass: 20}", "    drive: {max_wheel_torque: 200}\n",
        "      - {at: 0.5, linear: 3.0}\n"))
    assert (code, err, summary["status"], summary["fault"]) == (0, "", "ok", None)
    assert summary["robots"]["low"]["final_pose"]["x"] > 5.0


def test_a_goal_whose_robot_flips_fails_as_flipped_and_the_run_is_a_fault(tmp_path):
    goal = "      - {goto: {x: 10.0, y: 0.0}, max_linear: 3.0, acceleration: 100.0}\n"
    code, err, summary = run(tmp_path, "duration: 6\nrobots:\n" + robot(
        "tall", TALL, "    drive: {max_wheel_torque: 200}\n", goal))
    assert code == 3 and "robot 'tall' tipped over at step" in err
    assert summary["status"] == "fault"
    (record,) = summary["robots"]["tall"]["goals"]
    assert (record["status"], record["failure"]) == ("failed", "flipped")
    assert record["error"] is None and record["ended_at"] is None


def test_a_robot_that_gravity_lifts_off_the_floor_is_flying_after_the_flying_time(tmp_path):
    body = "duration: 4\nphysics: {gravity: [0, 0, 2.0]}\nrobots:\n" + robot("up", "{}")
    code, err, summary = run(tmp_path, body)
    assert code == 3
    assert summary["fault"] == {"robot": "up", "step": 240, "time": 1.0, "kind": "flying"}
    # 1 s at 2 m/s^2: 1 m up, rising at 2 m/s
    assert err.startswith("mobot: error: robot 'up' is flying at step 240: it has touched nothing for 1.0 s "
                          "and is 1.00 m above where it last did (vertical speed +2.00 m/s)")
    code, err, summary = run(tmp_path, body.replace("robots:", "faults: {flying_time: 2.0}\nrobots:"), "later")
    assert code == 3 and summary["fault"]["step"] == 480


def test_a_robot_thrown_up_fast_is_a_runaway(tmp_path):
    code, err, summary = run(tmp_path, "duration: 4\nphysics: {gravity: [0, 0, 60.0]}\nrobots:\n" + robot("up", "{}"))
    assert code == 3 and summary["fault"]["kind"] == "runaway"
    assert "robot 'up' ran away at step" in err and "beyond the limit of 20 m/s" in err
    loose = "duration: 0.6\nphysics: {gravity: [0, 0, 60.0]}\nfaults: {max_speed: 50, flying_time: 5}\nrobots:\n"
    code, err, summary = run(tmp_path, loose + robot("up", "{}"), "loose")
    assert (code, summary["status"]) == (0, "ok")  # 36 m/s at 0.6 s: within a limit of 50


def test_the_faults_section_is_checked_at_load(tmp_path):
    code, err, _ = run(tmp_path, "duration: 1\nfaults: {max_tilt: 0}\n")
    assert code == 2 and "s.yaml:4, key 'faults.max_tilt'" in err


# -- torque -------------------------------------------------------------------------------------

HEAVY = "{wheelbase: 0.5, track: 0.55, radius: 0.165, mass: 250}"
LIGHT = "{wheelbase: 0.5, track: 0.55, radius: 0.165, mass: 20}"
TURN = "      - {at: 0.5, angular: 0.5, for: 3.1416}\n"  # 90 deg left in place


def yaw_deg(summary: dict, name: str) -> float:
    return math.degrees(summary["robots"][name]["final_pose"]["yaw"])


def test_a_250_kg_skid_base_turns_90_degrees_as_a_light_one_does(tmp_path):
    code, err, summary = run(tmp_path, "duration: 5\nrobots:\n" + robot("heavy", HEAVY, commands=TURN)
                             + robot("light", LIGHT, "    pose: {x: 3.0}\n", TURN))
    assert (code, err) == (0, "")
    assert yaw_deg(summary, "heavy") == pytest.approx(90.0, abs=3.0)
    assert yaw_deg(summary, "light") == pytest.approx(90.0, abs=3.0)
    assert not [n for n in summary["notices"] if "torque limit" in n]
    resolved = (tmp_path / "s" / "scenario.yaml").read_text()
    # 275 kg (its wheels too) * (1 + 9.81 sin 45) m/s^2 * 0.165 m / 4 wheels; the light one
    # (22 kg: 7.2 N*m) keeps the 20 N*m floor
    assert "max_wheel_torque: 90.032" in resolved and "max_wheel_torque: 20.0" in resolved


def test_the_old_fixed_20_nm_stalls_the_heavy_base_and_says_so(tmp_path):
    code, err, summary = run(tmp_path, "duration: 5\nrobots:\n" + robot(
        "heavy", HEAVY, "    drive: {max_wheel_torque: 20}\n", TURN))
    assert code == 0 and abs(yaw_deg(summary, "heavy")) < 3.0
    (notice,) = [n for n in summary["notices"] if "torque limit" in n]
    assert notice.startswith("robot 'heavy': its wheels have been at their torque limit (20 N*m, from "
                             "drive.max_wheel_torque) since step 144 (1.0 s) while commanded to move")


def test_a_urdf_effort_limit_is_the_torque_and_a_tiny_one_is_warned(tmp_path):
    code, err, summary = run(tmp_path, "duration: 3\nrobots:\n" + robot(
        "weak", "{mass: 20, effort: 0.05}", commands="      - {at: 0.5, linear: 1.0, for: 2.0}\n"))
    assert code == 0 and summary["status"] == "ok"
    # 4 wheels * 0.05 N*m / 0.1 m = 2 N on 22 kg: 0.09 m/s^2, about 0.2 m of the 2 m commanded
    assert summary["robots"]["weak"]["final_pose"]["x"] < 0.5
    (notice,) = [n for n in summary["notices"] if "torque limit" in n]
    assert notice.startswith("robot 'weak': its wheels have been at their torque limit (0.05 N*m, from its "
                             "wheel joints' <limit effort>) since step 144")
    assert err == ""  # --quiet: said in summary.json only
    assert "max_wheel_torque: 0.05" in (tmp_path / "s" / "scenario.yaml").read_text()


# -- goals on ground truth ----------------------------------------------------------------------

GOTO = "    commands:\n      - {goto: {x: 2.0, y: 0.0}}\n"


def test_a_goal_reached_only_by_wrong_odometry_says_so(tmp_path):
    body = "duration: 20\nrobots:\n  - name: mobot\n    drive: {wheel_radius_multiplier: 2.0}\n" + GOTO
    code, err, summary = run(tmp_path, body)
    assert (code, summary["status"]) == (0, "ok")
    robot_record = summary["robots"]["mobot"]
    (goal,) = robot_record["goals"]
    assert goal["status"] == "reached_by_odometry_only"
    assert goal["error"] == pytest.approx(1.0, abs=0.05)  # odometry counts every metre twice
    assert robot_record["odom_error"]["max_position"] == pytest.approx(1.0, abs=0.05)
    (notice,) = [n for n in summary["notices"] if "odometry and ground truth" in n]
    assert notice.startswith("robot 'mobot': odometry and ground truth disagree by 0.99 m at ")
    assert notice.endswith("beyond faults.odom_tolerance 0.25 m")


def test_a_goal_with_true_odometry_is_reached(tmp_path):
    code, err, summary = run(tmp_path, "duration: 20\nrobots:\n  - name: mobot\n" + GOTO)
    (goal,) = summary["robots"]["mobot"]["goals"]
    assert (code, goal["status"], goal["failure"]) == (0, "reached", None)
    assert goal["error"] < 0.1 and summary["robots"]["mobot"]["odom_error"]["max_position"] < 0.1
    assert not [n for n in summary["notices"] if "odometry" in n]


def test_without_quiet_the_run_prints_what_it_said_during_the_run(tmp_path):
    scenario = tmp_path / "weak.yaml"
    scenario.write_text("version: 1\nduration: 3\nrobots:\n" + robot(
        "weak", "{mass: 20, effort: 0.05}", commands="      - {at: 0.5, linear: 1.0, for: 2.0}\n"))
    done = invoke(["run", scenario, "--out", tmp_path / "r"])
    assert done.exit_code == 0
    assert "mobot: warning: robot 'weak': its wheels have been at their torque limit (0.05 N*m" in done.stderr
