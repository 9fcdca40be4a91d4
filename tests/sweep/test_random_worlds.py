"""Randomised sweeps over generated worlds: each run draws a BARN-style world (its seed and
fill), a start in free space, a goal A* can reach, and lidar noise, all from the sweep seed;
the sweep runs unattended, resumes after a kill -9 to the same table, and reports the goal's
success rate and metrics per world. Bad free-space draws are located errors."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.assets.world.worldplan import load_world
from mobot_cli.cli import invoke
from tests.sweep.test_guard import session
from tests.sweep.test_sweep import rows, without_wall_time

REPO = Path(__file__).resolve().parents[2]
SWEEP = """\
scenario: {scenario}
name: random_barn
seed: 7
samples: 6
set: {{expect: [], duration: 4, robots.jackal.commands.0.timeout: 3.5}}
random:
  world.generate.seed: [0, 1000000]
  world.generate.fill: [0.1, 0.25]
  robots.jackal.sensors.front_laser.noise_stddev: [0.0, 0.02]
  robots.jackal.pose: {{region: [-4.0, -0.5, 1.0, 4.5], clearance: 0.4, yaw: [1.0, 2.1]}}
  robots.jackal.commands.0.goto: {{region: [-4.0, -0.5, 10.5, 13.0], clearance: 0.2}}
