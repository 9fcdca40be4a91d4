"""`mobot barn` end to end on BARN-like worlds generated here (cylinders on BARN's grid, a
reference path file), with the kinematic engine; and its bad input."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest

from mobot_cli.cli import invoke
from mobot_cli.sweep.barn_score import optimal_time, reference_length

CYLINDER = """    <model name='unit_cylinder_{i}'>
      <static>1</static>
      <pose frame=''>{x:.6f} {y:.6f} 0 0 0 0</pose>
      <link name='link'>
        <collision name='collision'>
          <geometry><cylinder><radius>0.075</radius><length>1</length></cylinder></geometry>
        </collision>
        <visual name='visual'>
          <geometry><cylinder><radius>0.075</radius><length>1</length></cylinder></geometry>
        </visual>
      </link>
    </model>
"""
# BARN's worlds: a ground plane and unit cylinders (r 0.075 m, 1 m long, centred on the floor)
# on a 0.15 m grid, x in -4.5..0, y in 5..9.5; the robot starts at (-2.25, 3), the goal is (-2.25, 13).
WORLD = """<sdf version='1.6'>
  <world name='default'>
    <model name='ground_plane'>
      <static>1</static>
      <link name='link'>
        <collision name='collision'>
          <geometry><plane><normal>0 0 1</normal><size>100 100</size></plane></geometry>
        </collision>
      </link>
    </model>
{cylinders}  </world>
</sdf>
"""
STRAIGHT = [(15, c) for c in range(30)]  # cells (15, 0)..(15, 29): x = -2.325, y 5.075..9.425
AROUND = [(15, c) for c in range(12)] + [(r, 12) for r in range(16, 26)] + [(25, c) for c in range(13, 30)]


def cylinders(points: list[tuple[float, float]]) -> str:
    return "".join(CYLINDER.format(i=i, x=x, y=y) for i, (x, y) in enumerate(points))


def barn_like(folder: Path) -> Path:
    """world_0: cylinders along both sides, the straight line clear; world_1: a wall across it
    at y = 7 (its reference path goes round the wall's end)."""
    sides = [(x, 5.0 + 0.15 * k) for x in (-4.2, -0.3) for k in range(31)]
    wall = [(-3.75 + 0.15 * k, 7.0) for k in range(19)]  # x -3.75..-1.05
    (folder / "path_files").mkdir(parents=True)
    for n, (points, path) in enumerate(((sides, STRAIGHT), (sides + wall, AROUND))):
        (folder / f"world_{n}.world").write_text(WORLD.format(cylinders=cylinders(points)), encoding="utf-8")
        np.save(folder / "path_files" / f"path_{n}.npy", np.array(path, dtype=np.int64))
    return folder


DATA = Path(__file__).resolve().parents[1] / "data" / "barn_like"  # barn_like()'s output (docs/barn.md runs it)


@pytest.fixture(scope="module")
def worlds() -> Path:
    return DATA


def test_the_bundled_barn_like_worlds_are_the_generators(tmp_path):
    made = barn_like(tmp_path / "BARN")
    files = sorted(p.relative_to(made) for p in made.rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(DATA) for p in DATA.rglob("*") if p.is_file())
    assert all((made / f).read_bytes() == (DATA / f).read_bytes() for f in files)


def barn(*args: str):
    return invoke(["barn", *args])


def read_csv(path: Path) -> list[dict[str, str]]:
    with path.open(encoding="utf-8", newline="") as f:
        return list(csv.DictReader(f))


def test_clear_world_succeeds_and_wall_collides(worlds, tmp_path):
    out = tmp_path / "out"
    done = barn(str(worlds), "--worlds", "0-1", "--out", str(out), "--jobs", "2")
    assert done.exit_code == 0, done.stderr
    rows = read_csv(out / "barn.csv")
    assert [r["world"] for r in rows] == ["0", "1"]
    clear, walled = rows
    # 0.5 m/s after 1 s of 0.5 m/s^2: the clock starts 0.1 m out (0.63 s in), 9 m to the goal's circle.
    expected = 1.0 + (9.0 - 0.25) / 0.5 - math.sqrt(2 * 0.1 / 0.5)
    t_opt = optimal_time(reference_length(STRAIGHT))
    assert clear["status"] == "succeeded"
    assert (clear["success"], clear["collision"], clear["timeout"]) == ("1", "0", "0")
    assert float(clear["time"]) == pytest.approx(expected, abs=0.1)
    assert float(clear["optimal_time"]) == pytest.approx(t_opt, abs=1e-4)
    assert float(clear["score"]) == pytest.approx(t_opt / float(clear["time"]), abs=2e-4)
    # The wall: the robot's front (0.229 m ahead of its centre) meets a cylinder at y = 7 - 0.075.
    to_wall = 7.0 - 0.075 - 0.229 - 3.0
    assert walled["status"] == "collided" and walled["collision"] == "1" and walled["score"] == "0.0000"
    assert float(walled["time"]) == pytest.approx(1.0 + (to_wall - 0.25) / 0.5 - math.sqrt(0.4), abs=0.1)
    assert float(walled["optimal_time"]) == pytest.approx(optimal_time(reference_length(AROUND)), abs=1e-4)
    summary = json.loads((out / "barn.json").read_text())["summary"]
    assert summary["worlds"] == 2 and summary["success_rate"] == 0.5 and summary["collision_rate"] == 0.5
    assert summary["timeout_rate"] == 0.0 and summary["mean_time"] == pytest.approx(float(clear["time"]), abs=1e-4)
    assert summary["mean_score"] == pytest.approx(float(clear["score"]) / 2, abs=1e-4)
    assert "BARN: 2 worlds" in done.stdout and "0.500" in done.stdout
    # Every run is a normal run folder of the sweep, its world swept.
    sweep = read_csv(out / "sweep" / "results.csv")
    assert [Path(r["world"]).name for r in sweep] == ["world_0.world", "world_1.world"]
    assert (out / "sweep" / "runs" / "0001" / "trajectory.png").is_file()
    # The same with one job: byte for byte.
    again = tmp_path / "again"
    assert barn(str(worlds), "--worlds", "0-1", "--out", str(again), "--jobs", "1", "--quiet").exit_code == 0
    assert (again / "barn.csv").read_bytes() == (out / "barn.csv").read_bytes()


def test_too_slow_is_a_timeout(worlds, tmp_path):
    done = barn(str(worlds), "--worlds", "0", "--out", str(tmp_path / "slow"), "--max-linear", "0.05", "--json")
    assert done.exit_code == 0, done.stderr
    document = json.loads(done.stdout)
    assert document["worlds"][0]["status"] == "timeout" and document["worlds"][0]["time"] == 100.0
    assert document["summary"]["timeout_rate"] == 1.0 and document["summary"]["mean_time"] is None


@pytest.mark.parametrize("args, message", [
    (["{missing}"], "nowhere: BARN folder not found. Give the folder"),
    (["{worlds}", "--worlds", "300"], "world 300 is out of range: BARN's static worlds are 0..299"),
    (["{worlds}", "--worlds", "0-x"], "'0-x' is not a world number or a range"),
    (["{worlds}", "--worlds", "2"], "world_2.world: BARN world 2 is missing: no such file"),
    (["{worlds}", "--engine", "ode"], "unknown engine 'ode'"),
    (["{tmp}"], "no BARN worlds (world_N.world) in this folder"),
    # what the scenario model refuses points at the flag, not at the generated scenario
    (["{worlds}", "--worlds", "0", "--robot", "nosuch"], "--robot: 'nosuch' is neither a bundled robot"),
    (["{worlds}", "--worlds", "0", "--max-angular", "0"], "--max-angular: must be above 0, got 0"),
    (["{worlds}", "--worlds", "0", "--robot", "mobot", "--no-lidar"],
     "--no-lidar: the robot has no 2D lidar on (a sensor on topic scan) to turn off. Drop --no-lidar."),
])
def test_bad_input_is_a_located_error(worlds, tmp_path, args, message):
    filled = [a.format(missing=tmp_path / "nowhere", worlds=worlds, tmp=tmp_path) for a in args]
    done = barn(*filled, "--out", str(tmp_path / "out"))
    assert done.exit_code == 2 and message in done.stderr and "Traceback" not in done.stderr
    assert not (tmp_path / "out").exists()


def test_missing_path_file_names_it(worlds, tmp_path):
    folder = tmp_path / "BARN"
    folder.mkdir()
    (folder / "world_0.world").write_text((worlds / "world_0.world").read_text())
    done = barn(str(folder), "--worlds", "0", "--out", str(tmp_path / "out"))
    assert done.exit_code == 2
    assert f"{folder}/path_files/path_0.npy: the reference path of BARN world 0 is missing" in done.stderr


def test_an_unknown_planner_is_refused_at_its_flag(worlds, tmp_path):
    done = barn(str(worlds), "--worlds", "0", "--planner", "nosuch", "--out", str(tmp_path / "out"))
    assert done.exit_code == 2
    assert done.stderr == "mobot: error: --planner: Input should be 'astar', got 'nosuch'\n"
    assert not (tmp_path / "out").exists()


def test_the_planned_goal_goes_round_the_wall_pursuit_runs_into(worlds, tmp_path):
    # world 1: the straight line to the goal runs into a wall of cylinders (see above)
    done = barn(str(worlds), "--worlds", "1", "--planner", "astar", "--local", "dwb", "--out", str(tmp_path / "out"))
    assert done.exit_code == 0, done.stderr
    [row] = list(csv.DictReader(open(tmp_path / "out" / "barn.csv")))
    assert row["status"] == "succeeded" and float(row["score"]) > 0.0
