"""trajectory.png, the floor plan, `mobot plot`, `mobot check RUN_DIR` and the run table."""

from __future__ import annotations

import json
import math
import shutil
import subprocess
import sys
from dataclasses import astuple

import pytest
from PIL import Image

from mobot_cli.assets.world.floorplan import BAND, MeshShadow, convex_hull, floor_parts, floor_plan
from mobot_cli.cli import CommandResult, invoke
from mobot_cli.plan import StaticBody, StaticShape, WorldPlan
from mobot_cli.record.render import FLOOR, PALETTE, Track, dash_runs, nice_step, render

SCENARIO = """version: 1
name: plottest
duration: 4.0
log: {rate_hz: 48}
robots:
  - name: r_{i}
    count: 2
    poses: [[0, 0, 0], [0, 1.5, 0]]
    commands: [{at: 0.5, linear: 0.4, angular: 0.5}]
"""


def area(poly) -> float:
    return abs(sum(a[0] * b[1] - b[0] * a[1] for a, b in zip(poly, poly[1:] + poly[:1]))) / 2


def color_pixels(image: Image.Image, color, tol: int = 12) -> int:
    return sum(n for n, c in image.getcolors(1 << 20) if all(abs(a - b) <= tol for a, b in zip(c, color)))


@pytest.fixture(scope="module")
def plot_run(tmp_path_factory):
    base = tmp_path_factory.mktemp("plot")
    (base / "s.yaml").write_text(SCENARIO)
    out = base / "run"
    assert invoke(["run", base / "s.yaml", "--out", out, "--quiet"]) == CommandResult(0, "", "")
    return out


def test_trajectory_png_after_every_run(plot_run):
    image = Image.open(plot_run / "trajectory.png").convert("RGB")
    assert image.size == (1200, 900)
    colors = image.getcolors(1 << 20)
    white = next(n for n, c in colors if c == (255, 255, 255))
    assert white < 0.99 * 1200 * 900  # not blank: grid, labels, paths
    # Each robot's path in its own colour: ~0.4 m/s for 3.5 s is hundreds of pixels of line.
    assert color_pixels(image, PALETTE[0]) > 400 and color_pixels(image, PALETTE[1]) > 400
    assert color_pixels(image, PALETTE[2]) < 50  # no third robot


def test_floor_plan_projects_collision_shapes_from_above(tmp_path):
    quarter = (0.0, 0.0, math.sin(math.pi / 8), math.cos(math.pi / 8))  # 45 degrees about z
    lying = (math.sin(math.pi / 4), 0.0, 0.0, math.cos(math.pi / 4))  # 90 degrees about x
    wall = tmp_path / "wall.obj"  # a 2 m x 0.1 m wall, 2.5 m tall: its sides are seen edge-on
    v = [(x, y, z) for x in (0, 2) for y in (0, 0.1) for z in (0, 2.5)]
    faces = [(1, 2, 4), (1, 4, 3), (5, 7, 8), (5, 8, 6), (1, 5, 6), (1, 6, 2), (3, 4, 8), (3, 8, 7),
             (2, 6, 8), (2, 8, 4), (1, 3, 7), (1, 7, 5)]
    wall.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in v) + "".join(f"f {a} {b} {c}\n" for a, b, c in faces))
    world = WorldPlan(bodies=(
        StaticBody(name="box", xyz=(3.0, 0.0, 0.0), quat=quarter,
                   shapes=(StaticShape("box", (1.0, 0.5, 0.8), xyz=(0, 0, 0.4)),)),
        StaticBody(name="rug", shapes=(StaticShape("box", (4.0, 4.0, 0.01), xyz=(0, 0, 0.005)),)),  # below the band
        StaticBody(name="lamp", shapes=(StaticShape("box", (1.0, 1.0, 0.1), xyz=(0, 0, 2.5)),)),  # above it
        StaticBody(name="pole", shapes=(StaticShape("cylinder", (0.2, 1.0), xyz=(-2, 0, 0.5)),)),
        StaticBody(name="log", shapes=(StaticShape("cylinder", (0.2, 1.0), xyz=(-2, 3, 0.2), quat=lying),)),
        StaticBody(name="wall", xyz=(0.0, -3.0, 0.0), shapes=(StaticShape("mesh", (1.0, 1.0, 1.0), mesh=str(wall)),)),
        StaticBody(name="urdf", urdf='<robot name="u"><link name="a"><collision><origin xyz="5 5 0.3"/>'
                                     '<geometry><sphere radius="0.3"/></geometry></collision></link></robot>'),
    ))
    shapes = floor_plan(world)
    polygons = [p for p in shapes if len(p) > 2]
    segments = [p for p in shapes if len(p) == 2]
    gon = 12 * math.sin(2 * math.pi / 24)  # area of a 24-gon of radius 1
    # box 1 x 0.5; pole: r 0.2 upright; log: r 0.2, 1 m, lying; sphere r 0.3; no rug, lamp or wall top
    assert sorted(area(p) for p in polygons) == pytest.approx(sorted([0.5, gon * 0.04, 0.4, gon * 0.09]))
    box = next(p for p in polygons if abs(area(p) - 0.5) < 1e-6)
    assert max(x for x, _ in box) == pytest.approx(3 + (0.5 + 0.25) / math.sqrt(2))  # turned 45 degrees
    log = next(p for p in polygons if abs(area(p) - 0.4) < 1e-3)  # the lying cylinder: 1 m x 0.4 m
    assert (min(y for _, y in log), max(y for _, y in log)) == pytest.approx((2.5, 3.5))
    assert len(segments) == 8 and all(-3.0 <= y <= -2.9 for s in segments for _, y in s)  # the wall's sides
    assert BAND == (0.02, 2.0)


