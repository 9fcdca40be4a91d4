"""Ctrl-C at any moment of `mobot run`, start-up imports included: `mobot: interrupted`, 130."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
DELAYS = (0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.6, 0.8, 1.0)


# `mobot` as the console script runs it, after telling the test (one byte on a pipe) that Python's
# own start-up is over: the delay counts from there, so a busy machine, which makes the
# interpreter's start-up slow, moves the interrupt no earlier into mobot's (before the guard).
ENTRY = ("import os, sys; import mobot_cli.__main__ as main; os.write(int(sys.argv[1]), b'.'); "
         "os.close(int(sys.argv[1])); del sys.argv[1]; main.entry()")


def _interrupt_after(delay: float, out: Path) -> tuple[int, str]:
    ready, told = os.pipe()
    proc = subprocess.Popen([sys.executable, "-c", ENTRY, str(told), "run", "scenarios/quickstart.yaml", "--out",
                             str(out), "--quiet"], cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True, pass_fds=(told,))
    os.close(told)
    try:
        assert os.read(ready, 1) == b".", proc.communicate(timeout=600)[1]  # no byte: it failed to start
    finally:
        os.close(ready)
    time.sleep(delay)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=600)
    return proc.returncode, err


def _before_mobot(err: str) -> bool:
    """A traceback from before mobot's entry point ran (Python's own start-up, the import of the
    package): entry() installs the Ctrl-C guard as its first statement, so any later interrupt
    is mobot's to handle and a traceback through entry() is a bug. So is one from a sweep's fork
    server or workers (multiprocessing's frames): they start with Ctrl-C held back."""
    return "Traceback" in err and "in entry" not in err and "multiprocessing" not in err


@pytest.mark.parametrize("delay", DELAYS)
def test_ctrl_c_at_any_moment_exits_130_without_a_traceback(delay, tmp_path):
    for attempt in range(5):
        code, err = _interrupt_after(delay, tmp_path / f"run{attempt}")
        # The few statements between the byte and entry()'s guard: a process descheduled just
        # there (a busy machine) takes the interrupt before mobot's guard. Retry.
        if not _before_mobot(err):
            break
    assert "Traceback" not in err, err
    assert code in (0, 130), (code, err)
    if code == 130:
        assert err == "mobot: interrupted\n"
        summary = tmp_path / f"run{attempt}" / "summary.json"
        if summary.exists():  # the run folder was made: it says how the run ended
            assert json.loads(summary.read_text())["status"] in ("interrupted", "ok")
    else:
        assert err == ""


@pytest.mark.parametrize("delay", (0.3, 0.6, 0.8, 0.9, 1.0, 1.2, 1.5))
def test_ctrl_c_at_any_moment_of_a_sweep_stops_it_without_a_traceback(delay, tmp_path):
    """Ctrl-C reaches the whole process group: the sweep, its fork server (maybe still importing
    mobot) and its workers. Only the sweep speaks."""
    for attempt in range(5):
        ready, told = os.pipe()
        proc = subprocess.Popen([sys.executable, "-c", ENTRY, str(told), "sweep", "scenarios/quickstart.yaml",
                                 "--grid", "robots.mobot.pose.x=0,1,2,3", "-j", "2", "--out",
                                 str(tmp_path / f"sweep{attempt}"), "--quiet"], cwd=REPO, stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE, text=True, start_new_session=True, pass_fds=(told,))
        os.close(told)
        try:
            assert os.read(ready, 1) == b".", proc.communicate(timeout=600)[1]
        finally:
            os.close(ready)
        time.sleep(delay)
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=600)
        if not _before_mobot(err):  # as above: retry an interrupt that beat entry()'s guard
            break
    assert "Traceback" not in err, err
    assert proc.returncode in (0, 130), (proc.returncode, err)
    if proc.returncode == 130:
        assert err.endswith("mobot: interrupted\n")
