"""`mobot scan` and the protocol's ``scan`` op: the latest reading of a robot's sensor."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from mobot_cli.cli import invoke
from mobot_cli.errors import LiveWorldError
from mobot_cli.live.client import Client
from mobot_cli.live.server import LiveServer
from mobot_cli.plan import SensorSpec
from tests.sim.sensor_world import lidar, one_robot, planned, room_distance

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def endpoint(tmp_path_factory):
    """A live world in this process (in --fast) whose robot has a lidar, an IMU and a bumper."""
    folder = tmp_path_factory.mktemp("scan")
    sensors = (lidar(xyz=(0.0, 0.0, 0.3), range_max=3.0),
               SensorSpec(name="imu", kind="imu", link="base_link", every=4),
               SensorSpec(name="bumper", kind="contact", link="base_link", every=24))
    plan, _ = planned(one_robot(folder, duration=1000.0), "mobot", *sensors)
    where = f"ipc://{tempfile.mkdtemp(prefix='mobot-s-')}/s.sock"
    server = LiveServer(plan, where, rtf=None)
    thread = threading.Thread(target=server.serve, daemon=True)
    thread.start()
    deadline = time.monotonic() + 60
    while True:
        try:
            with Client(where, timeout=0.5) as client:
                if client.ping()["step"] > 30:
                    break
        except LiveWorldError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.05)
    yield where
    with Client(where) as client:
        client.stop()
    thread.join(timeout=30)


def test_scan_replies_with_the_latest_ranges(endpoint):
    done = invoke(["scan", "mobot", "--json", "--endpoint", endpoint])
    assert done.exit_code == 0, done.stderr
    reply = json.loads(done.stdout)
    assert (reply["sensor"], reply["kind"], reply["topic"], reply["frame_id"]) == \
        ("scan", "lidar", "/mobot/scan", "mobot/base_link_scan")
    assert reply["angle_increment"] == 2 * math.pi / 359 and len(reply["ranges"]) == 360
    with Client(endpoint) as client:
        truth = client.odom("mobot")["truth"]
    yaw = truth["yaw"] + np.array([reply["angle_min"] + i * reply["angle_increment"] for i in range(360)])
    exact = room_distance((truth["x"], truth["y"], 0.35), np.stack([np.cos(yaw), np.sin(yaw), 0 * yaw], axis=1))
    got = np.array([math.inf if r is None else r for r in reply["ranges"]])
    near = exact <= 3.0
    assert np.max(np.abs(got[near] - exact[near])) < 0.01 and np.all(np.isinf(got[~near]))


def test_scan_prints_one_line_and_reads_other_sensors(endpoint):
    done = invoke(["scan", "mobot", "--endpoint", endpoint])
    assert done.exit_code == 0 and done.stdout.count("\n") == 1
    assert "mobot/scan (lidar, /mobot/scan) 360 beams over -180.0..180.0 deg:" in done.stdout
    assert "returns, nearest" in done.stdout
    imu = json.loads(invoke(["scan", "mobot", "--sensor", "imu", "--json", "--endpoint", endpoint]).stdout)
    assert imu["linear_acceleration"][2] == pytest.approx(9.81, abs=0.05)
    line = invoke(["scan", "mobot", "-s", "bumper", "--endpoint", endpoint]).stdout
    assert line.endswith("(contact, /mobot/bumper) no contact\n")


def test_scan_refusals_name_what_is_wrong(endpoint):
    # Generous timeouts: a busy machine may answer slowly, and only a hang should fail here.
    unknown = invoke(["scan", "mobot", "--sensor", "sonar", "--endpoint", endpoint, "--timeout", "120"])
    assert unknown.exit_code == 2 and "NOT_FOUND" in unknown.stderr
    assert "robot 'mobot' has no sensor 'sonar'; it has scan, imu, bumper" in unknown.stderr
    missing = invoke(["scan", "ghost", "--endpoint", endpoint, "--timeout", "120"])
    assert missing.exit_code == 2 and "no robot named 'ghost'" in missing.stderr
    with Client(endpoint, timeout=120) as client:
        plain = ('<robot name="plain"><link name="base_link"><collision><geometry><box size="0.2 0.2 0.1"/>'
                 '</geometry></collision><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" '
                 'ixy="0" ixz="0" iyz="0"/></inertial></link></robot>')
        client.spawn("plain", urdf=plain, pose={"x": -2.0, "y": -1.0})
        reply = client.call("scan", name="plain")
    assert (reply["ok"], reply["result"], reply["message"]) == (False, "NOT_FOUND", "robot 'plain' has no sensors")


def test_scan_follow_prints_each_new_reading(endpoint):
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    process = subprocess.Popen([sys.executable, "-m", "mobot_cli", "scan", "mobot", "--follow", "--json",
                                "--rate", "50", "--endpoint", endpoint], cwd=REPO, env=env,
                               stdout=subprocess.PIPE, text=True)
    try:
        lines = [json.loads(process.stdout.readline()) for _ in range(3)]
    finally:
        process.kill()
        process.wait()
    steps = [line["step"] for line in lines]
    assert steps == sorted(set(steps)) and all((s - steps[0]) % 24 == 0 for s in steps)


def test_scan_reads_a_range_sensor_of_a_spawned_robot(endpoint):
    """Last in this file: the box it spawns is in the lidar's view."""
    ranger = (REPO / "tests" / "assets" / "sensors" / "range.urdf").read_text()
    with Client(endpoint, timeout=120) as client:
        client.spawn("ranger", urdf=ranger, pose={"x": 1.0, "y": -1.5})
        deadline = time.monotonic() + 60
        while not (reply := client.call("scan", name="ranger", sensor="ir_front"))["ok"]:
            assert time.monotonic() < deadline, reply
            time.sleep(0.05)
    assert (reply["kind"], reply["topic"], reply["radiation_type"]) == ("range", "/ranger/ir/front", "infrared")
    assert (reply["min_range"], reply["max_range"], reply["field_of_view"]) == (0.02, 4.0, 0.0)
    assert reply["range"] == pytest.approx(3.0 - 1.1, abs=0.01)  # the east wall, 1.9 m ahead of its ray
    line = invoke(["scan", "ranger", "-s", "sonar_back", "--endpoint", endpoint, "--timeout", "120"]).stdout
    assert line.endswith("ranger/sonar_back (range, /ranger/sonar/back) 1.000 m (ultrasound, 0.03..1 m)\n")
