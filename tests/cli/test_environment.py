"""The CLI's Environment and invoke(): where output goes, terminals, --traceback, exit codes."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from mobot_cli import __version__
from mobot_cli.cli import CommandResult, invoke
from mobot_cli.cli.environment import Environment
from mobot_cli.errors import ScenarioError

REPO = Path(__file__).resolve().parents[2]
UNKNOWN_KEY = REPO / "tests" / "bad" / "unknown_key.yaml"
UNKNOWN_KEY_ERROR = (f"mobot: error: {UNKNOWN_KEY}:5, key 'robots.mobot.poze': unknown key 'poze'. "
                     "Did you mean 'pose'?\n")


@pytest.fixture
def tiny(tmp_path) -> Path:
    """A one-second scenario without notices, so stderr holds only what the test looks for."""
    path = tmp_path / "tiny.yaml"
    path.write_text("version: 1\nname: tiny\nduration: 1\nrobots:\n  - name: r\n")
    return path


def test_a_progress_bar_is_drawn_only_when_stderr_is_a_terminal(tiny, tmp_path):
    piped = invoke(["run", tiny, "--out", tmp_path / "piped"])
    assert (piped.exit_code, piped.stderr) == (0, "")
    terminal = invoke(["run", tiny, "--out", tmp_path / "tty"], env=Environment.captured(stderr_isatty=True))
    assert terminal.exit_code == 0
    assert "tiny ━" in terminal.stderr and " 100% " in terminal.stderr  # the bar, filled
    assert terminal.stderr.endswith("\x1b[2K")  # transient: erased when the run ends
    assert "\x1b[" not in terminal.stdout  # stdout is still not a terminal: a plain table
    assert terminal.stdout.replace(str(tmp_path / "tty"), "R").splitlines()[1:] == \
        piped.stdout.replace(str(tmp_path / "piped"), "R").splitlines()[1:]  # line 0 holds the wall time


def test_quiet_and_json_draw_no_bar_even_on_a_terminal(tiny, tmp_path):
    env = Environment.captured(stderr_isatty=True)
    assert invoke(["run", tiny, "--out", tmp_path / "q", "--quiet"], env=env) == CommandResult(0, "", "")
    env = Environment.captured(stderr_isatty=True)
    done = invoke(["run", tiny, "--out", tmp_path / "j", "--json"], env=env)
    assert (done.exit_code, done.stderr) == (0, "")
    summary = json.loads(done.stdout)
    assert summary == json.loads((tmp_path / "j" / "summary.json").read_text())
    assert summary["sim_time"] == 1.0 and list(summary["robots"]) == ["r"]


def test_colour_and_width_follow_the_environment(tiny, tmp_path):
    plain = invoke(["inspect", "mobot"])
    assert plain.exit_code == 0 and "\x1b[" not in plain.stdout
    styled = invoke(["inspect", "mobot"], env=Environment.captured(stdout_isatty=True, color=True))
    assert styled.exit_code == 0 and "\x1b[1mbase_footprint\x1b[0m" in styled.stdout
    narrow = invoke(["run", tiny, "--out", tmp_path / "r"], env=Environment.captured(width=50))
    table = [line for line in narrow.stdout.splitlines() if line[:1] in "┏┃┡│└"]
    assert table[-2].startswith("│ r ") and max(len(line) for line in table) <= 50


def test_errors_go_to_stderr_with_exit_2():
    assert invoke(["check", UNKNOWN_KEY]) == CommandResult(2, "", UNKNOWN_KEY_ERROR)


def test_invoke_writes_nothing_to_the_process_streams(capfd):
    assert invoke(["check", UNKNOWN_KEY]).exit_code == 2
    assert invoke(["--help"]).exit_code == 0
    assert capfd.readouterr() == ("", "")


def test_traceback_lets_the_error_propagate():
    with pytest.raises(ScenarioError, match="unknown key 'poze'"):
        invoke(["--traceback", "check", UNKNOWN_KEY])
    with pytest.raises(ScenarioError, match="unknown key 'poze'"):
        invoke(["check", UNKNOWN_KEY], env=Environment.captured(traceback=True))
    # --traceback is a root option: after the command's name it is a usage error like any other.
    late = invoke(["check", UNKNOWN_KEY, "--traceback"])
    assert late.exit_code == 2 and "No such option: --traceback" in late.stderr


def test_ctrl_c_is_exit_130(monkeypatch, tiny, tmp_path):
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr("mobot_cli.scenario.prepare.prepare", interrupted)  # where Ctrl-C lands in a run
    # Typer turns Ctrl-C into a quiet exit 130; the console script's entry point says
    # `mobot: interrupted` (tests/cli/test_interrupt.py), in-process callers get the code.
    assert invoke(["run", tiny, "--out", tmp_path / "r"]) == CommandResult(130, "", "")
    assert not (tmp_path / "r").exists()


def test_help_version_and_usage_errors_land_on_the_environment():
    helped = invoke(["--help"])
    assert (helped.exit_code, helped.stderr) == (0, "")
    assert helped.stdout.startswith("Usage: mobot [OPTIONS] COMMAND [ARGS]...") and "--traceback" in helped.stdout
    bare = invoke([])  # no command: the help, on stderr, as a usage error
    assert (bare.exit_code, bare.stdout, bare.stderr) == (2, "", helped.stdout)
    assert invoke(["--version"]) == CommandResult(0, f"mobot {__version__}\n", "")
    bogus = invoke(["bogus"])
    assert (bogus.exit_code, bogus.stdout) == (2, "") and "No such command 'bogus'" in bogus.stderr


def test_stdin_comes_from_the_environment_and_only_once():
    with pytest.raises(TypeError, match="give stdin through env"):
        invoke(["spawn", "r", "--stdin"], stdin="<robot/>", env=Environment.captured())
    # No live world is needed to see that --stdin was read: the request fails only at the endpoint.
    done = invoke(["spawn", "r", "--stdin", "--endpoint", "ipc:///nonexistent/mobot.sock", "--timeout", "0.2"],
                  stdin="<robot name='r'/>")
    assert (done.exit_code, done.stdout) == (4, "") and done.stderr.startswith("mobot: error: no live world")


def test_the_default_environment_asks_the_real_streams_once():
    """stdout to a pipe, stderr to a pseudo-terminal: only stderr is a terminal."""
    code = ("from mobot_cli.cli.environment import Environment; e = Environment.from_process(); "
            "print(e.stdout_isatty, e.stderr_isatty, e.traceback, e.color, e.width)")
    leader, follower = os.openpty()
    try:
        done = subprocess.run([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=follower, text=True,
                              timeout=60, check=True)
    finally:
        os.close(leader)
        os.close(follower)
    assert done.stdout == "False True False None None\n"
