"""A whole `mobot run` process on bad input: exit 2, one error on stderr, no traceback, whichever
side of loading finds it (the YAML read, --set, pydantic's validation, the resolver, the folder)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("args", [
    ["run", "tests/bad/unknown_key.yaml"],
    ["run", "tests/bad/sensor_missing_link.yaml", "--json"],
    ["run", "scenarios/quickstart.yaml", "--set", "robots[0].pose.x=wide"],
    ["run", "no/such/scenario.yaml"],
    ["run", "scenarios/quickstart.yaml", "--out", "README.md"],
    ["run", "tests/bad/malformed_yaml.yaml"],
    ["run", "tests/bad/missing_version.yaml"],
    ["run", "tests/bad/robot_syntax_error.yaml"],
    ["run", "tests/bad/world_spawn_in_furniture.yaml"],
    ["run", "scenarios/quickstart.yaml", "--set", "robots.nobody.pose.x=1"],
])
def test_bad_input_exits_2_with_one_error_and_no_traceback(args):
    done = subprocess.run([sys.executable, "-m", "mobot_cli", *args], capture_output=True, text=True, cwd=REPO,
                          timeout=120)
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.startswith("mobot: error: ") and "Traceback" not in done.stderr


def test_the_same_bad_file_reads_the_same_in_process_and_as_a_process():
    from mobot_cli.cli import invoke

    done = subprocess.run([sys.executable, "-m", "mobot_cli", "run", "tests/bad/unknown_key.yaml"],
                          capture_output=True, text=True, cwd=REPO, timeout=120)
    here = invoke(["run", REPO / "tests" / "bad" / "unknown_key.yaml"])
    assert here.exit_code == done.returncode == 2
    assert here.stderr.replace(str(REPO) + "/", "") == done.stderr
