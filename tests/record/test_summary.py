"""summary.json's record: plain dataclasses written without pydantic, read back by pydantic."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.record.summary import (
    SUMMARY,
    GoalRecord,
    LiveInfo,
    OdomError,
    OdomPose,
    Pose,
    RobotRecord,
    RunRecord,
    SensorRecord,
    Status,
    Versions,
)


def _robot(**changes) -> RobotRecord:
    fields = dict(name="r1", namespace="/r1", source="bundled:diff_drive", spawned_at=0,
                  final_pose=Pose(x=1, y=2, z=0, roll=0, pitch=0, yaw=np.float64(0.5)),
                  final_odom=OdomPose(x=1, y=2, yaw=0), distance=3, collisions=np.int64(2),
                  odom_error=OdomError(position=0, yaw=0),
                  sensors=[SensorRecord(name="scan", kind="lidar", topic="/r1/scan", frame_id="r1/base_scan",
                                        rate_hz=10, readings=np.int32(50), file="sensors/r1/scan.npy")],
                  goals=[GoalRecord(command=0, kind="goto", status="reached", started_at=1, ended_at=2, time=1,
                                    path_length=0.5, error=0, laps=None)])
    fields.update(changes)
    return RobotRecord(**fields)


def _run(**changes) -> RunRecord:
    fields = dict(status=Status.OK, scenario="s", world="empty", seed=np.int64(7),
                  versions=Versions(mobot="0.0", pybullet=None, python="3.11"), steps=240, sim_time=1,
                  wall_time=0.5, real_time_factor=2, physics_rate_hz=240, log_rate_hz=48,
                  robots={"r1": _robot()})
    fields.update(changes)
    return RunRecord(**fields)


def test_numbers_take_their_declared_type_as_a_pydantic_model_gave_them():
    record = _run()
    robot = record.robots["r1"]
    assert type(robot.spawned_at) is float and type(record.sim_time) is float
    assert type(robot.collisions) is int and type(record.seed) is int and type(robot.sensors[0].readings) is int
    assert type(robot.final_pose.yaw) is float and robot.goals[0].laps is None
    text = record.to_json()
    assert '"spawned_at": 0.0,' in text and '"sim_time": 1.0,' in text and '"rate_hz": 10.0,' in text
    assert '"collisions": 2,' in text and '"seed": 7,' in text and '"physics_rate_hz": 240,' in text
    assert '"status": "ok",' in text and '"laps": null' in text


def test_the_file_keeps_the_declared_key_order_and_two_space_indents():
    data = json.loads(_run().to_json())
    assert list(data) == ["status", "error", "scenario", "world", "seed", "versions", "steps", "sim_time",
                          "wall_time", "real_time_factor", "physics_rate_hz", "log_rate_hz", "notices", "robots",
                          "expectations", "live", "fault"]
    assert list(data["robots"]["r1"]) == ["name", "namespace", "source", "spawned_at", "deleted_at", "final_pose",
                                          "final_odom", "distance", "collisions", "odom_error", "sensors", "goals"]
    assert _run().to_json().splitlines()[1] == '  "status": "ok",'


def test_a_record_reads_back_equal_and_unknown_keys_are_ignored(tmp_path):
    record = _run(live=LiveInfo(endpoint="tcp://127.0.0.1:5555", pace="realtime", requests={"spawn": 2}))
    record.save(tmp_path, durable=False)
    assert RunRecord.load(tmp_path) == record
    data = json.loads((tmp_path / SUMMARY).read_text())
    data["added_later"] = {"x": 1}
    data["robots"]["r1"]["also_new"] = 3
    (tmp_path / SUMMARY).write_text(json.dumps(data))
    assert RunRecord.load(tmp_path) == record


@pytest.mark.parametrize("text", ["", "{", '{"status": "ok"}', '{"status": "maybe"}', "[]", "null"])
def test_anything_but_a_record_reads_as_none(tmp_path, text):
    (tmp_path / SUMMARY).write_text(text)
    assert RunRecord.load(tmp_path) is None
    assert RunRecord.load(tmp_path / "absent") is None


def test_a_wrong_type_in_the_file_reads_as_none(tmp_path):
    data = json.loads(_run().to_json())
    data["robots"]["r1"]["collisions"] = "many"
    (tmp_path / SUMMARY).write_text(json.dumps(data))
    assert RunRecord.load(tmp_path) is None


def test_a_nan_is_refused_when_written():
    with pytest.raises(ValueError):
        _run(wall_time=float("nan")).to_json()


def test_writing_a_record_does_not_import_pydantic():
    code = ("import sys; from mobot_cli.record.summary import *; import mobot_cli.run, mobot_cli.cli.run; "
            "print('pydantic' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"


finite = st.floats(allow_nan=False, allow_infinity=False, width=64)


@settings(max_examples=200, deadline=None)
@given(x=finite | st.integers(-10**6, 10**6), steps=st.integers(0, 10**9), error=st.none() | st.text(max_size=40))
def test_any_record_round_trips_through_its_file(tmp_path_factory, x, steps, error):
    folder = tmp_path_factory.mktemp("r")
    record = _run(sim_time=x, steps=steps, error=error, robots={"a": _robot(distance=x), "b": _robot(name="b")})
    record.save(folder, durable=False)
    again = RunRecord.load(folder)
    assert again == record and again.to_json() == record.to_json()
