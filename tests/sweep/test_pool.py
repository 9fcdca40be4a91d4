"""The local pool starts before the runs are prepared (LocalExecutor.prestart): workers that
started early still survive a crashed run, are stopped when the sweep ends before running
anything (bad input, nothing left to resume, Ctrl-C), and summaries are flushed by the sweep."""

from __future__ import annotations

import multiprocessing
import os
import signal
import subprocess
import sys
import time
from dataclasses import astuple
from pathlib import Path

import pytest

from mobot_cli.cli import CommandResult, invoke
from mobot_cli.sweep.execution import run_sweep
from mobot_cli.sweep.executor_local import LocalExecutor
from mobot_cli.sweep.expand import expand
from mobot_cli.sweep.spec import build_spec
from mobot_cli.sweep.task import run_task
from tests.sweep.test_guard import session
from tests.sweep.test_sweep import rows

REPO = Path(__file__).resolve().parents[2]
SHORT = """version: 1
name: short
duration: 1
log: {rate_hz: 10}
robots:
  - name: mobot
    commands: [{at: 0.5, linear: 0.2}]
"""


@pytest.fixture
def scenario(tmp_path) -> Path:
    path = tmp_path / "short.yaml"
    path.write_text(SHORT)
    return path


def workers_alive(count: int, timeout: float = 60.0) -> bool:
    """Wait until this process has ``count`` live worker processes."""
    deadline = time.monotonic() + timeout
    while len(multiprocessing.active_children()) < count:
        if time.monotonic() > deadline:
            return False
        time.sleep(0.02)
    return True


def crash_run_1(task):
    """A worker runner (test only): run 1 kills its worker."""
    if task.index == 1:
        os.kill(os.getpid(), signal.SIGKILL)
    return run_task(task)


def test_prestarted_workers_survive_a_crashed_run(scenario, tmp_path):
    executor = LocalExecutor(2, timeout=60.0, runner=crash_run_1)
    executor.prestart()
    spec = build_spec(scenario, ["robots.mobot.pose.x=0,1,2,3"], [], [], None, None, [])
    executor.prestart(4)  # as the sweep command does: the server first, the workers once the runs are counted
    assert workers_alive(2)  # started before the runs were prepared
    run_sweep(expand(spec), tmp_path / "out", executor, {})
    table = rows(tmp_path / "out")
    assert [(r["status"], r["failure"]) for r in table] == [("passed", ""), ("failed", "crash"), ("passed", ""),
                                                             ("passed", "")]
    assert table[1]["reason"] == "the worker process was killed by SIGKILL (a crash in the physics engine?)"
    assert float(table[3]["mobot.x"]) == pytest.approx(3.0 + 0.1, abs=0.02)
    assert multiprocessing.active_children() == []


def test_close_stops_workers_that_no_run_took(scenario):
    executor = LocalExecutor(3)
    executor.prestart(2)  # fewer runs than jobs: two workers
    assert workers_alive(2)
    time.sleep(0.2)
    assert len(multiprocessing.active_children()) == 2
    executor.close()
    assert multiprocessing.active_children() == []


def test_more_workers_than_runs_left_are_stopped(scenario, tmp_path):
    out = tmp_path / "out"
    grid = ["--grid", "robots.mobot.pose.x=0,1,2"]
    assert invoke(["sweep", scenario, *grid, "-j", "2", "--out", out, "--quiet"]) == CommandResult(0, "", "")
    assert multiprocessing.active_children() == []
    lines = (out / "results.csv").read_text().splitlines(keepends=True)
    (out / "results.csv").write_text("".join(lines[:3]))  # run 2 left: one worker of the two started
    result = invoke(["sweep", scenario, *grid, "-j", "2", "--out", out, "--resume", "--quiet"])
    assert result == CommandResult(0, "", "")
    assert len(rows(out)) == 3 and multiprocessing.active_children() == []
    # Nothing left: the workers started early run nothing and are stopped.
    result = invoke(["sweep", scenario, *grid, "-j", "2", "--out", out, "--resume", "--quiet"])
    assert result == CommandResult(0, "", "")
    assert multiprocessing.active_children() == []


def test_bad_input_found_while_the_pool_starts_leaves_no_worker(scenario, tmp_path):
    code, out, err = astuple(invoke(["sweep", scenario, "--grid", "settle=0.5,3", "--out", tmp_path / "out"]))
    assert (code, out) == (2, "") and "(in run 1: settle=3)" in err
    assert multiprocessing.active_children() == []
    assert not (tmp_path / "out").exists()


def test_ctrl_c_while_the_pool_starts(scenario, tmp_path):
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "mobot_cli", "sweep", str(scenario), "--grid",
                             "seed=" + ",".join(str(i) for i in range(40)), "-j", "2", "--out", str(out)],
                            cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    deadline = time.monotonic() + 60
    while len(session(proc.pid)) < 2 and time.monotonic() < deadline:  # the fork server is starting
        time.sleep(0.005)
    os.killpg(proc.pid, signal.SIGINT)  # as Ctrl-C in a terminal: the whole process group
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and "Traceback" not in err
    assert err.endswith("mobot: interrupted\n") or "Go on with: --resume" in err
    deadline = time.monotonic() + 10
    while session(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert session(proc.pid) == []  # no fork server, no worker left behind


def test_every_summary_is_flushed_to_disk_by_the_sweep(scenario, tmp_path, monkeypatch):
    synced = []
    fsync = os.fsync

    def noting(fd):
        synced.append(os.readlink(f"/proc/self/fd/{fd}"))
        fsync(fd)

    monkeypatch.setattr(os, "fsync", noting)  # this process only: the workers write without
    out = tmp_path / "out"
    assert invoke(["sweep", scenario, "--grid", "robots.mobot.pose.x=0,1,2", "--out", out, "--quiet"]) == \
        CommandResult(0, "", "")
    for run in ("0000", "0001", "0002"):
        assert str((out / "runs" / run / "summary.json").resolve()) in synced
