"""`mobot sweep --executor ray` on a local Ray instance gives the same results as the local pool."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from mobot_cli.cli import CommandResult, invoke

pytest.importorskip("ray", reason="Ray is an optional extra: pip install 'mobot-cli[ray]'")

SCENARIO = """version: 1
name: speed
duration: 2.0
log: {rate_hz: 48}
robots:
  - name: mobot
    commands: [{at: 0.5, linear: 0.2, for: 1.0}]
expect:
  - {robot: mobot, distance: {max: 0.3}}
"""


def rows(out: Path) -> list[dict[str, str]]:
    with (out / "results.csv").open() as f:
        return [{k: v for k, v in r.items() if k != "wall_time"} for r in csv.DictReader(f)]


def test_ray_and_local_sweeps_agree(tmp_path):
    scenario = tmp_path / "speed.yaml"
    scenario.write_text(SCENARIO)
    grid = ["--grid", "robots.mobot.commands.0.linear=0.1,0.4", "--grid", "robots.mobot.pose.y=0,1"]
    local, ray = tmp_path / "local", tmp_path / "ray"
    failed = "mobot: 2 of 4 runs failed; see {}/results.csv\n"
    assert invoke(["sweep", scenario, *grid, "--jobs", "2", "--out", local, "--quiet"]) == \
        CommandResult(1, "", failed.format(local))
    assert invoke(["sweep", scenario, *grid, "--executor", "ray", "--jobs", "2", "--out", ray, "--quiet"]) == \
        CommandResult(1, "", failed.format(ray))
    table = rows(ray)
    assert table == rows(local)
    assert [r["status"] for r in table] == ["passed", "passed", "failed", "failed"]  # 0.4 m/s goes 0.4 m
    for run in ("0000", "0003"):  # run folders came back from the Ray workers byte for byte
        for name in ("odom/mobot.csv", "scenario.yaml"):
            assert (ray / "runs" / run / name).read_bytes() == (local / "runs" / run / name).read_bytes()
        assert (ray / "runs" / run / "summary.json").is_file()


def test_an_unreachable_ray_address_is_bad_input(tmp_path):
    scenario = tmp_path / "speed.yaml"
    scenario.write_text(SCENARIO)
    done = invoke(["sweep", scenario, "--grid", "duration=1,2", "--executor", "ray", "--address", "127.0.0.1:1",
                   "--out", tmp_path / "out"])
    assert (done.exit_code, done.stdout) == (2, "")
    assert done.stderr.startswith("mobot: error: --address: cannot reach a Ray cluster at 127.0.0.1:1: ")
    assert not (tmp_path / "out").exists()
