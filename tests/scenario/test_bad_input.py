"""Every bad scenario in tests/bad gets its exact one-paragraph error, exit 2 and no run folder.

The expected texts are golden files beside the inputs; regenerate them after a deliberate
message change with MOBOT_UPDATE_GOLDEN=1 and review the diff.
"""

from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import astuple
from pathlib import Path

import pytest

from mobot_cli.cli import invoke

TESTS = Path(__file__).parent.parent  # tests/, which holds bad/
BAD = sorted((TESTS / "bad").glob("*.yaml"))


@pytest.mark.parametrize("path", BAD, ids=[p.stem for p in BAD])
def test_bad_scenario_error_text(path: Path, monkeypatch):
    monkeypatch.chdir(TESTS)
    code, out, err = astuple(invoke(["check", f"bad/{path.name}"]))
    assert code == 2
    assert out == ""
    assert "Traceback" not in err
    assert err.count("\n") == 1, "an error is one paragraph on one line"
    # Golden files must not depend on where the checkout is.
    err = err.replace(str(TESTS), "<tests>").replace(str(TESTS.parent), "<repo>")
    golden = path.with_suffix(".expected")
    if os.environ.get("MOBOT_UPDATE_GOLDEN"):
        golden.write_text(err)
    assert err == golden.read_text()


@pytest.mark.parametrize("path", BAD, ids=[p.stem for p in BAD])
def test_bad_scenario_leaves_no_run_folder(path: Path, monkeypatch, tmp_path):
    monkeypatch.chdir(TESTS)
    out_dir = tmp_path / "run"
    code, out, err = astuple(invoke(["run", f"bad/{path.name}", "--out", str(out_dir), "--quiet"]))
    assert code == 2, err
    assert out == "" and err.startswith("mobot: error: ")
    assert not out_dir.exists()


def test_real_process_exit_code_and_no_traceback(tmp_path):
    result = subprocess.run([sys.executable, "-m", "mobot_cli", "run", str(TESTS / "bad" / "unknown_key.yaml"),
                             "--out", str(tmp_path / "x")], capture_output=True, text=True, timeout=60)
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    assert result.stderr == (f"mobot: error: {TESTS}/bad/unknown_key.yaml:5, key 'robots.mobot.poze': "
                             "unknown key 'poze'. Did you mean 'pose'?\n")
    assert not (tmp_path / "x").exists()


def test_traceback_flag_shows_one(tmp_path):
    result = subprocess.run([sys.executable, "-m", "mobot_cli", "--traceback", "check",
                             str(TESTS / "bad" / "unknown_key.yaml")], capture_output=True, text=True, timeout=60)
    assert result.returncode != 0
    assert "Traceback" in result.stderr


def test_missing_scenario_file(tmp_path):
    code, out, err = astuple(invoke(["run", tmp_path / "nope.yaml", "--out", tmp_path / "r"]))
    assert code == 2 and out == ""
    assert err == (f"mobot: error: scenario file not found: {tmp_path / 'nope.yaml'}. "
                   "Check the path; bundled examples are in scenarios/.\n")
    assert not (tmp_path / "r").exists()


@pytest.mark.parametrize("override, message", [
    ("robots.mobt.pose.x=1", "no item named 'mobt' in 'robots'. Did you mean 'mobot'?"),
    ("physics.rate=100", "unknown key 'rate'. Did you mean 'rate_hz'?"),
    ("duration=0", "key 'duration': Input should be greater than 0, got 0"),
    ("robots.mobot.pose.z=.nan", "Input should be a finite number, got nan"),
    ("nonsense", "--set 'nonsense' is not KEY=VALUE"),
])
def test_bad_set_override(override, message, tmp_path):
    scenario = TESTS.parent / "scenarios" / "quickstart.yaml"
    code, out, err = astuple(invoke(["run", scenario, "--set", override, "--out", tmp_path / "r"]))
    assert code == 2 and out == ""
    assert err.startswith("mobot: error: ") and message in err
    assert not (tmp_path / "r").exists()


@pytest.mark.parametrize("args, message", [
    (["run"], "Missing argument 'scenario'"),
    (["bogus"], "No such command 'bogus'"),
    (["run", "scenarios/quickstart.yaml", "--bogus"], "No such option: --bogus"),
    (["run", "scenarios/quickstart.yaml", "--seed", "abc"], "Invalid value for '--seed'"),
])
def test_command_line_mistakes_exit_2_without_traceback(args, message):
    """Real processes: Typer's own usage errors must not escape as tracebacks."""
    result = subprocess.run([sys.executable, "-m", "mobot_cli", *args], capture_output=True, text=True,
                            timeout=60, cwd=TESTS.parent)
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    assert message in result.stderr and result.stdout == ""
