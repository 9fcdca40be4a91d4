"""A car in a scenario: drive.type checked against what is detected, steering_angle commands,
refused drives named in the error, and the clamp said in the run (summary.json and the terminal)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from mobot_cli.cli import invoke
from mobot_cli.errors import ScenarioError
from mobot_cli.scenario.prepare import prepare
from tests.sim.car import TRACKED, WHEELBASE, car

CAR = Path(__file__).resolve().parents[1] / "sim" / "robots" / "ackermann_car.urdf"


def scenario(tmp_path: Path, robot: str | Path, drive: str = "", commands: str = "") -> Path:
    path = tmp_path / "s.yaml"
    path.write_text(f"version: 1\nduration: 4\nrobots:\n  - name: car\n    description: {robot}\n"
                    + (f"    drive: {drive}\n" if drive else "")
                    + (f"    commands:\n{commands}" if commands else ""))
    return path


def test_steering_angle_becomes_the_bicycle_yaw_rate(tmp_path):
    path = scenario(tmp_path, CAR, "{type: ackermann}",
                    "      - {at: 0.5, linear: 0.5, steering_angle: 0.2, for: 1}\n")
    (command, stop) = prepare(path).plan.robots[0].commands
    assert command.angular == pytest.approx(0.5 * math.tan(0.2) / WHEELBASE)
    assert (stop.linear, stop.angular) == (0.0, 0.0)


def test_steering_angle_needs_a_car(tmp_path):
    path = scenario(tmp_path, "mobot", commands="      - {at: 0.5, linear: 0.5, steering_angle: 0.2}\n")
    with pytest.raises(ScenarioError, match="steering_angle is for cars") as err:
        prepare(path)
    assert err.value.location.line == 7


def test_angular_and_steering_angle_together_are_refused(tmp_path):
    path = scenario(tmp_path, CAR, commands="      - {at: 0.5, linear: 0.5, angular: 0.1, steering_angle: 0.2}\n")
    done = invoke(["check", path])
    assert done.exit_code == 2 and "gives both 'angular' and 'steering_angle'" in done.stderr


def test_a_car_is_never_driven_as_a_diff_drive(tmp_path):
    with pytest.raises(ScenarioError, match="drive.type is diff, but the drive detected in .* is ackermann") as err:
        prepare(scenario(tmp_path, CAR, "{type: diff}"))
    assert err.value.location.key == "robots.car.drive.type"


def test_a_diff_drive_is_not_a_car(tmp_path):
    with pytest.raises(ScenarioError, match="drive.type is ackermann, but the drive detected in 'mobot' is diff"):
        prepare(scenario(tmp_path, "mobot", "{type: ackermann}"))


def test_commands_to_a_refused_drive_name_it(tmp_path):
    robot = tmp_path / "tracked.urdf"
    robot.write_text(car(TRACKED))
    done = invoke(["check", scenario(tmp_path, robot, commands="      - {at: 0.5, linear: 0.5}\n")])
    assert done.exit_code == 2
    assert ("robot 'car' has commands but mobot cannot drive its tracked vehicle "
            "(gz::sim::systems::TrackedVehicle)") in done.stderr
    passive = invoke(["run", scenario(tmp_path, robot), "--out", tmp_path / "run", "--quiet"])
    assert passive.exit_code == 0, passive.stderr


def test_the_clamp_is_said_once_in_the_run(tmp_path):
    path = scenario(tmp_path, CAR, commands="      - {at: 0.5, linear: 0.5, angular: 2.0, for: 1}\n"
                                            "      - {at: 2, linear: 0.5, angular: -2.0, for: 1}\n")
    done = invoke(["run", path, "--out", tmp_path / "run"])
    assert done.exit_code == 0, done.stderr
    line = ("robot 'car' has Ackermann steering: turns tighter than its minimum turning radius 1.035 m "
            "are driven at that radius")
    assert done.stderr.count(line) == 1
    assert json.loads((tmp_path / "run" / "summary.json").read_text())["notices"].count(line) == 1


def test_the_resolved_scenario_keeps_the_car(tmp_path):
    path = scenario(tmp_path, CAR, "{type: ackermann, max_steering_angle: 0.3}",
                    "      - {at: 0.5, linear: 0.5, steering_angle: 0.1, for: 1}\n")
    first = invoke(["run", path, "--out", tmp_path / "a", "--quiet"])
    assert first.exit_code == 0, first.stderr
    again = invoke(["run", tmp_path / "a" / "scenario.yaml", "--out", tmp_path / "b", "--quiet"])
    assert again.exit_code == 0, again.stderr
    drive = prepare(tmp_path / "a" / "scenario.yaml").plan.robots[0].drive
    assert (drive.kind, drive.odometry, drive.max_steering_angle) == ("ackermann", "ground_truth", 0.3)
    assert (tmp_path / "a" / "odom" / "car.csv").read_bytes() == (tmp_path / "b" / "odom" / "car.csv").read_bytes()


def test_naming_other_driven_wheels_keeps_the_steering(tmp_path):
    """All four wheels driven (a 4WD car): still a car, its front wheels at their own speeds."""
    path = scenario(tmp_path, CAR, "{left_joints: [front_left_wheel_joint, rear_left_wheel_joint], "
                                   "right_joints: [front_right_wheel_joint, rear_right_wheel_joint]}",
                    "      - {at: 0.5, linear: 0.5, angular: 0.25, for: 3}\n")
    drive = prepare(path).plan.robots[0].drive
    assert drive.kind == "ackermann" and drive.steering_joints == ("left_steering_joint", "right_steering_joint")
    assert drive.left_joints == ("front_left_wheel_joint", "rear_left_wheel_joint")
    done = invoke(["run", path, "--out", tmp_path / "run", "--quiet"])
    assert done.exit_code == 0, done.stderr
