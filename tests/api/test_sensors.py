"""Sensor readings through the Python API: the latest scan, the run folder's scans, a wall follower."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from mcap.reader import make_reader

from mobot_cli.api import Simulation
from mobot_cli.errors import MobotError
from mobot_cli.run import execute
from mobot_cli.scenario.prepare import prepare
from tests.sim.sensor_world import HALF_X, HALF_Y, ROOM_SDF, room_scenario

LIDAR = {"lidar": "true"}
NOISE = 0.01 + 0.01  # the bundled lidar's noise stddev and range resolution, as a tolerance


def lidar_scenario(folder, duration=3.0):
    """The room with the bundled mobot (lidar at 10 Hz, every 24 steps) driving an arc."""
    robots = ("  - name: r\n    description: mobot\n    args: {lidar: 'true'}\n"
              "    pose: {x: -1.0, y: 0.5, yaw: 0.2}\n    commands:\n"
              "      - {at: 0.25, linear: 0.4, angular: 0.3}\n      - {at: 1.5, linear: 0.2, angular: -0.5}\n")
    return room_scenario(folder, robots, duration, extra="log: {formats: [csv, mcap]}\n")


def test_reading_scans_in_a_loop_leaves_mobot_runs_files_byte_for_byte(tmp_path):
    path = lidar_scenario(tmp_path)
    prepared = prepare(path)
    execute(prepared.plan, prepared.resolved_yaml, tmp_path / "run")
    script = {c.step: (c.linear, c.angular) for c in prepared.plan.robots[0].commands}
    seen = []
    with Simulation.open(path, out=tmp_path / "api", overrides=["robots.r.commands=[]"]) as sim:
        while sim.step_count < prepared.plan.total_steps:
            if sim.step_count in script:
                sim.command("r", *script[sim.step_count])
            scan = sim.scan("r")
            seen.append((sim.step_count, scan.step))
            sim.step(6)
    bags = sorted(p.relative_to(tmp_path / "run").as_posix() for p in (tmp_path / "run" / "bag").glob("*.mcap"))
    assert bags
    for name in ("odom/r.csv", "sensors/r/lidar.npy", "sensors/r/lidar.json", *bags):
        assert (tmp_path / "api" / name).read_bytes() == (tmp_path / "run" / name).read_bytes(), name
    # Every 6 steps a look at the scan: the latest one, taken at the step the world is at when due.
    assert seen[:6] == [(0, 0), (6, 0), (12, 0), (18, 0), (24, 24), (30, 24)]
    assert all(now - 24 < taken <= now for now, taken in seen)


def test_a_robot_deleted_after_its_scan_was_read_leaves_a_whole_bag(tmp_path):
    """A scan read ahead of its step's tick is recorded at the tick only if its robot is still there."""
    path = lidar_scenario(tmp_path, duration=1.0)
    with Simulation.open(path, out=tmp_path / "api") as sim:
        sim.step(24)
        assert sim.scan("r").step == 24  # read ahead of step 24's tick
        sim.delete("r")
        sim.step(24)
    rows = np.load(tmp_path / "api" / "sensors" / "r" / "lidar.npy")
    assert list(rows["t"]) == [0.0]  # the scan read at step 24 was of a robot gone before the tick
    with open(next((tmp_path / "api" / "bag").glob("*.mcap")), "rb") as bag:
        scans = [m.log_time for _, c, m in make_reader(bag).iter_messages() if c.topic == "/r/scan"]
    assert scans == [0]


def test_the_scan_is_the_run_folders_row_and_sees_the_walls(tmp_path):
    (tmp_path / "room.sdf").write_text(ROOM_SDF)
    with Simulation.open(tmp_path / "room.sdf", out=tmp_path / "r", seed=5) as sim:
        sim.spawn("r", "mobot", x=0.5, y=-0.5, args=LIDAR)
        assert sim.sensors("r") == {"lidar": "lidar"}
        sim.run_for(0.5)
        scan = sim.scan("r")
        state = sim.state("r")
    assert scan.step == 120 and scan.t == 0.5 and scan.frame == "lidar_link"
    assert scan.ranges.shape == scan.angles.shape == (360,) and (scan.range_min, scan.range_max) == (0.12, 12.0)
    # Straight ahead (+x), left (+y), behind and right: the room's inner faces from where it stands.
    x, y = state.true_x, state.true_y
    assert scan.toward(0.0) == pytest.approx(HALF_X - x, abs=NOISE)
    assert scan.toward(math.pi / 2) == pytest.approx(HALF_Y - y, abs=NOISE)
    assert scan.toward(math.pi) == pytest.approx(HALF_X + x, abs=NOISE)
    assert scan.toward(-math.pi / 2) == pytest.approx(HALF_Y + y, abs=NOISE)
    rows = np.load(tmp_path / "r" / "sensors" / "r" / "lidar.npy")
    (row,) = rows[rows["t"] == 0.5]
    assert np.array_equal(row["ranges"], scan.ranges)