@pytest.mark.parametrize("n", [6, 40])  # 144 triangles drawn with outlines; 6,400 filled only
def test_a_meshs_shadow_kept_as_arrays_draws_the_pixels_of_its_polygons(tmp_path, n):
    """trajectory.png draws meshes' shadows from arrays (a furnished office casts 800,000
    triangles): pixel for pixel the picture of the same shadow as a list of polygons."""
    import numpy as np

    grid = np.linspace(0.0, 2.0, n + 1)
    vertices = [(x, y, 0.5 * (x + y)) for y in grid for x in grid]  # a slope: no face is upright
    faces = [(j * (n + 1) + i, j * (n + 1) + i + 1, (j + 1) * (n + 1) + i + 1) for j in range(n) for i in range(n)]
    faces += [(a, c, c - 1) for a, _, c in faces]
    wall = [(3.0, 0.0, 0.0), (3.0, 2.0, 0.0), (3.0, 2.0, 1.0), (3.0, 0.0, 1.0)]  # upright: drawn as a line
    mesh = tmp_path / "m.obj"
    mesh.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in vertices + wall) +
                    "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces) +
                    f"f {len(vertices) + 1} {len(vertices) + 2} {len(vertices) + 3}\n")
    world = WorldPlan(bodies=(
        StaticBody(name="box", shapes=(StaticShape("box", (0.5, 0.5, 0.5), xyz=(-1, 0, 0.25)),)),
        StaticBody(name="slope", xyz=(0.2, 0.1, 0.0), shapes=(StaticShape("mesh", (1.0, 1.0, 1.0), mesh=str(mesh)),)),
    ))
    parts = floor_parts(world)
    shadow = next(part for part in parts if isinstance(part, MeshShadow))
    assert len(shadow.triangles) == 2 * n * n and len(shadow.segments) == 1
    tracks = [Track("a", [(0, 0), (1, 0)], [(0, 0), (1, 0.1)])]
    render(tracks, parts, tmp_path / "arrays.png", "t")
    render(tracks, floor_plan(world), tmp_path / "polygons.png", "t")
    assert (tmp_path / "arrays.png").read_bytes() == (tmp_path / "polygons.png").read_bytes()
    assert color_pixels(Image.open(tmp_path / "arrays.png").convert("RGB"), FLOOR, tol=2) > 20_000


def test_floor_plan_is_drawn_under_the_paths(tmp_path):
    world = WorldPlan(bodies=(StaticBody(name="box", shapes=(StaticShape("box", (1.0, 1.0, 1.0), xyz=(2, 2, 0.5)),)),))
    out = tmp_path / "t.png"
    render([Track("a", [(0, 0), (1, 0)], [(0, 0), (1, 0.1)])], floor_plan(world), out, "title")
    image = Image.open(out).convert("RGB")
    assert color_pixels(image, FLOOR, tol=2) > 5000  # the 1 m box is ~80 px wide here
    assert not (tmp_path / "t.png.tmp").exists()


