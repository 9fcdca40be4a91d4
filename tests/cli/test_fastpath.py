"""`mobot run` read without Typer (cli/fastpath.py) means what Typer reads from the same line.

Each command line runs twice with the run itself replaced by a recorder: once as `mobot` runs
it (the fast reader when it takes the line) and once with the fast reader switched off (Typer).
The values the run gets, what is printed and the exit code must be the same.
"""

from __future__ import annotations

import inspect
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.cli import fastpath, invoke, runner

REPO = Path(__file__).resolve().parents[2]


def _both(args: list[str], monkeypatch) -> tuple[tuple, tuple]:
    """(exit code, stdout, stderr, the run's arguments) as mobot reads the line, then as Typer does."""
    outcomes = []
    signature = inspect.signature(runner.run_scenario)
    for typer_only in (False, True):
        calls = []

        def record(*a, **k):
            bound = signature.bind(*a, **k)
            bound.apply_defaults()
            values = dict(bound.arguments)
            del values["env"]
            values["set_"] = list(values["set_"])
            calls.append(values)
            return 0

        with monkeypatch.context() as patch:
            patch.setattr(runner, "run_scenario", record)
            if typer_only:
                patch.setattr(fastpath, "read", lambda args: None)
            out = invoke(args)
        outcomes.append((out.exit_code, out.stdout, out.stderr, calls))
    return outcomes[0], outcomes[1]


READ_HERE = [
    ["run", "s.yaml"],
    ["run", "s.yaml", "--out", "o", "--quiet"],
    ["--traceback", "run", "-q", "s.yaml", "-o", "runs/x", "--json"],
    ["run", "--set", "robots.mobot.pose.x=-2.0", "s.yaml", "--set", "seed=3", "--seed", "12", "--duration", "2.5"],
    ["run", "s.yaml", "--realtime", "--skip-missing", "--duration", "10"],
    ["run", "dir with space/s.yaml", "--out", "a b"],
]
LEFT_TO_TYPER = [
    [], ["run"], ["run", "--help"], ["run", "-h"], ["--help"], ["--version"], ["run", "s.yaml", "--bogus"],
    ["run", "s.yaml", "--out=o"], ["run", "s.yaml", "-qo", "o"], ["run", "s.yaml", "--seed", "-1"],
    ["run", "s.yaml", "--seed", "1.5"], ["run", "s.yaml", "--seed", "007"], ["run", "s.yaml", "--duration", "1e3"],
    ["run", "s.yaml", "--duration", "inf"], ["run", "s.yaml", "--duration", "2."], ["run", "a.yaml", "b.yaml"],
    ["run", "s.yaml", "--out", "a", "--out", "b"], ["run", "s.yaml", "-q", "--quiet"], ["run", "--", "s.yaml"],
    ["run", "s.yaml", "--ros2"], ["run", "s.yaml", "--view", "--view-port", "0"], ["run", "s.yaml", "--out"],
    ["run", "s.yaml", "--out", "-"], ["run", "s.yaml", "--out", ""], ["run", ""], ["check", "s.yaml"],
    ["run", "s.yaml", "--traceback"], ["--traceback", "--traceback", "run", "s.yaml"],
]


@pytest.mark.parametrize("args", READ_HERE)
def test_plain_run_lines_are_read_here_as_typer_reads_them(args, monkeypatch):
    assert fastpath.read(args) is not None
    mine, typer = _both(args, monkeypatch)
    assert mine == typer
    assert mine[0] == 0 and len(mine[3]) == 1


@pytest.mark.parametrize("args", LEFT_TO_TYPER)
def test_other_lines_are_left_to_typer(args, monkeypatch):
    assert fastpath.read(args) is None
    mine, typer = _both(args, monkeypatch)
    assert mine == typer


TOKENS = ["run", "run", "--traceback", "s.yaml", "t.yml", "--out", "-o", "dir", "--out=dir", "--set", "a.b=1",
          "x=-1", "--seed", "3", "0", "-3", "007", "1e3", "--duration", "2.5", "2.", ".5", "inf", "--quiet",
          "-q", "-qo", "--json", "--realtime", "--skip-missing", "--ros2", "--view", "--view-port", "--", "-",
          "", "--help", "--bogus", "--version"]


@settings(max_examples=120, deadline=None)
@given(st.lists(st.sampled_from(TOKENS), max_size=8).map(lambda tail: ["run", *tail]) |
       st.lists(st.sampled_from(TOKENS), max_size=8))
def test_any_line_means_the_same_to_both_readers(args):
    with pytest.MonkeyPatch.context() as monkeypatch:
        mine, typer = _both(args, monkeypatch)
    assert mine == typer


def test_a_plain_run_starts_without_typer_and_errors_stay_located(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("version: 1\nname: bad\nduration: 2\nrobots:\n  - name: r\n    pose: {x: 1, yaw: fast}\n")
    code = ("import sys; from mobot_cli.cli import invoke\n"
            f"o = invoke(['run', {str(bad)!r}, '--out', {str(tmp_path / 'out')!r}, '--quiet'])\n"
            "print(o.exit_code, sorted(m for m in ('typer', 'click', 'typer._click') if m in sys.modules))\n"
            "print(o.stderr, end='')")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=REPO)
    first, *error = done.stdout.splitlines()
    assert first == "2 []"
    assert error[0].startswith(f"mobot: error: {bad}:6, key 'robots.r.pose.yaw': Input should be a valid number"), error
    assert not (tmp_path / "out").exists()
