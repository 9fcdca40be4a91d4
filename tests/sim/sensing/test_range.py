"""Range sensors in a run: one distance per reading against a wall at a known distance, the
plugins' noise, sensor_msgs/Range in the bag (read by the independent mcap readers), the run
folder's CSV, the Python API, and the same readings for the same seed."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from mobot_cli.api import Simulation
from mobot_cli.cli import invoke
from mobot_cli.errors import MobotError
from tests.record.test_sensor_records import _messages
from tests.sim.sensor_world import HALF_X, room_scenario

RANGER = Path(__file__).resolve().parents[2] / "assets" / "sensors" / "range.urdf"
X = 1.0  # the robot's x: its sensors sit 0.1 m ahead of it, facing the east wall
WALL = HALF_X - (X + 0.1)  # 1.9 m from the forward-facing sensors
NOISE = 0.05  # ir_noisy's <gaussianNoise>


def _scenario(folder: Path) -> Path:
    robots = f"  - name: r\n    description: {RANGER}\n    pose: {{x: {X}, y: 0.0}}\n"
    return room_scenario(folder, robots, 1.0, extra="log: {formats: [csv, mcap]}\n")


def _run(folder: Path, seed: int) -> Path:
    out = folder / f"run-{seed}"
    done = invoke(["run", str(_scenario(folder)), "--out", str(out), "--quiet", "--seed", str(seed)])
    assert done.exit_code == 0, done.stderr
    return out


def _csv(out: Path, sensor: str) -> np.ndarray:
    return np.genfromtxt(out / "sensors" / "r" / f"{sensor}.csv", delimiter=",", names=True)


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("range")
    return _run(folder, 11), _run(folder, 11), _run(folder, 12)


def test_a_single_ray_and_the_nearest_ray_of_a_cone_read_the_wall_within_a_centimetre(runs):
    out = runs[0]
    ir, sonar, back = _csv(out, "ir_front"), _csv(out, "sonar_left"), _csv(out, "sonar_back")
    assert len(ir) == 21 and len(sonar) == 11 and len(back) == 241  # 20 Hz, 10 Hz, every step for 1 s
    assert np.max(np.abs(ir["range"] - WALL)) < 0.01
    assert np.max(np.abs(_csv(out, "sonar_cone")["range"] - WALL)) < 0.01  # Gazebo's sonar, its cone forward
    # turned 0.5 rad, 0.15 either side: its nearest ray is 0.35 rad off the wall's normal
    assert np.max(np.abs(sonar["range"] - WALL / math.cos(0.35))) < 0.01
    assert np.all(back["range"] == 1.0)  # the west wall is 3.9 m behind: nothing within 1 m reads max


def test_the_plugins_gaussian_noise_has_its_statistics_and_stays_within_the_limits(runs):
    noisy = _csv(runs[0], "ir_noisy")["range"]
    assert len(noisy) == 241
    assert abs(noisy.mean() - WALL) < 4 * NOISE / math.sqrt(len(noisy))
    assert noisy.std(ddof=1) == pytest.approx(NOISE, rel=0.15)
    assert len(set(noisy.tolist())) > 200 and np.all((noisy >= 0.02) & (noisy <= 4.0))


def test_same_seed_same_readings_and_another_seed_others(runs):
    first, again, other = runs
    for name in ("sensors/r/ir_noisy.csv", "sensors/r/sonar_left.csv", "bag/bag.mcap"):
        assert (first / name).read_bytes() == (again / name).read_bytes(), name
    assert (first / "sensors/r/ir_noisy.csv").read_bytes() != (other / "sensors/r/ir_noisy.csv").read_bytes()
    assert (first / "sensors/r/ir_front.csv").read_bytes() == (other / "sensors/r/ir_front.csv").read_bytes()


def test_the_bag_holds_sensor_msgs_range_as_the_plugins_fill_it(runs):
    out = runs[0]
    got: dict[str, list] = {}
    for topic, msg in _messages(out / "bag" / "bag.mcap"):
        got.setdefault(topic, []).append(msg)
    ir, sonar, noisy = got["/r/ir/front"], got["/r/sonar/left"], got["/r/ir/noisy"]
    assert len(ir) == 21 and len(sonar) == 11 and len(noisy) == 241
    assert (ir[0].radiation_type, ir[0].field_of_view, ir[0].min_range, ir[0].max_range, ir[0].variance) == \
        (1, 0.0, np.float32(0.02), 4.0, 0.0)  # INFRARED; gazebo_ros: the wider axis, 0 for one ray
    assert (sonar[0].radiation_type, sonar[0].field_of_view, sonar[0].max_range) == (0, np.float32(0.3), 3.0)
    assert sonar[0].header.frame_id == "r/base_link_sonar_left"  # its pose in the link: a frame of its own
    assert noisy[0].variance == np.float32(NOISE ** 2)
    for msgs, name in ((ir, "ir_front"), (sonar, "sonar_left"), (noisy, "ir_noisy")):
        rows = _csv(out, name)
        for msg, row in zip(msgs, rows):  # the CSV has 6 decimals
            assert msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9 == pytest.approx(row["t"], abs=1e-6)
            assert msg.range == pytest.approx(row["range"], abs=2e-6)
    assert len(got["/r/imu/data"]) == 61  # hector's IMU plugin at 60 Hz


def test_the_api_gives_the_latest_range_as_the_run_folder_has_it(runs, tmp_path):
    with Simulation.open(_scenario(tmp_path), seed=11) as sim:
        first = sim.range("r", "ir_front")  # read as the world is at step 0
        assert first.step == 0 and abs(first.range - WALL) < 0.01
        with pytest.raises(MobotError, match="has 5 ranges: name the one you mean"):
            sim.range("r")
        sim.step(240)
        assert sim.sensors("r")["sonar_left"] == "range" and sim.sensors("r")["imu_controller"] == "imu"
        reading = sim.range("r", "ir_noisy")
        sonar = sim.range("r", "sonar_left")
    last = _csv(runs[0], "ir_noisy")[-1]
    assert (reading.step, reading.t) == (240, 1.0)
    assert reading.range == pytest.approx(last["range"], abs=1e-6)
    assert (reading.radiation, reading.min_range, reading.max_range) == ("infrared", 0.02, 4.0)
    assert sonar.range == pytest.approx(WALL / math.cos(0.35), abs=0.01) and sonar.field_of_view == 0.3
