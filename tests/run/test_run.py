"""`mobot run` end to end on the bundled robot: run folder, determinism, round trip, fidelity."""

from __future__ import annotations

import csv
import json
import math
from dataclasses import astuple
from pathlib import Path

import pytest

from mobot_cli.cli import invoke
from mobot_cli.scenario.prepare import prepare

REPO = Path(__file__).resolve().parents[2]
SCENARIOS = sorted((REPO / "scenarios").glob("*.yaml"))
HEADER = ("t,cmd_linear,cmd_angular,odom_x,odom_y,odom_yaw,odom_vx,odom_wz,"
          "true_x,true_y,true_z,true_roll,true_pitch,true_yaw,true_vx,true_wz\n")


def mobot(*args) -> int:
    """Run a quiet command: it prints nothing, whatever its exit code."""
    done = invoke(args)
    assert (done.stdout, done.stderr) == ("", ""), done
    return done.exit_code


def rows(path: Path) -> list[dict[str, float]]:
    with path.open() as f:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]


@pytest.fixture(scope="module")
def quickstart_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("qs") / "run"
    assert mobot("run", REPO / "scenarios" / "quickstart.yaml", "--out", out, "--quiet") == 0
    return out


def test_run_folder_layout_and_exact_csv_header(quickstart_run):
    assert sorted(p.name for p in quickstart_run.iterdir()) \
        == ["odom", "scenario.yaml", "summary.json", "trajectory.png"]
    csv_path = quickstart_run / "odom" / "mobot.csv"
    assert csv_path.read_text().splitlines(keepends=True)[0] == HEADER
    data = rows(csv_path)
    # 12 s at 240 Hz, logged every 5 steps (48 Hz): 577 rows including t = 0.
    assert len(data) == 12 * 48 + 1
    assert data[0]["t"] == 0.0 and data[-1]["t"] == pytest.approx(12.0)
    assert all(b["t"] - a["t"] == pytest.approx(5 / 240, abs=2e-6) for a, b in zip(data, data[1:]))


def test_summary_is_complete_and_matches_csv(quickstart_run):
    summary = json.loads((quickstart_run / "summary.json").read_text())
    assert summary["status"] == "ok"
    assert summary["steps"] == 2880 and summary["sim_time"] == 12.0 and summary["seed"] == 7
    last = rows(quickstart_run / "odom" / "mobot.csv")[-1]
    robot = summary["robots"]["mobot"]
    assert robot["final_pose"]["x"] == pytest.approx(last["true_x"], abs=1e-6)
    assert robot["final_pose"]["y"] == pytest.approx(last["true_y"], abs=1e-6)


def test_quickstart_drives_the_documented_path(quickstart_run):
    """1 m along +x, a 90 degree left turn in place, then 0.75 m along +y."""
    data = rows(quickstart_run / "odom" / "mobot.csv")
    end = data[-1]
    assert end["true_x"] == pytest.approx(1.0, abs=0.03)
    assert end["true_y"] == pytest.approx(0.75, abs=0.03)
    assert math.degrees(end["true_yaw"]) == pytest.approx(90.0, abs=3.0)
    summary = json.loads((quickstart_run / "summary.json").read_text())
    assert summary["robots"]["mobot"]["distance"] == pytest.approx(1.75, rel=0.03)
    # Encoder odometry is in the odom frame (origin at the spawn pose) and close to the truth.
    assert end["odom_x"] == pytest.approx(end["true_x"], abs=0.05)
    assert end["odom_y"] == pytest.approx(end["true_y"], abs=0.05)


def test_commands_hold_and_for_ends_with_a_stop(quickstart_run):
    data = {round(r["t"] * 240): r for r in rows(quickstart_run / "odom" / "mobot.csv")}
    assert data[115]["cmd_linear"] == 0.0  # settling
    assert data[120]["cmd_linear"] == 0.25  # at: 0.5
    assert data[1075]["cmd_linear"] == 0.25
    assert data[1080]["cmd_linear"] == 0.0  # for: 4.0 ends at 4.5 s
    assert data[1200]["cmd_angular"] == 0.5


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.stem)
def test_every_bundled_scenario_runs_deterministically(path, tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    assert mobot("run", path, "--out", a, "--quiet") == 0
    assert mobot("run", path, "--out", b, "--quiet") == 0
    files = sorted(p.relative_to(a) for p in (a / "odom").iterdir())
    assert files
    for rel in files:
        assert (a / rel).read_bytes() == (b / rel).read_bytes(), rel
    assert (a / "scenario.yaml").read_bytes() == (b / "scenario.yaml").read_bytes()


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.stem)
def test_resolved_scenario_round_trips(path, tmp_path):
    first = prepare(path)
    resolved = tmp_path / "resolved.yaml"
    resolved.write_text(first.resolved_yaml)
    again = prepare(resolved)
    assert again.plan == first.plan
    assert again.resolved_yaml == first.resolved_yaml


