"""The one timeline: every robot gets the same records however it entered the world."""

from __future__ import annotations

import csv
import json
import textwrap
from pathlib import Path

import pytest

from mobot_cli.record.summary import RunRecord, Status
from mobot_cli.run import execute
from mobot_cli.scenario.prepare import prepare
from mobot_cli.timeline.loop import simulate
from mobot_cli.timeline.records import Deleted, Sample, Spawned
from tests.live.live_server import LiveProcess

RATE = 240


def scenario(tmp_path: Path, body: str) -> Path:
    path = tmp_path / "s.yaml"
    path.write_text("version: 1\nseed: 3\n" + textwrap.dedent(body))
    return path


def times(path: Path) -> list[str]:
    with path.open() as f:
        return [row["t"] for row in csv.DictReader(f)]


SHORT_LIFE = """\
    duration: 2
    settle: 0.1
    log: {rate_hz: 48, formats: [csv, mcap]}
    robots:
      - {name: stays, description: mobot}
    events:
      - {at: 1.00417, spawn: {name: short, description: mobot, pose: {x: 2}}}   # step 241: between rows
      - {at: 1.0125, delete: short}                                              # step 243, same log period
"""


def test_a_short_life_gets_rows_at_its_spawn_and_its_delete(tmp_path):
    plan = prepare(scenario(tmp_path, SHORT_LIFE)).plan
    assert [e.step for e in plan.events] == [241, 243]
    out = tmp_path / "run"
    result = execute(plan, "", out)
    assert times(out / "odom" / "short.csv") == ["1.004167", "1.012500"]
    assert times(out / "odom" / "stays.csv")[:2] == ["0.000000", "0.020833"]  # its rows keep the log rate
    assert len(times(out / "odom" / "stays.csv")) == 2 * 48 + 1
    short = result.record.robots["short"]
    assert (short.spawned_at, short.deleted_at) == (pytest.approx(241 / RATE), pytest.approx(243 / RATE))
    assert short.final_pose.x == pytest.approx(2.0, abs=2e-3)


def test_records_come_in_order_spawn_rows_delete(tmp_path):
    plan = prepare(scenario(tmp_path, SHORT_LIFE)).plan
    mine = [r for r in simulate(plan) if (r.robot.name if isinstance(r, Spawned) else
                                          getattr(r, "name", None)) == "short"
            or (isinstance(r, Sample) and "short" in r.states)]
    kinds = [(type(r).__name__, r.step) for r in mine]
    assert kinds == [("Spawned", 241), ("Sample", 241), ("Sample", 243), ("Deleted", 243)]
    assert all(not r.complete for r in mine if isinstance(r, Sample))


def test_a_delete_on_a_log_row_is_not_recorded_twice(tmp_path):
    body = SHORT_LIFE.replace("at: 1.00417", "at: 0.5").replace("at: 1.0125", "at: 1.0")
    plan = prepare(scenario(tmp_path, body)).plan
    records = list(simulate(plan))
    at_delete = [r for r in records if isinstance(r, Sample) and r.step == RATE]
    # The robot's own last row comes first, then the log row of everyone still in the world.
    assert [(r.complete, sorted(r.states)) for r in at_delete] == [(False, ["short"]), (True, ["stays"])]
    assert isinstance(records[records.index(at_delete[0]) + 1], Deleted)


def test_the_record_reads_back_as_written(tmp_path):
    plan = prepare(scenario(tmp_path, SHORT_LIFE)).plan
    result = execute(plan, "", tmp_path / "run")
    again = RunRecord.load(tmp_path / "run")
    assert again == result.record and again.status is Status.OK
    text = (tmp_path / "run" / "summary.json").read_text()
    assert list(json.loads(text))[:4] == ["status", "error", "scenario", "world"]
    (tmp_path / "run" / "summary.json").write_text('{"status": "ok"}')
    assert RunRecord.load(tmp_path / "run") is None  # not a record mobot wrote


def _bag(folder: Path) -> tuple[dict[str, str], list]:
    from mcap_ros2.reader import read_ros2_messages

    topics, messages = {}, []
    for m in read_ros2_messages(str(next((folder / "bag").glob("*.mcap")))):
        topics[m.channel.topic] = m.schema.name
        messages.append((m.channel.topic, m.ros_msg))
    return topics, messages