def test_a_wall_follower_holds_its_distance(tmp_path):
    """Follow the right-hand wall (y = -2) at 0.5 m on the lidar alone, from 0.8 m and a bad heading."""
    (tmp_path / "room.sdf").write_text(ROOM_SDF)
    with Simulation.open(tmp_path / "room.sdf", seed=2) as sim:
        sim.spawn("r", "mobot", x=-2.3, y=-1.2, yaw=0.25, args=LIDAR)
        sim.run_for(0.5)
        side = []
        while sim.t < 12.0:
            scan = sim.scan("r")
            assert scan.step == sim.step_count  # a fresh scan every 0.1 s control period
            right = (scan.angles > -2.1) & (scan.angles < -1.05)  # a sector around -90 deg
            nearest = int(np.argmin(np.where(right, scan.ranges, np.inf)))
            distance, bearing = float(scan.ranges[nearest]), float(scan.angles[nearest])
            side.append(distance)
            sim.command("r", 0.3, -2.0 * (distance - 0.5) + 2.0 * (bearing + math.pi / 2))
            sim.run_for(0.1)
        state = sim.state("r")
        last = sim.scan("r")
    assert state.true_x > 0.9  # it went 3.2 m and more along the wall (0.3 m/s for 11.5 s: 3.45 m)
    assert state.true_y == pytest.approx(-HALF_Y + 0.5, abs=0.04)  # held at 0.5 m from the wall
    assert abs(math.remainder(state.true_yaw, math.tau)) < 0.1  # parallel to it
    assert side[0] == pytest.approx(0.8, abs=0.04)  # started 0.8 m off (a minimum of noisy beams: low)
    assert max(side[-30:]) - min(side[-30:]) < 0.05  # the last 3 s steady
    assert last.toward(-math.pi / 2) == pytest.approx(state.true_y + HALF_Y, abs=NOISE + 0.01)
    assert last.toward(0.0) == pytest.approx(HALF_X - state.true_x, abs=0.05)  # the wall ahead, too


def test_sensor_mistakes_are_mobot_errors(tmp_path):
    with Simulation.open("empty") as sim:
        sim.spawn("plain", "mobot")
        sim.spawn("seeing", "mobot", y=2.0, args=LIDAR)
        assert sim.sensors("plain") == {}
        with pytest.raises(MobotError, match="robot 'plain' has no lidar"):
            sim.scan("plain")
        with pytest.raises(MobotError, match="no lidar named 'scan'") as info:
            sim.scan("seeing", "scan")
        assert info.value.hint == "It has: lidar."
        with pytest.raises(MobotError, match="no robot named 'seing'"):
            sim.scan("seing")
        # Nothing returns in an empty world: +inf, and finite() gives range_max.
        scan = sim.scan("seeing")
        assert scan.step == 0 and np.isinf(scan.ranges).all() and (scan.finite() == 12.0).all()
        assert sim.reading("seeing").data.ranges.shape == (1, 360)
        assert sim.scan("seeing") is scan  # made once per reading, and read-only
        with pytest.raises(ValueError, match="read-only"):
            scan.ranges[0] = 1.0
        sim.step(24)
        assert sim.scan("seeing").step == 24


def _scan(ranges, angles):
    from mobot_cli.api import Scan

    return Scan("r", "lidar", 0, 0.0, np.asarray(angles), np.zeros(1), np.asarray(ranges, np.float32),
                0.12, 12.0, "f")


@settings(max_examples=200, deadline=None)
@given(st.lists(st.one_of(st.floats(0.12, 12.0), st.just(math.inf)), min_size=2, max_size=50),
       st.floats(-10.0, 10.0))
def test_finite_and_toward_on_any_scan(values, angle):
    n = len(values)
    angles = -math.pi + 2 * math.pi * np.arange(n) / n  # a full circle, as a 360-degree lidar's
    scan = _scan(values, angles)
    finite = scan.finite()
    assert np.isfinite(finite).all() and (finite >= 0).all() and (finite <= np.float32(12.0)).all()
    assert np.array_equal(finite[np.isfinite(scan.ranges)], scan.ranges[np.isfinite(scan.ranges)])
    # toward() takes the beam nearest to the angle, the circle wrapped: no other beam is nearer.
    got = scan.toward(angle)
    gaps = np.abs(np.remainder(angles - angle + math.pi, 2 * math.pi) - math.pi)
    assert got in scan.ranges[gaps <= gaps.min() + 1e-9]  # (a tie: either beam; inf == inf in NumPy)
