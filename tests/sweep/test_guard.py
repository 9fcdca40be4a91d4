"""A sweep owns its folder and its workers: kill -9 of the sweep takes its workers with it, and a
second sweep (a --resume) is refused while one runs in the folder."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mobot_cli.cli import invoke

REPO = Path(__file__).resolve().parents[2]
LONG = """version: 1
name: long
duration: 600
log: {rate_hz: 10}
robots:
  - name: mobot
    commands: [{at: 0.5, linear: 0.2, angular: 0.2}]
"""
GRID = ["--grid", "robots.mobot.pose.x=0,1,2,3"]


@pytest.fixture
def scenario(tmp_path) -> Path:
    path = tmp_path / "long.yaml"
    path.write_text(LONG)
    return path


def session(sid: int) -> list[int]:
    """Live (not zombie) processes of a session, from /proc."""
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[3]) == sid and fields[0] != "Z":
            found.append(int(stat.parent.name))
    return found


def start_sweep(scenario: Path, out: Path) -> subprocess.Popen:
    """A sweep of four 600 s runs on two workers, in a session of its own; returns once both
    workers are inside a run."""
    proc = subprocess.Popen([sys.executable, "-m", "mobot_cli", "sweep", str(scenario), *GRID, "-j", "2",
                             "--out", str(out), "--quiet"], cwd=REPO, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    started = [out / "runs" / f"000{i}" / "odom" / "mobot.csv" for i in (0, 1)]
    deadline = time.monotonic() + 90
    while not all(p.is_file() for p in started):
        assert proc.poll() is None, proc.stderr.read()
        assert time.monotonic() < deadline, "the sweep's runs did not start"
        time.sleep(0.1)
    return proc


def kill_9(proc: subprocess.Popen) -> list[int]:
    """SIGKILL the sweep process alone; returns what was left of its session after 10 s."""
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    proc.stderr.close()
    deadline = time.monotonic() + 10
    while session(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.1)
    return session(proc.pid)


def test_kill_9_of_a_sweep_leaves_no_worker_running(scenario, tmp_path):
    proc = start_sweep(scenario, tmp_path / "sweep")
    try:
        workers = [pid for pid in session(proc.pid) if pid != proc.pid]
        assert len(workers) >= 2  # two workers (and the fork server they come from)
        assert kill_9(proc) == []
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)  # never leave a 600 s run behind, whatever failed
        except ProcessLookupError:
            pass


def test_a_second_sweep_in_a_running_sweeps_folder_is_refused_until_it_is_gone(scenario, tmp_path):
    out = tmp_path / "sweep"
    proc = start_sweep(scenario, out)
    try:
        refusal = (f"mobot: error: a sweep (pid {proc.pid}) is still running in {out}. Wait for it to end or "
                   "stop it, then --resume; or choose another --out.\n")
        for extra in (["--resume"], []):
            second = subprocess.run([sys.executable, "-m", "mobot_cli", "sweep", str(scenario), *GRID, "-j", "1",
                                     "--out", str(out), "--quiet", *extra], cwd=REPO, capture_output=True,
                                    text=True, timeout=120)
            assert second.returncode == 2 and second.stderr == refusal
        assert kill_9(proc) == []
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    # The killed sweep's lock died with it: --resume goes on (each run stopped by --timeout here).
    resumed = subprocess.run([sys.executable, "-m", "mobot_cli", "sweep", str(scenario), *GRID, "-j", "2",
                              "--timeout", "1", "--out", str(out), "--quiet", "--resume"], cwd=REPO,
                             capture_output=True, text=True, timeout=120)
    assert resumed.returncode == 1, resumed.stderr
    assert resumed.stderr == f"mobot: 4 of 4 runs failed; see {out}/results.csv\n"
    lines = (out / "results.csv").read_text().splitlines()
    assert len(lines) == 5 and all(",failed,timeout," in line for line in lines[1:])


def test_a_sweep_out_that_is_a_file_is_refused_before_any_run(scenario, tmp_path):
    out = tmp_path / "taken"
    out.write_text("keep me")
    outcome = invoke(["sweep", str(scenario), *GRID, "--out", str(out), "--quiet"])
    assert outcome.exit_code == 2
    assert outcome.stderr == f"mobot: error: --out {out} is a file. Give --out a folder, new or existing.\n"
    assert out.read_text() == "keep me"