"""
DRAWN = ["world.generate.seed", "world.generate.fill", "robots.jackal.sensors.front_laser.noise_stddev",
         "robots.jackal.pose.x", "robots.jackal.pose.y", "robots.jackal.pose.yaw",
         "robots.jackal.commands.0.goto.x", "robots.jackal.commands.0.goto.y"]


@pytest.fixture(scope="module")
def sweep_file(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("random") / "random_barn.yaml"
    path.write_text(SWEEP.format(scenario=REPO / "scenarios" / "generated_barn.yaml"), encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def reference(sweep_file, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("reference") / "out"
    result = invoke(["sweep", str(sweep_file), "--jobs", "2", "--out", str(out)])
    assert result.exit_code == 0, result
    return out


def test_every_run_draws_its_world_start_goal_and_noise(reference):
    table = rows(reference)
    assert [r["run"] for r in table] == [str(i) for i in range(6)]
    assert all(r["status"] == "passed" for r in table)
    assert len({r["world.generate.seed"] for r in table}) == 6
    for r in table:
        assert all(r[k] for k in DRAWN)
        assert 0.1 <= float(r["world.generate.fill"]) <= 0.25
        assert -4.0 <= float(r["robots.jackal.pose.x"]) <= -0.5 and 1.0 <= float(r["robots.jackal.pose.y"]) <= 4.5
        assert 1.0 <= float(r["robots.jackal.pose.yaw"]) <= 2.1
        assert 10.5 <= float(r["robots.jackal.commands.0.goto.y"]) <= 13.0
        assert r["jackal.success"] in ("true", "false") and r["jackal.failure"] != "unreachable"
        assert r["jackal.spl"] and r["jackal.clearance_min"]  # the goal's metrics, per world
        run = reference / r["folder"]
        # the run's world is the drawn one, kept as an SDF file; the start is clear of every cylinder
        world = load_world(str(run / "generated.world")).plan
        assert f"seed: {r['world.generate.seed']}," in (run / "generated.world").read_text()
        x, y = float(r["robots.jackal.pose.x"]), float(r["robots.jackal.pose.y"])
        nearest = min(math.hypot(b.xyz[0] - x, b.xyz[1] - y) - b.shapes[0].size[0] for b in world.bodies)
        assert nearest >= 0.4 - 0.01
        noise = json.loads((run / "sensors/jackal/front_laser.json").read_text())
        assert noise.get("noise_stddev", float(r["robots.jackal.sensors.front_laser.noise_stddev"])) == \
            pytest.approx(float(r["robots.jackal.sensors.front_laser.noise_stddev"]))
    summary = json.loads((reference / "sweep.json").read_text())["goals"]["jackal"]
    successes = sum(r["jackal.success"] == "true" for r in table)
    assert summary["runs"] == 6 and summary["successes"] == successes
    assert summary["success_rate"] == round(successes / 6, 4)


def test_the_draws_are_the_same_every_time(sweep_file, reference):
    """Prepared again (as a rerun or --resume prepares it), the sweep draws the same values; its
    runs are byte for byte the same (test_a_killed_sweep_resumes_to_the_same_table)."""
    from mobot_cli.sweep.expand import expand
    from mobot_cli.sweep.spec import build_spec

    def draws(seed=None):
        return [v.params for v in expand(build_spec(sweep_file, [], [], [], None, seed, [])).variants]

    first = draws()
    assert first == draws()
    assert [dict(p) for p in first] == [{k: r[k] for k in DRAWN} for r in rows(reference)]
    assert all(a != b for a, b in zip(first, draws(seed=8)))  # another sweep seed, other draws


def test_a_killed_sweep_resumes_to_the_same_table(sweep_file, reference, tmp_path):
    out = tmp_path / "killed"
    proc = subprocess.Popen([sys.executable, "-m", "mobot_cli", "sweep", str(sweep_file), "-j", "2", "--out",
                             str(out), "--quiet"], cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline and proc.poll() is None:
        done = (out / "results.csv").read_text().count("\n") - 1 if (out / "results.csv").exists() else 0
        if done >= 2:
            break
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)  # the sweep and its workers, with no chance to tidy up
    proc.wait(timeout=60)
    deadline = time.monotonic() + 30
    while session(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert session(proc.pid) == []
    finished = len(rows(out)) if (out / "results.csv").exists() else 0
    assert 2 <= finished < 6
    resumed = invoke(["sweep", str(sweep_file), "-j", "2", "--out", str(out), "--resume"])
    assert resumed.exit_code == 0, resumed
    assert f"({finished} from before --resume)" in resumed.stdout
    assert "jackal: goals reached in " in resumed.stdout
    assert without_wall_time(rows(out)) == without_wall_time(rows(reference))
    for run in (f"runs/{i:04d}" for i in range(6)):
        assert (out / run / "odom/jackal.csv").read_bytes() == (reference / run / "odom/jackal.csv").read_bytes()


def test_bad_free_space_draws_are_located_errors(tmp_path):
    base = REPO / "scenarios" / "generated_barn.yaml"
    cases = {
        "robots.jackal.pose.x: {region: [0, 1, 0, 1]}": "'robots.jackal.pose.x' cannot be drawn from free space",
        "robots.jackal.pose: {region: [1, 0, 0, 1]}": "region must be [xmin, xmax, ymin, ymax] with xmin < xmax",
        "robots.jackal.pose: {region: [0, 1, 0, 1], clarance: 1}": "unknown key 'clarance' in a free-space draw",
        "robots.jackal.commands.0.goto: {region: [-4, 0, 11, 13], yaw: [0, 1]}": "a goal is drawn as x and y",
        "robots.jackal.pose: {region: [-2.4, -2.1, 6.9, 7.1], clearance: 3}": "no free place in region",
    }
    for line, words in cases.items():
        path = tmp_path / "bad.yaml"
        path.write_text(f"scenario: {base}\nsamples: 1\nrandom:\n  {line}\n", encoding="utf-8")
        result = invoke(["sweep", str(path), "--out", str(tmp_path / "out")])
        assert result.exit_code == 2 and result.stdout == "", (line, result)
        assert result.stderr.startswith(f"mobot: error: {path}:4, key 'random.{line.split(':')[0]}': "), result.stderr
        assert words in result.stderr, (line, result.stderr)
        assert not (tmp_path / "out").exists()


ITEM = st.one_of(st.integers(-10, 10), st.floats(-10, 10), st.text(max_size=2))
FIELD = st.one_of(st.none(), st.booleans(), st.integers(-20, 20), st.floats(allow_nan=True, allow_infinity=True),
                  st.text(max_size=3), st.lists(ITEM, max_size=5))


@settings(max_examples=200, deadline=None)
@given(key=st.sampled_from(["robots.r.pose", "robots.r.commands.0.goto", "robots.r.pose.x", "world.generate.seed"]),
       value=st.dictionaries(st.sampled_from(["region", "clearance", "yaw", "other"]), FIELD, max_size=4))
def test_any_free_space_entry_is_a_draw_or_a_located_error(key, value):
    from mobot_cli.errors import Location, MobotError
    from mobot_cli.sweep.freedraw import FreeDraw, parse

    where = Location(file="sweep.yaml", line=4, key=f"random.{key}")
    try:
        draw = parse(key, value, where)
    except MobotError as exc:
        assert exc.location == where
        return
    assert isinstance(draw, FreeDraw) and draw.region[0] < draw.region[1] and draw.region[2] < draw.region[3]
    assert 0 <= draw.clearance <= 10 and draw.yaw[0] <= draw.yaw[1]
