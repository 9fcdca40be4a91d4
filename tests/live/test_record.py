"""`mobot serve --out`: scenario events in a live world, `mobot stop`, SIGINT/SIGTERM, the record."""

from __future__ import annotations

import csv
import json
import signal
from pathlib import Path

import pytest

from mobot_cli.cli import CommandResult, invoke
from mobot_cli.errors import RequestRefused
from tests.live.live_server import REPO, LiveProcess, wait_for_step

EVENTS = REPO / "scenarios" / "events.yaml"


def rows(path: Path) -> list[dict[str, float]]:
    with path.open() as f:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]


def history(out: Path) -> list[dict]:
    return [json.loads(line) for line in (out / "history.jsonl").read_text().splitlines()]


@pytest.fixture
def cache(tmp_path_factory) -> Path:
    return tmp_path_factory.getbasetemp() / "mobot-cache"


def test_scenario_events_play_live_as_in_a_run(tmp_path, cache):
    """Serving events.yaml logs, step for step, the rows `mobot run` writes for it."""
    server = LiveProcess(str(EVENTS), "--fast", cache_dir=cache, out=tmp_path / "live")
    try:
        with server.client() as client:
            wait_for_step(client, 6 * 240 + 10)
            names = [robot["name"] for robot in client.list()]
        assert names == ["mobot_0", "late"]  # mobot_1 deleted at 3 s, late spawned at 3.5 s
        stopped = invoke(["stop", "--endpoint", server.endpoint])
        assert (stopped.exit_code, stopped.stderr) == (0, "")
        assert stopped.stdout.startswith(f"stopped the live world at {server.endpoint} at t=")
        assert server.wait() == 0, server.output()
    finally:
        server.kill()
    assert invoke(["run", str(EVENTS), "--out", str(tmp_path / "run"), "--quiet"]) == CommandResult(0, "", "")
    live, run = tmp_path / "live", tmp_path / "run"
    for name in ("mobot_0", "mobot_1", "late"):
        ran = (run / "odom" / f"{name}.csv").read_text().splitlines()
        served = (live / "odom" / f"{name}.csv").read_text().splitlines()
        assert served[:len(ran)] == ran, name
    assert rows(live / "odom" / "mobot_1.csv")[-1]["t"] == 3.0  # its state when it was deleted
    assert rows(live / "odom" / "late.csv")[0]["t"] == 3.5
    events = [(h["op"], h["name"], h["by"]) for h in history(live)]
    assert events == [("spawn", "mobot_0", "scenario"), ("spawn", "mobot_1", "scenario"),
                      ("delete", "mobot_1", "scenario"), ("spawn", "late", "scenario")]
    summary = json.loads((live / "summary.json").read_text())
    assert summary["status"] == "ok" and summary["scenario"] == "events"
    assert summary["robots"]["mobot_1"]["deleted_at"] == 3.0
    assert summary["robots"]["late"]["spawned_at"] == 3.5
    assert (live / "scenario.yaml").read_text() == (run / "scenario.yaml").read_text()


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_a_signal_flushes_the_record_and_exits_0(tmp_path, cache, signum):
    out = tmp_path / "rec"
    server = LiveProcess("--fast", cache_dir=cache, out=out)
    try:
        with server.client() as client:
            client.spawn("r1", description="mobot", pose={"x": 1.0})
            client.cmd("r1", linear=0.2, for_=1.0, wait=True)
            with pytest.raises(RequestRefused):
                client.spawn("r1", description="mobot")  # refused, and recorded as such
            step = client.ping()["step"]
        assert server.signal(signum) == 0, server.output()
    finally:
        server.kill()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "ok" and summary["steps"] >= step
    assert summary["robots"]["r1"]["distance"] == pytest.approx(0.2, abs=0.03)
    data = rows(out / "odom" / "r1.csv")
    assert data[-1]["t"] == pytest.approx(summary["steps"] / 240, abs=1e-6)  # the final state is recorded
    ops = [(h["op"], h["name"], h["result"]) for h in history(out)]
    assert ops == [("spawn", "r1", "OK"), ("cmd", "r1", "OK"), ("spawn", "r1", "NAME_NOT_UNIQUE")]


