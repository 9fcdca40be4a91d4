"""The README's examples are tests: its first commands, its scenario, its error message."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

from mobot_cli.cli import Outcome, invoke

REPO = Path(__file__).resolve().parent.parent
README = (REPO / "README.md").read_text()


def test_first_lines_are_the_install_and_run_and_the_test_commands():
    first_block = re.search(r"```bash\n(.*?)```", README, re.S).group(1).splitlines()
    assert first_block[0] == "python3 -m pip install -e . && mobot run scenarios/quickstart.yaml"
    assert first_block[1] == 'python3 -m pip install -e ".[test]" && python3 -m pytest -q'
    ci = (REPO / ".ci" / "run").read_text()
    assert first_block[1] in ci, ".ci/run must run exactly the README's test command"


def test_the_scenario_example_runs(tmp_path):
    example = next(b for b in re.findall(r"```yaml\n(.*?)```", README, re.S) if b.startswith("version: 1"))
    path = tmp_path / "example.yaml"
    path.write_text(example)
    assert invoke(["run", str(path), "--out", str(tmp_path / "r"), "--quiet"]) == Outcome(0, "", "")
    assert sorted(p.name for p in (tmp_path / "r" / "odom").iterdir()) == \
        ["mobot.csv", "mobot_0.csv", "mobot_1.csv", "mobot_2.csv"]


def test_the_error_example_is_what_mobot_prints():
    shown = re.search(r"\$ mobot run tests/bad/unknown_key.yaml\n(mobot: error: .*)\n", README).group(1)
    result = subprocess.run([sys.executable, "-m", "mobot_cli", "run", "tests/bad/unknown_key.yaml"],
                            capture_output=True, text=True, cwd=REPO, timeout=60)
    assert result.returncode == 2
    assert result.stderr == shown + "\n"


def test_the_in_process_example_runs(tmp_path, monkeypatch):
    """The Development section's invoke() example, run as written from a checkout-like folder."""
    block = re.search(r"```python\n(.*?)```", README[README.index("## Development"):], re.S).group(1)
    assert "invoke(" in block
    (tmp_path / "scenarios").symlink_to(REPO / "scenarios")
    monkeypatch.chdir(tmp_path)
    exec(compile(block, "README.md", "exec"), {})
    assert (tmp_path / "runs" / "api" / "summary.json").is_file() and (tmp_path / "runs" / "tty").is_dir()


def test_the_python_api_example_runs(tmp_path, monkeypatch):
    """The Python API section's go-to-goal controller reaches its goal as written."""
    section = README[README.index("## Python API and Gymnasium"):]
    block = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    monkeypatch.chdir(tmp_path)
    scope: dict = {}
    exec(compile(block, "README.md", "exec"), scope)
    sim = scope["sim"]
    final = sim.record.robots["r1"].final_pose
    assert abs(final.x - 1.5) < 0.1 and abs(final.y - 0.5) < 0.1
    assert (tmp_path / "runs" / "goal" / "odom" / "r1.csv").is_file()


def test_the_goals_example_runs_and_passes(tmp_path):
    """The Goals section's scenario: every goal reached, every check over time passed."""
    section = README[README.index("## Goals, patrols and coverage"):]
    example = re.search(r"```yaml\n(.*?)```", section, re.S).group(1)
    path = tmp_path / "goals.yaml"
    path.write_text(example)
    assert invoke(["run", str(path), "--out", str(tmp_path / "r"), "--quiet"]) == Outcome(0, "", "")
    record = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert [g["status"] for g in record["robots"]["mobot"]["goals"]] == ["reached"] * 4
    assert record["expectations"]["failed"] == 0


def test_the_python_api_scan_example_stops_in_front_of_the_wall(monkeypatch, tmp_path):
    """The Python API section's lidar example, as written: it stops 0.4 m short of the wall ahead."""
    section = README[README.index("## Python API and Gymnasium"):README.index("## ROS 2 bag")]
    block = next(b for b in re.findall(r"```python\n(.*?)```", section, re.S) if "sim.scan(" in b)
    monkeypatch.chdir(tmp_path)
    scope: dict = {}
    exec(compile(block, "README.md", "exec"), scope)
    sim, ahead, scan = scope["sim"], scope["ahead"], scope["scan"]
    assert 0.3 < ahead.min() < 0.4 and scan.t == pytest.approx(16.4, abs=0.3)  # 7.9 m at 0.5 m/s
    # The house's wall ahead of (-3, -2.5) has its face at x = 5.3 (8.3 m away at the start).
    final = sim.record.robots["r1"]
    assert final.final_pose.x + ahead.min() == pytest.approx(5.3, abs=0.03)
    assert (tmp_path / "runs" / "stop" / "sensors" / "r1" / "lidar.npy").is_file()
