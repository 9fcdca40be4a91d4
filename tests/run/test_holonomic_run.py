"""Sideways commands in a scenario: `mobot run` drives a mecanum base by ``linear_y``, the resolved
scenario reruns to the same bytes, and ``drive.type`` picks the drive kind."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from mobot_cli.cli import invoke
from mobot_cli.scenario.prepare import prepare

ROBOTS = Path(__file__).resolve().parents[1] / "sim" / "robots"


def scenario(tmp_path: Path, description: str, *, args: str = "{}", drive: str = "", commands: str = "",
             engine: str = "bullet") -> Path:
    path = tmp_path / "s.yaml"
    where = ROBOTS / description if "." in description else description  # a file, or a bundled name
    path.write_text(f"version: 1\nduration: 6\nsettle: 0.5\nphysics: {{engine: {engine}}}\nrobots:\n"
                    f"  - name: m\n    description: {where}\n    args: {args}\n"
                    + (f"    drive: {drive}\n" if drive else "")
                    + (f"    commands:\n{commands}" if commands else ""))
    return path


SIDEWAYS = ("      - {at: 1.0, linear_y: 0.25, for: 4.0}\n")


@pytest.mark.parametrize("engine", ["bullet", "kinematic"])
def test_a_scenario_moves_a_mecanum_base_sideways_and_reruns_identically(tmp_path, engine):
    path = scenario(tmp_path, "mecanum", args="{drive: plugin}", commands=SIDEWAYS, engine=engine)
    first = invoke(["run", path, "--out", tmp_path / "one", "--quiet"])
    assert first.exit_code == 0, first.stderr
    rows = list(csv.DictReader((tmp_path / "one" / "odom" / "m.csv").open()))
    end = rows[-1]
    assert float(end["true_y"]) - float(rows[0]["true_y"]) == pytest.approx(1.0, rel=0.02)
    assert abs(float(end["true_x"]) - float(rows[0]["true_x"])) < 0.01
    assert float(end["odom_y"]) == pytest.approx(1.0, rel=0.02)
    resolved = (tmp_path / "one" / "scenario.yaml").read_text()
    assert "type: holonomic" in resolved and "linear_y: 0.25" in resolved
    again = tmp_path / "again.yaml"
    again.write_text(resolved)
    second = invoke(["run", again, "--out", tmp_path / "two", "--quiet"])
    assert second.exit_code == 0, second.stderr
    assert (tmp_path / "two" / "odom" / "m.csv").read_bytes() == (tmp_path / "one" / "odom" / "m.csv").read_bytes()


def test_drive_type_holonomic_makes_a_four_wheel_base_mecanum(tmp_path):
    prepared = prepare(scenario(tmp_path, "skid4.urdf.xacro", drive="{type: holonomic}", commands=SIDEWAYS))
    drive = prepared.plan.robots[0].drive
    assert drive.kind == "mecanum" and drive.wheelbase == pytest.approx(0.5)
    assert drive.wheel_separation_multiplier == 1.0 and drive.twist_feedback is False
    again = tmp_path / "again.yaml"
    again.write_text(prepared.resolved_yaml)
    assert prepare(again).plan.robots[0].drive == drive


def test_drive_type_diff_drives_a_mecanum_base_as_skid_steer(tmp_path):
    prepared = prepare(scenario(tmp_path, "mecanum", args="{drive: plugin}", drive="{type: diff}"))
    drive = prepared.plan.robots[0].drive
    assert drive.kind == "diff" and drive.wheel_separation_multiplier > 1.0
    again = tmp_path / "again.yaml"
    again.write_text(prepared.resolved_yaml)
    assert prepare(again).plan.robots[0].drive == drive


def test_naming_other_wheels_keeps_a_detected_holonomic_kind(tmp_path):
    drive = ("{left_joints: [front_left_wheel_joint, rear_left_wheel_joint], "
             "right_joints: [front_right_wheel_joint, rear_right_wheel_joint], odometry: ground_truth}")
    prepared = prepare(scenario(tmp_path, "mecanum", args="{drive: rollers}", drive=drive))
    spec = prepared.plan.robots[0].drive
    assert spec.kind == "mecanum" and spec.odometry == "ground_truth" and spec.wheelbase == pytest.approx(0.4)


def test_the_bag_records_linear_y_in_cmd_vel_and_odom(tmp_path):
    from tests.record.test_bag import by_topic, messages

    path = scenario(tmp_path, "mecanum", args="{drive: plugin}", commands=SIDEWAYS)
    path.write_text(path.read_text().replace("duration: 6\n", "duration: 2\nlog: {formats: [csv, mcap]}\n"))
    done = invoke(["run", path, "--out", tmp_path / "bag", "--quiet"])
    assert done.exit_code == 0, done.stderr
    recorded = by_topic(messages(tmp_path / "bag" / "bag"), "/m/cmd_vel")
    cmds = [(m[3].linear.x, m[3].linear.y, m[3].angular.z) for m in recorded]
    assert cmds[0] == (0.0, 0.0, 0.0) and cmds[-1] == (0.0, 0.25, 0.0)
    odom = by_topic(messages(tmp_path / "bag" / "bag"), "/m/odom")[-1][3].twist.twist
    assert odom.linear.y == pytest.approx(0.25, abs=0.005) and odom.linear.x == pytest.approx(0.0, abs=0.005)