def test_rerunning_the_resolved_scenario_reproduces_the_run(quickstart_run, tmp_path):
    assert mobot("run", quickstart_run / "scenario.yaml", "--out", tmp_path / "again", "--quiet") == 0
    assert (tmp_path / "again" / "odom" / "mobot.csv").read_bytes() == \
        (quickstart_run / "odom" / "mobot.csv").read_bytes()


def test_fleet_names_namespaces_and_poses(tmp_path):
    plan = prepare(REPO / "scenarios" / "fleet.yaml").plan
    assert [r.name for r in plan.robots] == [f"mobot_{i}" for i in range(5)]
    assert [r.namespace for r in plan.robots] == [f"/mobot_{i}" for i in range(5)]
    assert [r.frame_prefix for r in plan.robots] == [f"mobot_{i}/" for i in range(5)]
    assert [r.pose.xyz[:2] for r in plan.robots] == [(0, 0), (1, 1), (2, 0), (1, 2), (0, 2)]


def test_json_prints_the_summary(tmp_path):
    code, out, err = astuple(invoke(["run", REPO / "scenarios" / "quickstart.yaml", "--out", tmp_path / "r",
                                     "--json", "--duration", "2"]))
    assert (code, err) == (0, "")
    summary = json.loads(out)
    assert summary["status"] == "ok" and summary["sim_time"] == 2.0
    assert summary == json.loads((tmp_path / "r" / "summary.json").read_text())


def test_set_and_seed_override(tmp_path):
    out = tmp_path / "r"
    assert mobot("run", REPO / "scenarios" / "quickstart.yaml", "--out", out, "--quiet", "--seed", "11",
                 "--set", "robots.mobot.pose.x=2.0", "--duration", "1") == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["seed"] == 11
    assert rows(out / "odom" / "mobot.csv")[0]["true_x"] == pytest.approx(2.0, abs=1e-3)


@pytest.mark.parametrize("name", ["quickstart", "patrol", "coverage"])
def test_resolved_scenario_matches_golden_file(name):
    """The resolved format is a contract: a change here must be deliberate (regenerate and review)."""
    golden = REPO / "tests" / "golden" / f"{name}.resolved.yaml"
    assert prepare(REPO / "scenarios" / f"{name}.yaml").resolved_yaml == golden.read_text()


def test_a_warm_headless_run_imports_no_plotting_viewer_or_mesh_code(tmp_path):
    """DESIGN: headless runs must not import plotting or viewer code (nor heavy mesh tooling)."""
    code = ("import sys, pathlib; from mobot_cli.scenario.prepare import prepare; "
            "from mobot_cli.run import execute; "
            f"p = prepare({str(REPO / 'scenarios' / 'quickstart.yaml')!r}); "
            f"execute(p.plan, p.resolved_yaml, pathlib.Path({str(tmp_path / 'r')!r})); "
            "print(sorted(m for m in ('matplotlib', 'yourdfpy', 'trimesh', 'rich', 'xacro', 'pyglet', 'cyclonedds', "
            "'viser', 'websockets', 'mobot_cli.view') "
            "if m in sys.modules))")
    import subprocess
    import sys
    first = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert first.returncode == 0, first.stderr  # the first run may fill the cache
    second = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert second.returncode == 0, second.stderr
    assert second.stdout.strip() == "[]"
    assert (tmp_path / "r" / "trajectory.png").stat().st_size > 10_000


def test_a_robot_falling_out_of_the_world_is_a_simulation_fault(tmp_path):
    """Exit 3, a located one-line error, and a summary that says fault (not ok)."""
    (tmp_path / "void.sdf").write_text(
        '<?xml version="1.0"?><sdf version="1.6"><world name="void"><model name="pillar">'
        "<static>true</static><pose>5 5 0.5 0 0 0</pose><link name='l'><collision name='c'><geometry>"
        "<box><size>1 1 1</size></box></geometry></collision></link></model></world></sdf>")
    scenario = tmp_path / "s.yaml"
    scenario.write_text("version: 1\nduration: 5\nworld: void.sdf\nrobots:\n"
                        "  - {name: faller, pose: {x: 0, y: 0, z: 1.0}}\n")
    code, out, err = astuple(invoke(["run", scenario, "--out", tmp_path / "r", "--quiet"]))
    assert (code, out) == (3, "")
    assert err.endswith("robot 'faller' fell out of the world (z = -10.1 m) at step 360. "
                        "Is there a floor under its spawn pose?\n")
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert summary["status"] == "fault" and summary["steps"] < 5 * 240