def test_plot_helpers():
    assert [nice_step(s) for s in (2.2, 10, 21, 0.3)] == [0.5, 2, 5, 0.05]
    runs = dash_runs([(0, 0), (10, 0), (10, 10)], 3, 2)
    assert runs == [[(0, 0), (3, 0)], [(5, 0), (8, 0)], [(10, 0), (10, 3)], [(10, 5), (10, 8)]]
    assert convex_hull([(0, 0), (1, 0), (1, 1), (0, 1), (0.5, 0.5)]) == [(0, 0), (1, 0), (1, 1), (0, 1)]


def test_mobot_plot_redraws_a_run_and_overlays_a_sweep(plot_run, tmp_path):
    out = tmp_path / "again.png"
    assert invoke(["plot", plot_run, "--out", out]) == CommandResult(0, f"wrote {out} (2 paths)\n", "")
    redrawn, original = Image.open(out).convert("RGB"), Image.open(plot_run / "trajectory.png").convert("RGB")
    assert redrawn.size == original.size
    assert color_pixels(redrawn, PALETTE[0]) == pytest.approx(color_pixels(original, PALETTE[0]), rel=0.05)
    sweep = tmp_path / "sweep"
    for i in range(3):
        shutil.copytree(plot_run, sweep / "runs" / f"000{i}")
    runs = [{"run": i, "folder": f"runs/000{i}", "params": {"robots.r_0.pose.x": str(i)}} for i in range(3)]
    (sweep / "sweep.json").write_text(json.dumps({"runs": runs}))
    assert invoke(["plot", sweep]) == CommandResult(0, f"wrote {sweep / 'trajectory.png'} (6 paths from 3 runs)\n", "")
    assert color_pixels(Image.open(sweep / "trajectory.png").convert("RGB"), PALETTE[5]) > 400
    from mobot_cli.record.replot import _swept_values

    assert _swept_values(sweep) == {"0000": "x=0", "0001": "x=1", "0002": "x=2"}


def test_mobot_plot_refuses_other_folders(tmp_path):
    assert invoke(["plot", tmp_path]) == CommandResult(2, "", f"mobot: error: '{tmp_path}' is neither a run folder nor "
                                                 "a sweep folder. Give the folder that mobot run --out or mobot "
                                                 "sweep --out wrote.\n")


def test_mobot_check_says_how_a_run_folder_ended(plot_run, tmp_path):
    assert invoke(["check", plot_run]) == CommandResult(
        0, f"ok: run 'plottest' in {plot_run}: 4 s simulated, 2 robot(s), every file in place\n", "")
    broken = shutil.copytree(plot_run, tmp_path / "broken")
    (broken / "trajectory.png").unlink()
    code, out, err = astuple(invoke(["check", broken]))
    assert (code, err) == (2, "")  # a verdict, not an error
    assert out.startswith(f"incomplete: run 'plottest' in {broken}: trajectory.png is missing\n")
    summary = json.loads((broken / "summary.json").read_text())
    summary.update(status="fault", error="robot 'r_0' left the world")
    (broken / "summary.json").write_text(json.dumps(summary))
    code, out, err = astuple(invoke(["check", broken, "--json"]))
    assert (code, err) == (3, "")
    result = json.loads(out)
    assert result["status"] == "fault"
    assert result["problems"] == ["summary.json says 'fault': robot 'r_0' left the world"]
    summary.update(status="ok", error=None, expectations={"passed": 1, "failed": 2, "results": []})
    (broken / "summary.json").write_text(json.dumps(summary))
    shutil.copy(plot_run / "trajectory.png", broken)
    code, out, err = astuple(invoke(["check", broken]))
    assert (code, err) == (1, "")
    assert out.startswith(f"failed: run 'plottest' in {broken}")


def test_run_prints_a_table_per_robot_and_json(plot_run, tmp_path):
    scenario = plot_run.parent / "s.yaml"
    code, text, err = astuple(invoke(["run", scenario, "--out", tmp_path / "t"]))
    assert (code, err) == (0, "")
    table = [line for line in text.splitlines() if line[:1] in "┏┃┡│└"]
    assert len(table) == 6 and max(len(line) for line in table) <= 80  # fits pipes and CI logs
    for word in ("plottest: 4 s simulated", "real time", "distance", "yaw", "odom error", "collisions",
                 "r_0", "r_1"):
        assert word in text
    code, out, err = astuple(invoke(["run", scenario, "--out", tmp_path / "j", "--json"]))
    assert (code, err) == (0, "")
    summary = json.loads(out)
    assert sorted(summary["robots"]) == ["r_0", "r_1"] and summary["status"] == "ok"


