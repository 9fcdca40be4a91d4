"""``world: {generate: ...}`` in a scenario: parameters checked with located errors (and never
a traceback, whatever the mapping holds), reruns byte for byte, the run folder's world file
loading back to the world the run used, and `mobot map` of a scenario's generated world."""

from __future__ import annotations

from pathlib import Path

from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.assets.world.worldplan import load_world
from mobot_cli.cli import invoke
from mobot_cli.errors import MobotError
from mobot_cli.scenario.prepare import prepare

SCENARIO = """\
version: 1
name: gen
world:
  generate: {generate}
physics: {{engine: kinematic}}
duration: {duration}
robots:
  - name: r
    description: mobot
    args: {{lidar: "true"}}
    pose: {{x: {x}, y: {y}}}
    commands:
      - {{at: 0.5, goto: {{x: {gx}, y: {gy}}}, planner: astar, timeout: 20}}
"""


def scenario(folder: Path, generate: str, duration: float = 3.0, start=(0.0, 0.0), goal=(1.0, 0.0)) -> Path:
    path = folder / "gen.yaml"
    path.write_text(SCENARIO.format(generate=generate, duration=duration, x=start[0], y=start[1],
                                    gx=goal[0], gy=goal[1]), encoding="utf-8")
    return path


def test_bad_parameters_are_located_errors(tmp_path):
    cases = {
        "{kind: barn, seed: 1, fill: 1.5}": (4, "world.generate.fill", "less than or equal to 1"),
        "{kind: maze, fill: 0.2}": (4, "world.generate", "'fill' is not a parameter of kind maze: it takes seed, "
                                                        "cells, cell, wall, height"),
        "{kind: castle}": (4, "world.generate.kind", "'barn', 'boxes', 'maze' or 'rooms'"),
        "{kind: maze, cell: 0.4, wall: 0.3}": (4, "world.generate", "wall 0.3 m leaves no room in cells of 0.4 m"),
        "{kind: boxes, box_size: [2, 1]}": (4, "world.generate", "box_size [2, 1] runs backwards"),
        "{kind: rooms, seed: -1}": (4, "world.generate.seed", "greater than or equal to 0"),
        "{kind: rooms, sise: [3, 3]}": (4, "world.generate.sise", "unknown key 'sise'"),
    }
    for text, (line, key, words) in cases.items():
        result = invoke(["check", str(scenario(tmp_path, text))])
        assert result.exit_code == 2 and "Traceback" not in result.stderr, (text, result)
        assert result.stderr.startswith(f"mobot: error: {tmp_path / 'gen.yaml'}:{line}, key '{key}': "), result.stderr
        assert words in result.stderr, (text, result.stderr)
    assert "Did you mean 'size'?" in invoke(["check", str(scenario(tmp_path, "{kind: rooms, sise: [3, 3]}"))]).stderr


VALUES = st.one_of(st.integers(-5, 300), st.floats(-2, 300, allow_nan=False), st.booleans(), st.text(max_size=4),
                   st.lists(st.integers(-2, 50), max_size=3), st.lists(st.floats(-1, 30, allow_nan=False), max_size=3))
PARAMS = st.dictionaries(st.sampled_from(["seed", "fill", "smooth", "rows", "cols", "enclosure", "corridor", "size",
                                          "count", "box_size", "gap", "keep_clear", "cells", "cell", "rooms",
                                          "door", "jitter", "wall", "height"]), VALUES, max_size=3)


@settings(max_examples=60, deadline=None)
@given(kind=st.sampled_from(["barn", "boxes", "maze", "rooms"]), params=PARAMS)
def test_any_parameters_give_a_world_or_a_located_error(tmp_path_factory, kind, params):
    import json

    folder = tmp_path_factory.mktemp("gen")
    params = {k: v for k, v in params.items() if not (k in ("rows", "cols", "count") and isinstance(v, int) and v > 60)}
    path = scenario(folder, json.dumps({"kind": kind, **params}), duration=1.0, start=(30.0, 30.0))
    try:
        plan = prepare(path).plan
    except MobotError as exc:
        assert exc.location.file is not None and exc.location.line is not None, exc
        return
    assert plan.generated_world.startswith("<?xml") and plan.world.ground_plane


def test_reruns_are_byte_identical_and_the_saved_world_is_the_world_run(tmp_path):
    path = scenario(tmp_path, "{kind: rooms, seed: 5, size: [8, 6], rooms: [2, 2]}", duration=6.0,
                    start=(-2.0, -1.5), goal=(2.0, 1.5))
    first, second, again = tmp_path / "a", tmp_path / "b", tmp_path / "c"
    for out in (first, second):
        assert invoke(["run", str(path), "--out", str(out), "--quiet"]).exit_code == 0
    for name in ("odom/r.csv", "generated.world", "scenario.yaml", "sensors/r/lidar.npy"):
        assert (first / name).read_bytes() == (second / name).read_bytes(), name
    # the run folder's scenario.yaml generates the same world again, the same run again
    assert invoke(["run", str(first / "scenario.yaml"), "--out", str(again), "--quiet"]).exit_code == 0
    assert (again / "odom/r.csv").read_bytes() == (first / "odom/r.csv").read_bytes()
    # the world file kept in the run folder loads back to the obstacles the run had
    run_world = prepare(first / "scenario.yaml").plan.world
    assert load_world(str(first / "generated.world")).plan.bodies == run_world.bodies
    assert len(run_world.bodies) >= 4 + 2 + 2  # outer walls and the inner walls beside their doors
    # another seed, another world and another run
    other = tmp_path / "d"
    assert invoke(["run", str(path), "--set", "world.generate.seed=6", "--out", str(other), "--quiet"]).exit_code == 0
    assert (other / "generated.world").read_bytes() != (first / "generated.world").read_bytes()


def test_map_takes_a_scenario_with_a_generated_world(tmp_path):
    path = scenario(tmp_path, "{kind: maze, seed: 2, cells: [3, 3]}", duration=1.0, start=(0.0, 0.0))
    result = invoke(["map", str(path), "--out", str(tmp_path / "m1")])
    assert result.exit_code == 0, result
    assert invoke(["run", str(path), "--out", str(tmp_path / "run"), "--quiet"]).exit_code == 0
    result = invoke(["map", str(tmp_path / "run" / "generated.world"), "--out", str(tmp_path / "m2")])
    assert result.exit_code == 0, result
    assert (tmp_path / "m1/map.pgm").read_bytes() == (tmp_path / "m2/map.pgm").read_bytes()
    pgm = (tmp_path / "m1/map.pgm").read_bytes()
    assert pgm.count(bytes([0])) > 100  # walls drawn occupied
