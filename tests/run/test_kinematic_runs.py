"""The kinematic engine through every door: `mobot run`, sweeps, sensors, the live world."""

from __future__ import annotations

import csv
import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from mobot_cli.cli import invoke
from mobot_cli.plan import SensorSpec
from mobot_cli.sim.bullet.world import World
from mobot_cli.sim.engine import open_world
from tests.sim.sensor_world import lidar, one_robot, planned, room_distance

REPO = Path(__file__).resolve().parents[2]
SCENARIOS = sorted((REPO / "scenarios").glob("*.yaml"))
KINEMATIC = "physics.engine=kinematic"


def quiet(*args) -> int:
    done = invoke([str(a) for a in args])
    assert (done.stdout, done.stderr) == ("", ""), done
    return done.exit_code


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.stem)
def test_every_bundled_scenario_runs_kinematic_deterministically(path, tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    assert quiet("run", path, "--out", a, "--quiet", "--set", KINEMATIC) == 0
    assert quiet("run", path, "--out", b, "--quiet", "--set", KINEMATIC) == 0
    files = sorted(p.relative_to(a) for p in (a / "odom").iterdir())
    assert files
    for rel in files:
        assert (a / rel).read_bytes() == (b / rel).read_bytes(), rel
    summary = json.loads((a / "summary.json").read_text())
    assert summary["status"] == "ok"
    # The resolved scenario says which engine ran, and runs the same again.
    assert "engine: kinematic" in (a / "scenario.yaml").read_text()
    assert quiet("run", a / "scenario.yaml", "--out", tmp_path / "again", "--quiet") == 0
    assert (tmp_path / "again" / files[0]).read_bytes() == (a / files[0]).read_bytes()


def final(folder: Path, robot: str = "mobot") -> dict[str, float]:
    with (folder / "odom" / f"{robot}.csv").open() as f:
        return {k: float(v) for k, v in list(csv.DictReader(f))[-1].items()}


def test_quickstart_ends_where_the_physics_engine_ends_it(tmp_path):
    assert quiet("run", REPO / "scenarios" / "quickstart.yaml", "--out", tmp_path / "b", "--quiet") == 0
    assert quiet("run", REPO / "scenarios" / "quickstart.yaml", "--out", tmp_path / "k", "--quiet",
                 "--set", KINEMATIC) == 0
    b, k = final(tmp_path / "b"), final(tmp_path / "k")
    assert math.hypot(b["true_x"] - k["true_x"], b["true_y"] - k["true_y"]) < 0.05
    assert abs(b["true_yaw"] - k["true_yaw"]) < 0.01
    # No slip: the kinematic robot's encoders are its ground truth.
    assert (k["odom_x"], k["odom_y"], k["odom_yaw"]) \
        == pytest.approx((k["true_x"], k["true_y"], k["true_yaw"]), abs=1e-6)


def test_a_low_step_rate_is_allowed_and_exact(tmp_path):
    assert quiet("run", REPO / "scenarios" / "quickstart.yaml", "--out", tmp_path / "k", "--quiet",
                 "--set", KINEMATIC, "--set", "physics.rate_hz=10", "--set", "log.rate_hz=10") == 0
    end = final(tmp_path / "k")
    # 0.25 m/s for 4 s, a quarter turn (0.5 rad/s for 3.1 s at 10 Hz), 0.25 m/s for 3 s.
    yaw = 0.5 * 3.1
    assert (end["true_x"], end["true_y"], end["true_yaw"]) == pytest.approx(
        (1.0 + 0.75 * math.cos(yaw), 0.75 * math.sin(yaw), yaw), abs=1e-6)


def test_an_unknown_engine_is_a_located_error_with_a_suggestion(tmp_path):
    done = invoke(["run", str(REPO / "scenarios" / "quickstart.yaml"), "--out", str(tmp_path / "r"),
                   "--set", "physics.engine=kinematik"])
    assert done.exit_code == 2 and "Traceback" not in done.stderr
    assert "key 'physics.engine': unknown engine 'kinematik'. Did you mean 'kinematic'?" in done.stderr
    assert not (tmp_path / "r").exists()


def test_the_engine_is_a_sweep_axis(tmp_path):
    done = invoke(["sweep", str(REPO / "scenarios" / "quickstart.yaml"), "--grid", "physics.engine=bullet,kinematic",
                   "--jobs", "1", "--out", str(tmp_path / "s")])
    assert done.exit_code == 0, done.stderr
    with (tmp_path / "s" / "results.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert sorted(row["physics.engine"] for row in rows) == ["bullet", "kinematic"]
    assert all(row["status"] == "passed" for row in rows)


def test_a_lidar_reads_the_same_ranges_in_both_engines(tmp_path):
    """The kinematic robot drives 1 m; a physics robot spawned where it stopped reads the same."""
    sensor = lidar(xyz=(0.0, 0.0, 0.3), range_max=6.0, every=1)
    plan, _ = planned(one_robot(tmp_path, x=-1.0, y=0.25, yaw=0.0), "mobot", sensor)
    kin = dataclasses.replace(plan, physics=dataclasses.replace(plan.physics, engine="kinematic"))
    robot = plan.robots[0]
    robot = dataclasses.replace(robot, drive=dataclasses.replace(robot.drive, max_wheel_acceleration=None))
    with open_world(kin.physics, kin.world) as world:
        world.spawn(robot)
        world.set_command("mobot", 0.5, 0.0)
        for _ in range(2 * kin.physics.rate_hz):
            world.step()
        (moved,) = world.sense([("mobot", "scan")])
        assert world.read("mobot").true_x == pytest.approx(0.0, abs=1e-9)
    there = dataclasses.replace(robot, pose=dataclasses.replace(robot.pose, xyz=(0.0, 0.25, 0.0)))
    with World(plan.physics, plan.world) as world:
        world.spawn(there)
        (spawned,) = world.sense([("mobot", "scan")])
    assert moved.position == pytest.approx(spawned.position, abs=1e-6)
    np.testing.assert_allclose(moved.ranges, spawned.ranges, atol=1e-5)
    exact = room_distance(moved.position, moved.beams.directions)
    near = exact <= 6.0
    assert np.max(np.abs(moved.ranges.reshape(-1)[near] - exact[near])) < 0.01


def kinematic_world(plan):
    plan = dataclasses.replace(plan, physics=dataclasses.replace(plan.physics, engine="kinematic"))
    world = open_world(plan.physics, plan.world, seed=plan.seed)
    for robot in plan.robots:
        world.spawn(robot)
    return world


def test_an_imu_reads_the_kinematic_turn_rate_and_centripetal_acceleration(tmp_path):
    """Spinning in place at 1 rad/s with the IMU 0.2 m ahead of the axle: w = 1, a_x = -0.2 m/s^2."""
    imu = SensorSpec(name="imu", kind="imu", link="base_link", every=12, xyz=(0.2, 0.0, 0.0))
    plan, _ = planned(one_robot(tmp_path, x=0.0, y=0.0, yaw=0.0), "mobot", imu)
    with kinematic_world(plan) as world:
        world.set_command("mobot", 0.0, 1.0)
        readings = []
        for step in range(1, 481):
            world.step()
            if step % 12 == 0:
                readings.extend(world.sense([("mobot", "imu")]))
    late = readings[-10:]
    assert all(r.angular_velocity[2] == pytest.approx(1.0, abs=1e-9) for r in late)
    assert all(r.linear_acceleration[0] == pytest.approx(-0.2, abs=0.01) for r in late)
    assert all(r.linear_acceleration[2] == pytest.approx(9.81, abs=1e-9) for r in late)


def test_a_bumper_feels_the_wall_the_robot_stopped_at(tmp_path):
    bumper = SensorSpec(name="bumper", kind="contact", link="base_link", every=12)
    plan, _ = planned(one_robot(tmp_path, x=2.5, y=0.0, yaw=0.0), "mobot", bumper)
    with kinematic_world(plan) as world:
        (standing,) = world.sense([("mobot", "bumper")])
        world.set_command("mobot", 0.4, 0.0)
        for _ in range(480):
            world.step()
        (pushing,) = world.sense([("mobot", "bumper")])
        assert world.read("mobot").collisions == 1
    assert standing.contacts == ()
    assert pushing.contacts and all("walls" in c.other for c in pushing.contacts)
    assert all(c.normal[0] < -0.9 for c in pushing.contacts)  # the wall's normal (-x); no forces here