def test_csv_only_run_imports_neither_rosbags_nor_matplotlib_nor_rich(plot_run, tmp_path):
    quiet = ["run", str(plot_run.parent / "s.yaml"), "--out", str(tmp_path / "o"), "-q"]
    json_ = ["run", str(plot_run.parent / "s.yaml"), "--out", str(tmp_path / "j"), "--json"]
    code = ("import sys; from mobot_cli.cli import invoke; "
            f"assert invoke({quiet!r}).exit_code == 0; assert invoke({json_!r}).exit_code == 0; "
            "print(sorted(m for m in ('rosbags', 'matplotlib', 'PIL', 'rich') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "['PIL']"  # Pillow draws trajectory.png; nothing else is loaded


@pytest.mark.parametrize("kind", ["box", "mesh", "plane"])
@pytest.mark.parametrize("height", [0.034, 0.059, 0.19])
def test_the_band_is_measured_from_the_floor_under_the_robots(tmp_path, kind, height):
    """A floor above z = 0 is not an obstacle; a 10 cm step on it is; a shelf 2.1 m above it is not."""
    if kind == "mesh":  # a 10 x 10 m floor tile as two triangles, as a COLLADA floor becomes
        tile = tmp_path / "floor.obj"
        tile.write_text(f"v -5 -5 {height}\nv 5 -5 {height}\nv 5 5 {height}\nv -5 5 {height}\n"
                        "f 1 2 3\nf 1 3 4\n")
        floor = StaticShape("mesh", (1.0, 1.0, 1.0), mesh=str(tile))
    elif kind == "plane":
        floor = StaticShape("plane", (0.0, 0.0, 1.0), xyz=(0, 0, height))
    else:
        floor = StaticShape("box", (10.0, 10.0, 0.1), xyz=(0, 0, height - 0.05))
    world = WorldPlan(ground_plane=False, bodies=(
        StaticBody(name="floor", shapes=(floor,)),
        StaticBody(name="step", shapes=(StaticShape("box", (1.0, 1.0, 0.1), xyz=(2, 0, height + 0.05)),)),
        StaticBody(name="shelf", shapes=(StaticShape("box", (1.0, 1.0, 0.1), xyz=(-2, 0, height + 2.1)),)),
        StaticBody(name="table", shapes=(StaticShape("box", (1.0, 1.0, 0.05), xyz=(0, 2, height + 0.7)),)),
    ))
    robot_root = height + 0.033  # a base_link at wheel height, not on the floor itself
    areas = sorted(round(area(p), 6) for p in floor_plan(world, [(0.0, 0.0, robot_root)]) if len(p) > 2)
    assert areas == [1.0, 1.0]  # the step and the table top; not the floor, not the shelf
    from_zero = [p for p in floor_plan(world) if len(p) > 2]  # the old way: the floor is "in the band"
    assert kind == "plane" or max(area(p) for p in from_zero) >= 50  # a triangle of the tile, or the box


def test_trajectory_png_of_a_raised_floor_leaves_the_floor_white(tmp_path):
    world = WorldPlan(ground_plane=False, bodies=(
        StaticBody(name="stage", shapes=(StaticShape("box", (6.0, 6.0, 0.19), xyz=(0, 0, 0.095)),)),))
    from mobot_cli.record.trajectory import draw, drawn

    path = [(0.0, 0.0), (1.0, 0.0)]
    draw([drawn("r", path, path, 0.19)], WorldPlan(ground_plane=False), tmp_path / "empty.png", "stage", "")
    nothing = color_pixels(Image.open(tmp_path / "empty.png").convert("RGB"), FLOOR, tol=2)  # text edges
    draw([drawn("r", path, path, 0.19)], world, tmp_path / "t.png", "stage", "")
    assert color_pixels(Image.open(tmp_path / "t.png").convert("RGB"), FLOOR, tol=2) == nothing
    # a recording without heights: the band from z = 0, the stage drawn
    draw([drawn("r", path, path, None)], world, tmp_path / "t.png", "stage", "")
    assert color_pixels(Image.open(tmp_path / "t.png").convert("RGB"), FLOOR, tol=2) > 5000