def _robot_view(topics: dict[str, str], messages: list, name: str) -> dict:
    """What the bag holds of one robot, its name taken out so that two robots compare."""
    def strip(frame: str) -> str:
        return frame.replace(f"{name}/", "<r>/")

    own = {t.replace(f"/{name}/", "/<r>/"): ty for t, ty in topics.items() if t.startswith(f"/{name}/")}
    tf = {(strip(t.header.frame_id), strip(t.child_frame_id)) for topic, msg in messages if topic == "/tf"
          for t in msg.transforms if t.child_frame_id.startswith(f"{name}/")}
    static = {(strip(t.header.frame_id), strip(t.child_frame_id)) for topic, msg in messages
              if topic == "/tf_static" for t in msg.transforms if t.child_frame_id.startswith(f"{name}/")}
    joints = {tuple(msg.name) for topic, msg in messages if topic == f"/{name}/joint_states"}
    descriptions = [msg.data for topic, msg in messages if topic == f"/{name}/robot_description"]
    return {"topics": own, "tf": tf, "tf_static": static, "joints": joints,
            "description": [d.replace(f'name="{name}"', "") for d in descriptions]}


def test_a_live_spawned_robot_is_recorded_like_a_scenario_robot(tmp_path, tmp_path_factory):
    """Robot 'a' comes from the scenario, 'b' from `mobot spawn`: the same topics, frames, joints."""
    path = scenario(tmp_path, """\
        duration: 1
        settle: 0.1
        log: {rate_hz: 48, formats: [csv, mcap]}
        robots:
          - {name: a, description: mobot}
    """)
    out = tmp_path / "rec"
    server = LiveProcess(str(path), "--fast", cache_dir=tmp_path_factory.getbasetemp() / "mobot-cache", out=out)
    try:
        with server.client() as client:
            client.spawn("b", description="mobot", pose={"x": 2.0})
            client.cmd("b", linear=0.3, for_=0.5, wait=True)
            client.stop()
        assert server.wait() == 0, server.output()
    finally:
        server.kill()
    topics, messages = _bag(out)
    a, b = _robot_view(topics, messages, "a"), _robot_view(topics, messages, "b")
    assert a["topics"] == b["topics"] == {
        "/<r>/odom": "nav_msgs/msg/Odometry", "/<r>/cmd_vel": "geometry_msgs/msg/Twist",
        "/<r>/joint_states": "sensor_msgs/msg/JointState", "/<r>/robot_description": "std_msgs/msg/String"}
    assert a["tf"] == b["tf"] and ("<r>/base_link", "<r>/left_wheel") in b["tf"]
    assert a["tf_static"] == b["tf_static"] and ("world", "<r>/odom") in b["tf_static"]
    assert a["joints"] == b["joints"] and len(b["description"]) == 1
    record = RunRecord.load(out)
    assert [(r.name, r.namespace, r.source.endswith("mobot.urdf.xacro")) for r in record.robots.values()] \
        == [("a", "/a", True), ("b", "/b", True)]
    assert record.live is not None and record.live.requests["spawn"] == 1


@pytest.mark.parametrize("name", ["fleet", "events"])
def test_a_reset_timeline_replays_its_scenario_to_the_last_bit(name):
    """Timeline.reset (a live world's `reset`): the world rebuilt at step 0, the same robots, events and
    scripts, the same rows; robots leave by "reset" and come back by "reset"."""
    from mobot_cli.sim.bullet.world import World
    from mobot_cli.timeline.loop import Timeline

    plan = prepare(Path(__file__).resolve().parents[2] / "scenarios" / f"{name}.yaml").plan
    records: list = []
    with World(plan.physics, plan.world, seed=plan.seed) as world:
        timeline = Timeline(plan, world)
        timeline.attach(records.append)
        timeline.start()
        lives = []
        for _ in range(2):
            start = len(records)
            for _ in range(900):
                timeline.tick()
                timeline.advance()
            timeline.tick()
            lives.append([(r.step, sorted((n, s.row()) for n, s in r.states.items()))
                          for r in records[start:] if isinstance(r, Sample)])
            before = timeline.robots.copy()
            timeline.reset()
            assert timeline.step == 0 and timeline.resets == len(lives)
            deleted = [r.name for r in records if isinstance(r, Deleted) and r.by == "reset"]
            assert deleted[-len(before):] == list(before)
            respawned = [r.robot.name for r in records if isinstance(r, Spawned) and r.by == "reset"]
            assert respawned[-len(plan.robots):] == [robot.name for robot in plan.robots]
    assert lives[0] == lives[1] and len(lives[0]) > 10
