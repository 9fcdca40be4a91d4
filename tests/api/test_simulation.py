"""The Python API: your code steps the world on the timeline `mobot run` plays."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from mobot_cli.api import Simulation, Status
from mobot_cli.cli import invoke
from mobot_cli.errors import SpawnError, UsageError
from mobot_cli.scenario.prepare import prepare

REPO = Path(__file__).resolve().parents[2]
QUICKSTART = REPO / "scenarios" / "quickstart.yaml"
FLEET = REPO / "scenarios" / "fleet.yaml"


@pytest.mark.parametrize("scenario", [QUICKSTART, FLEET], ids=["quickstart", "fleet"])
def test_sending_a_scripts_commands_reproduces_mobot_run_byte_for_byte(tmp_path, scenario):
    plan = prepare(scenario).plan
    script: dict[int, list] = {}
    for robot in plan.robots:
        for cmd in robot.commands:
            script.setdefault(cmd.step, []).append((robot.name, cmd.linear, cmd.angular))
    assert invoke(["run", scenario, "--out", tmp_path / "run", "--quiet"]).exit_code == 0
    silent = [f"robots.{index}.commands=[]" for index in range(len(prepare(scenario).scenario.robots))]
    with Simulation.open(scenario, out=tmp_path / "api", overrides=silent) as sim:
        while sim.step_count < plan.total_steps:
            for name, linear, angular in script.get(sim.step_count, ()):
                sim.command(name, linear, angular)
            sim.step()
    assert sim.record.status is Status.OK and sim.record.steps == plan.total_steps
    for robot in plan.robots:
        ran = (tmp_path / "run" / "odom" / f"{robot.name}.csv").read_bytes()
        assert (tmp_path / "api" / "odom" / f"{robot.name}.csv").read_bytes() == ran, robot.name


def test_a_go_to_goal_controller_in_a_few_lines(tmp_path):
    """The README's example: drive the bundled robot to (1.5, 0.5) on its own odometry."""
    goal = (1.5, 0.5)
    with Simulation.open("empty", out=tmp_path / "goal") as sim:
        sim.spawn("r1", "mobot")
        sim.run_for(0.5)  # let it settle
        for _ in range(400):  # 10 Hz control for at most 40 s
            s = sim.state("r1")
            dx, dy = goal[0] - s.odom_x, goal[1] - s.odom_y
            if math.hypot(dx, dy) < 0.05:
                break
            heading = math.remainder(math.atan2(dy, dx) - s.odom_yaw, math.tau)
            sim.command("r1", linear=0.3 * max(0.0, math.cos(heading)), angular=1.5 * heading)
            sim.run_for(0.1)
        sim.command("r1", 0.0, 0.0)
        sim.run_for(0.5)
        final = sim.state("r1")
    assert math.hypot(final.true_x - goal[0], final.true_y - goal[1]) < 0.1
    assert sim.record.robots["r1"].distance == pytest.approx(math.hypot(*goal), rel=0.15)
    assert (tmp_path / "goal" / "odom" / "r1.csv").is_file() and (tmp_path / "goal" / "trajectory.png").is_file()


def test_spawn_delete_and_time(tmp_path):
    with Simulation.open("empty") as sim:
        assert (sim.t, sim.robots) == (0.0, [])
        sim.spawn("a", "mobot", x=1.0, yaw=math.pi / 2)
        sim.step(240)
        assert sim.step_count == 240 and sim.t == 1.0
        state = sim.state("a")
        assert (state.true_x, state.true_yaw) == (pytest.approx(1.0, abs=2e-3), pytest.approx(math.pi / 2, abs=2e-3))
        sim.command("a", 0.2, duration=1.0)
        sim.run_for(2.0)
        assert sim.state("a").cmd_linear == 0.0 and sim.state("a").true_y == pytest.approx(0.2, abs=0.03)
        sim.delete("a")
        assert sim.robots == []
    assert sim.record is None  # nothing recorded without out


def test_bad_calls_are_mobot_errors():
    with Simulation.open("empty") as sim:
        sim.spawn("a", "mobot")
        with pytest.raises(UsageError, match="no robot named 'b'"):
            sim.state("b")
        with pytest.raises(UsageError, match="whole number of steps"):
            sim.step(-1)
        with pytest.raises(UsageError, match="not a valid robot name"):
            sim.spawn("1bad", "mobot")
        with pytest.raises(SpawnError, match="already in the world"):
            sim.spawn("a", "mobot", x=3.0)
        with pytest.raises(SpawnError):
            sim.spawn("b", "mobot")  # on top of 'a'
    with pytest.raises(UsageError, match="closed"):
        sim.step()


def test_an_exception_in_your_loop_is_recorded(tmp_path):
    with pytest.raises(RuntimeError):
        with Simulation.open(QUICKSTART, out=tmp_path / "r") as sim:
            sim.step(10)
            raise RuntimeError("my controller broke")
    assert sim.record.status is Status.ERROR and sim.record.error == "my controller broke"


def test_goto_drives_with_the_goal_controller_and_reports_how_it_ended():
    with Simulation.open("house") as sim:
        sim.spawn("r", "mobot", x=-3.0, y=-2.5)
        assert sim.goal_status("r") is None
        sim.run_for(0.5)
        sim.goto("r", -1.5, -3.5, yaw=1.57, localization="ground_truth")
        while sim.goal_status("r") == "running" and sim.t < 30:
            sim.run_for(0.5)
        assert sim.goal_status("r") == "reached"
        s = sim.state("r")
        assert math.hypot(s.true_x + 1.5, s.true_y + 3.5) < 0.05 and abs(s.true_yaw - 1.57) < 0.06
        with pytest.raises(UsageError, match=r"goto 'r': goto \(0, 0\) is inside world model 'coffee_table'"):
            sim.goto("r", 0.0, 0.0)
        with pytest.raises(UsageError, match=r"goto 'r': bogus: Extra inputs are not permitted"):
            sim.goto("r", 1.0, 0.0, bogus=1)
        sim.goto("r", -3.0, -2.5)
        sim.run_for(1.0)
        sim.command("r", 0.0, 0.0)  # a command takes over
        assert sim.goal_status("r") == "cancelled"


def test_a_deleted_robots_name_and_namespace_can_be_taken_again():
    with Simulation.open("empty") as sim:
        sim.spawn("a", "mobot")
        sim.delete("a")
        sim.spawn("a", "mobot", x=2.0)  # its namespace /a is free again
        assert sim.robots == ["a"] and sim.state("a").true_x == pytest.approx(2.0, abs=1e-6)
        with pytest.raises(SpawnError, match="already in the world"):
            sim.spawn("a", "mobot", x=-2.0)
