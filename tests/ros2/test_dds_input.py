"""ROS 2 input cannot stop the world: a participant on the domain publishes NaN, inf, 1e308 and
broken CDR to a robot's cmd_vel (tests/ros2/dds_peer.py `send`, a real DDS participant on
loopback). Each sample is dropped and counted, the robot keeps finite odometry, the run ends 0
with summary.json, and a good sample after them still drives.
"""

from __future__ import annotations

import json
import math
import re
import struct
import subprocess
import sys

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.live.live_server import LiveProcess
from tests.ros2.test_dds import PEER, REPO, WORLD, peer, ros_env  # noqa: F401 - ros_env: autouse fixture

pytest.importorskip("cyclonedds")

HEADER = b"\x00\x01\x00\x00"  # CDR little-endian encapsulation
MALFORMED = "not a little-endian CDR Twist"


def twist(linear: float, angular: float) -> str:
    return (HEADER + struct.pack("<6d", linear, 0.0, 0.0, 0.0, 0.0, angular)).hex()


BAD = {  # payload -> why it is dropped
    twist(math.nan, 0.0): "not finite",
    twist(0.0, math.inf): "not finite",
    twist(-math.inf, math.nan): "not finite",
    twist(1e308, 0.0): "beyond 100 m/s or 100 rad/s",
    twist(0.0, -1e5): "beyond 100 m/s or 100 rad/s",
    (HEADER + bytes(8)).hex(): MALFORMED,  # truncated
    ("0001" + "0000" + struct.pack("<6d", *[0.1] * 6).hex())[:-8]: MALFORMED,  # 4 bytes short
    ("0000" + "0000" + struct.pack(">6d", 0.1, 0, 0, 0, 0, 0).hex()): MALFORMED,  # big-endian
    twist(0.1, 0.0) + "ffffffff" * 64: MALFORMED,  # a length no Twist has
}
GOOD = twist(0.2, 0.1)


def test_bad_cmd_vel_samples_are_dropped_and_counted_and_the_live_world_goes_on(tmp_path):
    scenario = tmp_path / "world.yaml"
    scenario.write_text(WORLD.format(ros2=""))
    out = tmp_path / "out"
    live = LiveProcess(str(scenario), "--ros2", cache_dir=tmp_path / "cache", out=out)
    try:
        sent = peer("send", "rt/r1/cmd_vel", *BAD, GOOD)
        with live.client() as client:
            odom = client.odom("r1")
        code = live.signal()
        output = live.output()
    finally:
        live.kill()
    assert sent["matched"] == 1 and sent["written"][-1]
    # Cyclone refuses some broken payloads itself, at the writer (truncated ones) or the reader:
    # those never reach mobot. Every well-formed one does, and is counted.
    malformed = [why for why, written in zip(BAD.values(), sent["written"]) if written].count(MALFORMED)
    assert malformed >= 1, sent
    assert odom["cmd"] == {"linear": 0.2, "angular": 0.1}  # the good one after them all still drives
    assert all(math.isfinite(v) for part in ("truth", "odom") for v in odom[part].values()
               if isinstance(v, float)), odom
    assert code == 0, output
    summary = json.loads((out / "summary.json").read_text())
    [line] = [n for n in summary["notices"] if n.startswith("ROS 2:")]
    found = re.fullmatch(r"ROS 2: (\d+) sample\(s\) on /r1/cmd_vel dropped \(2 beyond 100 m/s or 100 rad/s, "
                         r"(\d) not a little-endian CDR Twist, 3 not finite\); the world went on", line)
    assert found and 1 <= int(found.group(2)) <= malformed, line
    assert int(found.group(1)) == 5 + int(found.group(2))
    assert f"{found.group(1)} cmd_vel sample(s) refused" in output
    assert "Traceback" not in output