def test_live_requests_win_over_the_script(tmp_path, cache):
    """Deleting a robot live, or taking a scripted spawn's name, skips those events (recorded)."""
    out = tmp_path / "rec"
    # Paused until both requests are in: on a busy machine a playing world could reach the
    # script's 3 s before they are answered.
    server = LiveProcess(str(EVENTS), "--rtf", "2", "--paused", cache_dir=cache, out=out)
    try:
        with server.client() as client:
            client.delete("mobot_1")  # the script deletes it at 3 s
            client.spawn("late", description="mobot", pose={"x": -3.0})  # the script spawns 'late' at 3.5 s
            client.resume()
            wait_for_step(client, 4 * 240)
            client.stop()
        assert server.wait() == 0
    finally:
        server.kill()
    skipped = [h for h in history(out) if h["op"] == "event"]
    assert [h["result"] for h in skipped] == ["NOT_FOUND", "NAME_NOT_UNIQUE"]
    assert skipped[0]["message"].startswith("event at 3 s skipped: ")
    assert skipped[1]["message"].startswith("event at 3.5 s skipped: ")
    assert rows(out / "odom" / "late.csv")[0]["true_x"] == pytest.approx(-3.0, abs=2e-3)


def test_a_name_used_again_gets_its_own_file(tmp_path, cache):
    out = tmp_path / "rec"
    server = LiveProcess("--fast", cache_dir=cache, out=out)
    try:
        with server.client() as client:
            client.spawn("again", description="mobot")
            wait_for_step(client, client.ping()["step"] + 48)
            client.delete("again")
            client.spawn("again", description="mobot", pose={"x": 2.0})
            wait_for_step(client, client.ping()["step"] + 48)
            client.stop()
        assert server.wait() == 0
    finally:
        server.kill()
    assert rows(out / "odom" / "again.csv")[0]["true_x"] == pytest.approx(0.0, abs=2e-3)
    assert rows(out / "odom" / "again__2.csv")[0]["true_x"] == pytest.approx(2.0, abs=2e-3)
    summary = json.loads((out / "summary.json").read_text())
    assert set(summary["robots"]) == {"again", "again__2"}
    assert summary["robots"]["again"]["deleted_at"] is not None


def test_duration_stops_the_server_by_itself(tmp_path, cache):
    out = tmp_path / "rec"
    server = LiveProcess("--fast", "--duration", "2", "--set", "physics.rate_hz=100", cache_dir=cache, out=out,
                         ready=False)  # it may be done before a ping could get through
    try:
        assert server.wait() == 0, server.output()
    finally:
        server.kill()
    summary = json.loads((out / "summary.json").read_text())
    assert (summary["status"], summary["steps"], summary["physics_rate_hz"]) == ("ok", 200, 100)
    assert summary["live"]["pace"] == "fast"


def test_spawning_into_a_furnished_world(tmp_path, cache):
    """The bundled house: robot names are unique among its models too; furniture refuses a robot."""
    server = LiveProcess("house", "--fast", cache_dir=cache)
    try:
        with server.client() as client:
            assert client.ping()["world"] == "house"
            with pytest.raises(RequestRefused, match="NAME_NOT_UNIQUE: 'sofa' is already the name"):
                client.spawn("sofa", description="mobot", pose={"x": 3.5, "y": 1.0})
            with pytest.raises(RequestRefused, match="INVALID_POSE: .* into world model 'sofa'"):
                client.spawn("couch_potato", description="mobot", pose={"x": 0.0, "y": -1.6, "z": 0.05})
            placed = client.spawn("r1", description="mobot", pose={"x": 3.5, "y": 1.0})
            assert (placed["pose"]["x"], placed["pose"]["y"]) == pytest.approx((3.5, 1.0), abs=2e-3)
    finally:
        server.kill()
