"""`mobot sweep`: rows that match the physics, jobs-independent results, resume, isolation of bad runs."""

from __future__ import annotations

import csv
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from dataclasses import astuple
from pathlib import Path

import pytest

from mobot_cli.cli import CommandResult, invoke
from mobot_cli.sweep.execution import run_sweep
from mobot_cli.sweep.executor_local import LocalExecutor
from mobot_cli.sweep.expand import derive_seed, expand
from mobot_cli.sweep.spec import build_spec, split_values
from mobot_cli.sweep.task import run_task

REPO = Path(__file__).resolve().parents[2]
SPEED = """version: 1
name: speed
duration: 2.5
settle: 0.5
log: {rate_hz: 48}
robots:
  - name: mobot
    commands: [{at: 0.5, linear: 0.2, for: 1.5}]
expect:
  - {robot: mobot, distance: {max: 0.5}}
"""
GRID = ["--grid", "robots.mobot.commands.0.linear=0.1,0.2,0.4", "--grid", "robots.mobot.commands.0.for=1.0,1.5"]
HEADER = ("run,status,failure,seed,robots.mobot.commands.0.linear,robots.mobot.commands.0.for,expect_passed,"
          "expect_failed,wall_time,mobot.distance,mobot.x,mobot.y,mobot.yaw,mobot.collisions,folder,reason")


def rows(out: Path) -> list[dict[str, str]]:
    with (out / "results.csv").open() as f:
        return list(csv.DictReader(f))


def without_wall_time(table: list[dict[str, str]]) -> list[dict[str, str]]:
    return [{k: v for k, v in r.items() if k != "wall_time"} for r in table]