def test_a_nan_cmd_vel_during_mobot_run_leaves_a_finished_run(tmp_path):
    scenario = tmp_path / "world.yaml"
    scenario.write_text(WORLD.format(ros2="").replace("duration: 1.0", "duration: 20.0"))
    out = tmp_path / "run"
    run = subprocess.Popen([sys.executable, "-m", "mobot_cli", "run", str(scenario), "--ros2", "--realtime",
                            "-o", str(out)], cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        sent = peer("send", "rt/r1/cmd_vel", twist(math.nan, 0.0), twist(0.0, math.inf), twist(1e308, 0.0),
                    *[payload for payload, why in BAD.items() if why == MALFORMED][2:], timeout=60)
        _, stderr = run.communicate(timeout=120)
    finally:
        run.kill()
    assert sent == {"written": [True] * 5, "matched": 1}
    assert run.returncode == 0, stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "ok"
    [line] = [n for n in summary["notices"] if n.startswith("ROS 2:")]
    found = re.fullmatch(r"ROS 2: (\d) sample\(s\) on /r1/cmd_vel dropped \(1 beyond 100 m/s or 100 rad/s, "
                         r"(\d) not a little-endian CDR Twist, 2 not finite\); the world went on", line)
    assert found and int(found.group(1)) == 3 + int(found.group(2)) and int(found.group(2)) in (1, 2), line
    rows = (out / "odom" / "r1.csv").read_text().splitlines()
    assert len(rows) > 100  # it went on to the end, a row every 1/48 s
    values = [float(v) for row in rows[1:] for v in row.split(",") if v not in ("", "nan")]
    assert all(math.isfinite(v) for v in values) and len(values) > 1000


@given(st.binary(max_size=200))
@settings(max_examples=300, deadline=None)
def test_any_bytes_are_a_bounded_finite_twist_or_a_reason_and_never_raise(data):
    from mobot_cli.ros2 import inputs

    checked = inputs.cmd_vel(data)
    if isinstance(checked, str):
        assert checked in (inputs.MALFORMED, inputs.NOT_FINITE, inputs.TOO_FAST)
    else:
        linear, angular = checked
        assert math.isfinite(linear) and abs(linear) <= 100 and math.isfinite(angular) and abs(angular) <= 100


@given(st.floats(), st.floats(), st.sampled_from([b"", b"\0" * 4, b"\xff" * 300]))
@settings(max_examples=300, deadline=None)
def test_a_twist_is_taken_only_when_finite_bounded_and_of_a_twists_length(linear, angular, tail):
    from mobot_cli.ros2 import inputs

    checked = inputs.cmd_vel(bytes.fromhex(twist(linear, angular)) + tail)
    if len(tail) > 4:
        assert checked == inputs.MALFORMED
    elif not (math.isfinite(linear) and math.isfinite(angular)):
        assert checked == inputs.NOT_FINITE
    elif abs(linear) > 100 or abs(angular) > 100:
        assert checked == inputs.TOO_FAST
    else:
        assert checked == (linear, angular, 0.0)  # (linear.x, angular.z, linear.y)


def test_linear_y_to_a_robot_that_cannot_move_sideways_is_dropped_with_one_warning(tmp_path):
    scenario = tmp_path / "world.yaml"
    scenario.write_text(WORLD.format(ros2=""))
    out = tmp_path / "out"
    sideways = (HEADER + struct.pack("<6d", 0.2, 0.3, 0.0, 0.0, 0.0, 0.1)).hex()
    live = LiveProcess(str(scenario), "--ros2", cache_dir=tmp_path / "cache", out=out)
    try:
        sent = peer("send", "rt/r1/cmd_vel", sideways, sideways)
        with live.client() as client:
            odom = client.odom("r1")
        code = live.signal()
    finally:
        live.kill()
    assert sent["matched"] == 1 and all(sent["written"])
    assert odom["cmd"] == {"linear": 0.2, "angular": 0.1}  # linear.x and angular.z still drive
    assert code == 0
    notices = json.loads((out / "summary.json").read_text())["notices"]
    assert [n for n in notices if "linear.y" in n] == [
        "ROS 2: cmd_vel linear.y for robot 'r1' is ignored: it has a diff drive, and only holonomic "
        "(mecanum, omni) drives move sideways"]
