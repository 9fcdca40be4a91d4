"""Scenario `events:`: spawns and deletes at given times, resolved to whole steps and run."""

from __future__ import annotations

import csv
import json
import textwrap
from dataclasses import astuple
from pathlib import Path

import pytest

from mobot_cli.cli import CommandResult, invoke
from mobot_cli.errors import ScenarioError
from mobot_cli.scenario.prepare import prepare

REPO = Path(__file__).resolve().parents[2]
EVENTS = REPO / "scenarios" / "events.yaml"


def rows(path: Path) -> list[dict[str, float]]:
    with path.open() as f:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]


def scenario(tmp_path: Path, body: str) -> Path:
    path = tmp_path / "s.yaml"
    path.write_text("version: 1\nduration: 5\nsettle: 0.5\n" + textwrap.dedent(body))
    return path


@pytest.fixture(scope="module")
def events_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("events") / "run"
    assert invoke(["run", str(EVENTS), "--out", str(out), "--quiet"]) == CommandResult(0, "", "")
    return out


def test_events_resolve_to_steps_in_time_order():
    plan = prepare(EVENTS).plan
    assert [(e.step, e.delete, e.spawn and e.spawn.name) for e in plan.events] == \
        [(720, "mobot_1", None), (840, None, "late")]
    late = plan.events[1].spawn
    assert (late.namespace, late.frame_prefix, late.spawn_step) == ("/late", "late/", 840)
    # 4.0 s for 1.5 s: a command at step 960 and its stop at 1320, both in scenario time.
    assert [(c.step, c.linear) for c in late.commands] == [(960, 0.2), (1320, 0.0)]


def test_deleted_robot_file_ends_and_spawned_robot_file_starts(events_run):
    gone = rows(events_run / "odom" / "mobot_1.csv")
    assert gone[-1]["t"] == 3.0  # its state at the step it was deleted
    late = rows(events_run / "odom" / "late.csv")
    assert late[0]["t"] == 3.5
    assert (late[0]["true_x"], late[0]["true_y"]) == pytest.approx((1.0, -1.0), abs=2e-3)
    assert late[0]["true_yaw"] == pytest.approx(1.5708, abs=1e-3)
    by_step = {round(r["t"] * 240): r for r in late}
    assert by_step[955]["cmd_linear"] == 0.0 and by_step[960]["cmd_linear"] == 0.2
    # 0.3 m forward (odom frame = spawn pose), which is +y in the world for a robot facing +y.
    assert late[-1]["odom_x"] == pytest.approx(0.3, abs=0.02)
    assert late[-1]["true_y"] == pytest.approx(-0.7, abs=0.02)
    summary = json.loads((events_run / "summary.json").read_text())
    assert set(summary["robots"]) == {"mobot_0", "mobot_1", "late"}


def test_events_reorder_by_time_and_commands_stop_at_deletion(tmp_path):
    path = scenario(tmp_path, """
        robots:
          - name: a
            commands: [{at: 1.0, linear: 0.2}, {at: 4.0, linear: 0.1}]
        events:
          - {at: 3.0, spawn: {name: b, pose: {x: 2}}}
          - {at: 2.0, delete: a}
    """)
    plan = prepare(path).plan
    assert [(e.step, e.delete or e.spawn.name) for e in plan.events] == [(480, "a"), (720, "b")]
    assert [c.step for c in plan.robots[0].commands] == [240]  # the one at 4 s comes after the delete


def test_event_after_the_end_is_dropped_with_a_notice(tmp_path):
    path = scenario(tmp_path, """
        robots: [{name: a}]
        events: [{at: 9.0, delete: a}]
    """)
    plan = prepare(path).plan
    assert plan.events == ()
    assert any("event at 9 s is at or after the end of the run (5 s) and never happens" in n
               for n in plan.notices)


@pytest.mark.parametrize("body, message", [
    ("robots: [{name: a}]\nevents: [{at: 1.0, delete: a}, {at: 2.0, delete: a}]",
     "event at 2 s deletes 'a', which is not in the world then. It was deleted at 1 s"),
    ("events: [{at: 1.0, spawn: {name: 'f_{i}', count: 2, poses: [[0, 0, 0], [1, 0, 0]]}}]",
     "a spawn event spawns one robot"),
    ("events: [{at: 1.0}]", "an event needs exactly one of 'spawn' or 'delete'"),
    ("robots: [{name: a}]\nevents: [{at: 1.0, spawn: {name: b, namespace: /a}}]",
     "namespace '/a' of 'b' is already used by 'a'"),
])
def test_bad_events(tmp_path, body, message):
    with pytest.raises(ScenarioError) as err:
        prepare(scenario(tmp_path, body))
    assert message in str(err.value)


def test_a_spawn_event_into_another_robot_stops_the_run_with_the_event_time(tmp_path):
    path = scenario(tmp_path, """
        robots: [{name: a}]
        events: [{at: 1.0, spawn: {name: b, pose: {x: 0.05}}}]
    """)
    code, out, err = astuple(invoke(["run", path, "--out", tmp_path / "out", "--quiet"]))
    assert out == ""
    assert code == 2
    assert err.startswith("mobot: error: event at 1 s: robot 'b' spawned at ")
    assert "into robot 'a'" in err
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["status"] == "fault"