@pytest.fixture(scope="module")
def scenario(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("speed") / "speed.yaml"
    path.write_text(SPEED)
    return path


@pytest.fixture(scope="module")
def two_jobs(scenario) -> Path:
    out = scenario.parent / "jobs2"
    result = invoke(["sweep", scenario, *GRID, "--jobs", "2", "--out", out, "--quiet"])
    assert result == CommandResult(1, "", failed(1, out))
    return out


def failed(runs: int, out: Path) -> str:
    """What a quiet sweep prints when runs failed."""
    return f"mobot: {runs} of 6 runs failed; see {out}/results.csv\n"


def test_grid_rows_match_speed_times_time(two_jobs):
    assert (two_jobs / "results.csv").read_text().splitlines()[0] == HEADER
    table = rows(two_jobs)
    assert [r["run"] for r in table] == ["0", "1", "2", "3", "4", "5"]
    for r in table:
        speed, seconds = float(r["robots.mobot.commands.0.linear"]), float(r["robots.mobot.commands.0.for"])
        assert float(r["mobot.distance"]) == pytest.approx(speed * seconds, abs=1e-3)
        assert float(r["mobot.x"]) == pytest.approx(speed * seconds, abs=1e-3)
        assert r["mobot.collisions"] == "0"
        assert (two_jobs / r["folder"] / "odom" / "mobot.csv").is_file()
    # The one run past 0.5 m fails its expectation, and only it.
    assert [(r["status"], r["failure"]) for r in table] == [("passed", "")] * 5 + [("failed", "expectation")]
    assert table[5]["reason"] == "robot 'mobot' was expected to travel at most 0.5 m by the end; it travelled 0.600 m"
    assert (table[5]["expect_passed"], table[5]["expect_failed"]) == ("0", "1")
    assert [int(r["seed"]) for r in table] == [derive_seed(0, i) for i in range(6)]  # the scenario's seed is 0
    document = json.loads((two_jobs / "sweep.json").read_text())
    assert document["status"] == "complete"
    assert document["counts"] == {"total": 6, "passed": 5, "failed": 1, "not_run": 0}
    assert document["runs"][5]["params"] == {"robots.mobot.commands.0.linear": "0.4",
                                             "robots.mobot.commands.0.for": "1.5"}


def test_one_job_gives_the_same_results_as_two(scenario, two_jobs, tmp_path):
    out = tmp_path / "jobs1"
    result = invoke(["sweep", scenario, *GRID, "--jobs", "1", "--out", out, "--quiet"])
    assert result == CommandResult(1, "", failed(1, out))
    assert without_wall_time(rows(out)) == without_wall_time(rows(two_jobs))
    for run in ("0000", "0005"):
        for name in ("odom/mobot.csv", "scenario.yaml"):
            assert (out / "runs" / run / name).read_bytes() == (two_jobs / "runs" / run / name).read_bytes()


def test_resume_runs_only_what_is_missing(scenario, two_jobs, tmp_path):
    out = tmp_path / "resumed"
    shutil.copytree(two_jobs, out)
    lines = (out / "results.csv").read_text().splitlines(keepends=True)
    (out / "results.csv").write_text("".join(lines[:3]) + lines[3][:20])  # runs 0, 1 and a torn line
    kept = (out / "runs" / "0000" / "odom" / "mobot.csv").stat().st_mtime_ns
    shutil.rmtree(out / "runs" / "0004")
    result = invoke(["sweep", scenario, *GRID, "--out", out, "--resume", "--quiet"])
    assert result == CommandResult(1, "", failed(1, out))
    assert without_wall_time(rows(out)) == without_wall_time(rows(two_jobs))
    assert (out / "runs" / "0000" / "odom" / "mobot.csv").stat().st_mtime_ns == kept  # not run again
    assert (out / "runs" / "0004" / "odom" / "mobot.csv").is_file()  # run again
    # Resuming with other values is refused before anything runs.
    code, stdout, err = astuple(invoke(["sweep", scenario, "--grid", "robots.mobot.commands.0.linear=0.3",
                                        "--out", out, "--resume", "--quiet"]))
    assert (code, stdout) == (2, "") and err.startswith("mobot: error: ")


def faulty_runner(task):
    """A worker runner (test only) that segfaults, hangs or raises for chosen runs."""
    if task.index == 1:
        os.kill(os.getpid(), signal.SIGSEGV)
    if task.index == 2:
        time.sleep(600)
    if task.index == 3:
        raise RuntimeError("a bug in a run")
    return run_task(task)


def test_crashing_hanging_and_raising_runs_fail_alone(scenario, tmp_path):
    spec = build_spec(scenario, ["robots.mobot.pose.x=0,1,2,3,4,5"], [], [], None, None, ["duration=1.5"])
    report = run_sweep(expand(spec), tmp_path / "out", LocalExecutor(2, timeout=3.0, runner=faulty_runner), {})
    table = rows(tmp_path / "out")
    assert [(r["run"], r["status"], r["failure"]) for r in table] == [
        ("0", "passed", ""), ("1", "failed", "crash"), ("2", "failed", "timeout"), ("3", "failed", "error"),
        ("4", "passed", ""), ("5", "passed", "")]
    assert table[1]["reason"] == "the worker process was killed by SIGSEGV (a crash in the physics engine?)"
    assert table[2]["reason"] == "no result after 3 s: the run was stopped"
    assert table[3]["reason"] == "RuntimeError: a bug in a run"
    assert float(table[5]["mobot.x"]) == pytest.approx(5.0 + 0.2, abs=0.02)  # workers replaced, runs went on
    assert len(report.failed) == 3


def test_a_run_that_raises_is_a_failed_row(tmp_path):
    path = tmp_path / "two.yaml"
    path.write_text("version: 1\nname: two\nduration: 1\nrobots:\n  - name: a\n  - name: b\n    pose: {x: 2}\n")
    out = tmp_path / "out"
    # b on top of a cannot be spawned: found in the worker, not while preparing.
    assert invoke(["sweep", path, "--grid", "robots.b.pose.x=2,0", "--out", out, "--quiet"]) == \
        CommandResult(1, "", f"mobot: 1 of 2 runs failed; see {out}/results.csv\n")
    table = rows(out)
    assert [(r["status"], r["failure"]) for r in table] == [("passed", ""), ("failed", "error")]
    assert table[1]["reason"].startswith("robot 'b' spawned at x=0.000, y=0.000")
    assert "into robot 'a'" in table[1]["reason"]
    assert table[1]["a.x"] == "" and float(table[0]["b.x"]) == pytest.approx(2.0, abs=1e-3)


def test_ctrl_c_stops_cleanly_keeping_finished_rows(scenario, tmp_path):
    out = tmp_path / "stopped"
    proc = subprocess.Popen([sys.executable, "-m", "mobot_cli", "sweep", str(scenario), "--grid",
                             "robots.mobot.pose.x=0,1,2,3,4,5,6,7,8,9", "--set", "duration=5", "-j", "1",
                             "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and len(_lines(out / "results.csv")) < 2:
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGINT)  # as Ctrl-C in a terminal: the whole process group
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130
    deadline = time.monotonic() + 10
    while _running_in_session(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert _running_in_session(proc.pid) == []  # no worker left behind
    assert f"finished runs are in {out}/results.csv. Go on with: --resume --out {out}" in err
    assert "Traceback" not in err
    table = rows(out)
    assert 1 <= len(table) < 10 and all(r["status"] == "passed" for r in table)
    assert json.loads((out / "sweep.json").read_text())["status"] == "interrupted"


def _running_in_session(session: int) -> list[int]:
    """Live (not zombie) processes of a session, from /proc."""
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[3]) == session and fields[0] != "Z":
            found.append(int(stat.parent.name))
    return found


def _lines(path: Path) -> list[str]:
    try:
        return path.read_text().splitlines()
    except OSError:
        return []


def test_random_draws_are_seeded_and_in_bounds(scenario):
    def draw(seed):
        spec = build_spec(scenario, [], [], ["robots.mobot.pose.x=-1.5:1.5", "robots.mobot.commands.0.for=1:3"],
                          5, seed, [])
        return expand(spec)

    first = draw(3)
    values = [dict(v.params) for v in first.variants]
    assert len(values) == 5
    assert all(-1.5 <= float(v["robots.mobot.pose.x"]) <= 1.5 for v in values)
    assert all(v["robots.mobot.commands.0.for"] in ("1", "2", "3") for v in values)  # whole-number bounds
    assert [dict(v.params) for v in draw(3).variants] == values
    assert [dict(v.params) for v in draw(4).variants] != values
    assert [v.seed for v in first.variants] == [derive_seed(3, i) for i in range(5)]
    assert first.prepared[2].plan.robots[0].pose.xyz[0] == float(values[2]["robots.mobot.pose.x"])


def test_sweeping_the_seed_writes_one_seed_column(scenario, tmp_path):
    out = tmp_path / "seeds"
    # 0x10 is YAML for 16: the column holds the seed the run used, not the text swept.
    assert invoke(["sweep", scenario, "--grid", "seed=3,0x10", "--grid", "robots.mobot.commands.0.for=1.0",
                   "--jobs", "1", "--out", out, "--quiet"]) == CommandResult(0, "", "")
    header = (out / "results.csv").read_text().splitlines()[0].split(",")
    assert header.count("seed") == 1
    assert header[:5] == ["run", "status", "failure", "seed", "robots.mobot.commands.0.for"]
    table = rows(out)
    assert [(r["seed"], r["robots.mobot.commands.0.for"]) for r in table] == [("3", "1.0"), ("16", "1.0")]
    for r in table:
        assert json.loads((out / r["folder"] / "summary.json").read_text())["seed"] == int(r["seed"])


def test_seeds_and_value_splitting_are_stable():
    assert derive_seed(0, 0) == 1578226896  # changing this changes every recorded sweep's seeds
    assert derive_seed(0, 1) != derive_seed(1, 0)
    assert split_values("0, 0.5,[1, 2],{a: 1},'x,y'") == ["0", "0.5", "[1, 2]", "{a: 1}", "'x,y'"]


def test_a_sweep_file_with_zip_set_and_grid(tmp_path):
    (tmp_path / "speed.yaml").write_text(SPEED)
    sweep_file = tmp_path / "poses.yaml"
    sweep_file.write_text("""scenario: speed.yaml
name: poses
seed: 9
set: {robots.mobot.commands.0.for: 1.0}
grid: {robots.mobot.commands.0.linear: [0.1, 0.3]}
zip:
  robots.mobot.pose.x: [0, 2]
  robots.mobot.pose.y: [0, 1]
""")
    out = tmp_path / "out"
    code, stdout, err = astuple(invoke(["sweep", sweep_file, "--out", out, "--json"]))
    assert (code, err) == (0, "")
    printed = json.loads(stdout)
    assert printed["name"] == "poses" and printed["seed"] == 9
    table = rows(out)
    assert printed["results"] == table
    assert [(r["robots.mobot.commands.0.linear"], r["robots.mobot.pose.x"], r["robots.mobot.pose.y"])
            for r in table] == [("0.1", "0", "0"), ("0.1", "2", "1"), ("0.3", "0", "0"), ("0.3", "2", "1")]
    assert float(table[3]["mobot.x"]) == pytest.approx(2.0 + 0.3, abs=2e-3)  # 1 s at 0.3 m/s
    assert float(table[3]["mobot.y"]) == pytest.approx(1.0, abs=2e-3)


@pytest.mark.parametrize("args, message", [
    (["--grid", "robots.mobot.poze.x=0,1"],
     "mobot: error: --grid robots.mobot.poze.x=0,1, key 'robots.mobot.poze': unknown key 'poze'. Did you mean 'pose'?"),
    (["--grid", "robots.mobt.pose.x=0,1"],
     "mobot: error: --grid robots.mobt.pose.x=0,1: no item named 'mobt' in 'robots'. Did you mean 'mobot'?"),
    (["--grid", "robots.mobot.pose.x="], "mobot: error: --grid robots.mobot.pose.x=: no values given."),
    (["--grid", "robots.mobot.pose.x=0,abc"], "mobot: error: --grid robots.mobot.pose.x=0,abc, key "
     "'robots.mobot.pose.x': Input should be a valid number, unable to parse string as a number, got 'abc'"),
    ([], "mobot: error: nothing to sweep: the sweep has no runs."),
    (["--random", "robots.mobot.pose.x=0:1", "--samples", "0"],
     "mobot: error: --samples: samples must be at least 1, got 0: the sweep has no runs"),
    (["--random", "robots.mobot.pose.x=1:0", "--samples", "2"],
     "mobot: error: --random robots.mobot.pose.x=1:0: random LOW 1 must be below HIGH 0"),
    (["--zip", "robots.mobot.pose.x=0,1", "--zip", "robots.mobot.pose.y=0,1,2"],
     "mobot: error: --zip robots.mobot.pose.x=0,1: zipped lists must be of one length"),
    (["--grid", "duration=1,2", "--executor", "dask"], "mobot: error: --executor: unknown executor 'dask'."),
    (["--grid", "settle=0.5,1"], "(in run 1: settle=1)"),
])
def test_bad_sweep_input_is_exit_2_before_anything_runs(args, message, scenario, tmp_path):
    code, out, err = astuple(invoke(["sweep", scenario, *args, "--out", tmp_path / "out"]))
    assert (code, out) == (2, "")
    assert message in err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert not (tmp_path / "out").exists()


def test_a_sweep_file_naming_a_missing_scenario(tmp_path):
    sweep_file = tmp_path / "s.yaml"
    sweep_file.write_text("# a sweep\nscenario: nowhere.yaml\ngrid: {duration: [1, 2]}\n")
    assert invoke(["sweep", sweep_file, "--out", tmp_path / "out"]) == CommandResult(2, "", (
        f"mobot: error: {sweep_file}:2, key 'scenario': scenario file not found: {tmp_path}/nowhere.yaml. "
        "Paths in a sweep file are relative to the sweep file.\n"))
    assert not (tmp_path / "out").exists()


def test_an_existing_sweep_folder_is_not_overwritten(two_jobs, scenario):
    before = (two_jobs / "results.csv").read_bytes()
    code, out, err = astuple(invoke(["sweep", scenario, *GRID, "--out", two_jobs]))
    assert (code, out) == (2, "") and err.startswith("mobot: error: ")
    assert "already holds a sweep. Add --resume to finish it" in err
    assert (two_jobs / "results.csv").read_bytes() == before


def test_the_bundled_sweep_file_expands_to_checked_runs():
    spec = build_spec(REPO / "scenarios" / "sweeps" / "speeds.yaml", [], [], [], None, None, [])
    sweep = expand(spec)
    assert sweep.name == "speeds" and sweep.seed == 1
    assert [v.params for v in sweep.variants][:2] == [
        (("robots.mobot.commands.0.linear", "0.2"), ("robots.mobot.drive.odometry", "encoder")),
        (("robots.mobot.commands.0.linear", "0.2"), ("robots.mobot.drive.odometry", "ground_truth"))]
    assert len(sweep.variants) == 6
    assert sweep.prepared[1].plan.robots[0].drive.odometry == "ground_truth"
    assert len(sweep.prepared[0].plan.expectations) == 6


def test_the_bundled_passing_sweep_exits_0_with_every_row_passed(tmp_path):
    """scenarios/sweeps/engines.yaml: both engines x both odometry sources, every expectation met."""
    done = invoke(["sweep", str(REPO / "scenarios" / "sweeps" / "engines.yaml"), "--out", str(tmp_path / "s"),
                   "--jobs", "1", "--quiet"])
    assert done.exit_code == 0, done
    table = rows(tmp_path / "s")
    assert [(r["physics.engine"], r["robots.mobot.drive.odometry"]) for r in table] == [
        ("bullet", "encoder"), ("bullet", "ground_truth"), ("kinematic", "encoder"), ("kinematic", "ground_truth")]
    assert all((r["status"], r["expect_failed"], r["mobot.collisions"]) == ("passed", "0", "0") for r in table)
    assert all(float(r["mobot.x"]) == pytest.approx(1.0, abs=0.05) for r in table)  # 1 m east, then north


def test_pictures_only_when_asked(scenario, two_jobs, tmp_path):
    """No trajectory.png in a sweep's runs unless --pictures; the other files are the same bytes,
    and `mobot plot` draws a run folder later."""
    assert not list(two_jobs.rglob("*.png"))
    out = tmp_path / "pictures"
    result = invoke(["sweep", scenario, *GRID, "--jobs", "2", "--out", out, "--quiet", "--pictures"])
    assert result.exit_code == 1
    assert len(list((out / "runs").glob("*/trajectory.png"))) == 6
    for name in ("odom/mobot.csv", "scenario.yaml"):
        assert (out / "runs" / "0003" / name).read_bytes() == (two_jobs / "runs" / "0003" / name).read_bytes()
    copy = tmp_path / "later"
    shutil.copytree(two_jobs / "runs" / "0003", copy)
    assert invoke(["plot", copy]).exit_code == 0
    assert (copy / "trajectory.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
