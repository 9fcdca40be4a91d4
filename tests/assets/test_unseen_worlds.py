"""Classes of trouble public Gazebo worlds gave mobot, each on a small world written here.

- a COLLADA/OBJ mesh with exporter debris 1e17 m away (chaolmu's pot_flower in office_env_large)
- walls of a mesh that lean by micrometres (chaolmu's cpr_office), or by the 0.8 mrad of a
  roll of 1.57 for pi/2 (fetch_gazebo's test_zone): a gap on the map and for the planner
- a glass pane thinner than a cell (a box 1 cm thick): only its corners were on the map
- a raised floor slab over a ground plane (gazebo's cafe): every goal on it was refused as
  inside the slab, and its map was solid
- a dense furniture mesh near a robot (chaolmu's office_small): PyBullet's closest-point answer
  overflowed and the process crashed; and its 50,000-triangle cups on a table, answered a point
  per triangle at every clearance read once within the radius asked, took 0.29x real time
- a floor plan of a million small triangles (office_small, office_env_large): minutes to map
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from dataclasses import astuple
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.assets.world.worldplan import load_world
from mobot_cli.cli import invoke
from mobot_cli.common import meshfile
from mobot_cli.common.raster import Grid, fill_shape, fill_shapes
from mobot_cli.errors import WorldError

ROOT = Path(__file__).resolve().parents[2]


def obj(vertices, faces) -> str:
    return "".join(f"v {float(x)!r} {float(y)!r} {float(z)!r}\n" for x, y, z in vertices) + \
        "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces)


def mesh_world(tmp_path: Path, mesh: str, name: str = "m.obj", pose: str = "0 0 0 0 0 0", ground: str = "") -> Path:
    (tmp_path / name).write_text(mesh)
    path = tmp_path / "w.sdf"
    path.write_text(
        f"<?xml version='1.0'?><sdf version='1.9'><world name='w'>{ground}<model name='thing'><static>true</static>"
        f"<pose>{pose}</pose><link name='l'><collision name='c'><geometry><mesh><uri>{name}</uri></mesh>"
        "</geometry></collision></link></model></world></sdf>")
    return path


CUBE_V = [(x, y, z) for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 1.0)]
CUBE_F = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
          (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]


def test_triangles_far_from_a_meshs_origin_are_left_out_with_a_warning(tmp_path):
    far = [(8.1e17, 0.0, 6.9e17), (8.1e17, 1.0, 6.9e17), (8.1e17, 0.0, 6.9e17 + 1.0)]
    path = mesh_world(tmp_path, obj(CUBE_V + far, CUBE_F + [(8, 9, 10)]))
    world = load_world(str(path), tmp_path)
    bounds = world.summary["bounds"]
    assert bounds["min"] == pytest.approx([0, 0, 0]) and bounds["max"] == pytest.approx([1, 1, 1])
    assert world.summary["meshes"]["triangles"] == 12
    warning = next(n for n in world.notices if "km from its origin" in n)
    assert "mesh m.obj: 1 of its 13 triangles lie more than 10 km from its origin (up to 1.06e+18 m): " \
           "left out, as no robot reaches them" in warning
    assert "w.sdf:1, key 'model[thing].link[l].collision[c]'" in warning
    shape = world.plan.bodies[0].shapes[0]
    assert shape.mesh.endswith(".obj") and shape.mesh != str(tmp_path / "m.obj")  # the cleaned copy
    assert len(meshfile.read_mesh(shape.mesh)[1]) == 12
    # the map is the cube's, not a grid from 0 to 8e17 m (which is refused as too large)
    done = invoke(["map", path, "--out", tmp_path / "map"])
    assert done.exit_code == 0, done.stderr
    assert "40 x 40 cells of 0.05 m from (-0.5, -0.5), 441 occupied" in done.stdout


def test_a_mesh_whose_triangles_all_lie_far_away_is_a_located_error(tmp_path):
    path = mesh_world(tmp_path, obj([(v[0] + 2e4, v[1], v[2]) for v in CUBE_V], CUBE_F))
    with pytest.raises(WorldError) as err:
        load_world(str(path), tmp_path)
    assert "mesh m.obj: all of its 12 triangles lie more than 10 km from its origin" in str(err.value)
    assert err.value.location.key == "model[thing].link[l].collision[c]"


@pytest.mark.parametrize("lean", [0.0, 3e-5, 4e-4, 2.4e-3, 0.015])
def test_a_mesh_wall_leaning_by_micrometres_is_a_whole_wall_on_the_map(tmp_path, lean):
    """A 2 m wall along y = 1, 1 m tall, its top edge `lean` off the vertical: its shadow is a
    sliver thinner than any cell's centre can fall in, so it is drawn as its side, as an
    upright wall is (cpr_office's walls lean by 3e-5 m; a 3 m wall stood up by a roll of 1.57,
    as test_zone's, by 2.4 mm; 0.015 m is 0.86 degrees. Before, only their ends were mapped)."""
    wall = [(0.0, 1.0, 0.0), (2.0, 1.0, 0.0), (2.0, 1.0 + lean, 1.0), (0.0, 1.0 + lean, 1.0)]
    path = mesh_world(tmp_path, obj(wall, [(0, 1, 2), (0, 2, 3)]))
    done = invoke(["map", path, "--out", tmp_path / "map", "--origin", "-1,-1", "--size", "4,4"])
    assert done.exit_code == 0, done.stderr
    data = (tmp_path / "map" / "map.pgm").read_bytes()
    image = np.frombuffer(data[len(b"P5\n80 80\n255\n"):], dtype=np.uint8).reshape(80, 80)[::-1]
    row = image[int((1.0 + 1.0) / 0.05)]  # the cells from y = 1.0 to 1.05
    columns = np.nonzero(row == 0)[0]
    assert len(columns) == 41 and columns[0] == 20 and columns[-1] == 60  # x = 0 .. 2 m, every cell
    assert (image == 0).sum() == 41


def test_a_glass_pane_thinner_than_a_cell_is_a_whole_wall_on_the_map(tmp_path):
    """A 3 m x 1 cm box standing at 0.3 rad: no cell's centre lies in its shadow, yet every cell
    along it is occupied (before: its four corners' cells)."""
    path = tmp_path / "w.sdf"
    path.write_text(
        "<?xml version='1.0'?><sdf version='1.9'><world name='w'><model name='pane'><static>true</static>"
        "<pose>0 0 0.5 0 0 0.3</pose><link name='l'><collision name='c'><geometry><box><size>3 0.01 1</size>"
        "</box></geometry></collision></link></model></world></sdf>")
    done = invoke(["map", path, "--out", tmp_path / "map", "--origin", "-2,-1", "--size", "4,2"])
    assert done.exit_code == 0, done.stderr
    data = (tmp_path / "map" / "map.pgm").read_bytes()
    image = np.frombuffer(data[len(b"P5\n80 40\n255\n"):], dtype=np.uint8).reshape(40, 80)[::-1]
    # the occupied cells' centres, along the pane and across it: end to end without a gap, and
    # none further from it than a cell
    rows, columns = np.nonzero(image == 0)
    x, y = -2.0 + (columns + 0.5) * 0.05, -1.0 + (rows + 0.5) * 0.05
    along = np.sort(np.cos(0.3) * x + np.sin(0.3) * y)
    across = np.abs(-np.sin(0.3) * x + np.cos(0.3) * y)
    assert along[0] < -1.45 and along[-1] > 1.45 and np.diff(along).max() < 0.05 * math.sqrt(2.0)  # neighbours
    assert across.max() < 0.05 and 60 <= len(rows) <= 100


def _plate(n: int) -> str:
    """A 1 m x 0.5 m upright plate of 2 n^2 triangles, facing x, at x = 0."""
    return _upright(np.linspace(-0.5, 0.5, n + 1), np.linspace(0.0, 0.5, n + 1))


def _upright(ys, zs) -> str:
    """An upright grid at x = 0 over ``ys`` by ``zs``, two triangles a square."""
    n, m = len(ys) - 1, len(zs) - 1
    vertices = [(0.0, y, z) for z in zs for y in ys]
    faces = []
    for j in range(m):
        for i in range(n):
            a = j * (n + 1) + i
            faces += [(a, a + 1, a + n + 2), (a, a + n + 2, a + n + 1)]
    return obj(vertices, faces)


@pytest.mark.parametrize("engine", ["bullet", "kinematic"])
def test_clearance_to_a_dense_mesh_does_not_crash_and_is_the_gap(tmp_path, engine):
    """51,200 triangles within the metrics' 2 m of a six-link robot: PyBullet answered one point
    per triangle per link in one buffer, overflowed it and crashed the process (a segfault, so
    the run is a child process here)."""
    mesh_world(tmp_path, _plate(160), pose="1 0 0 0 0 0", ground="<include><uri>model://ground_plane</uri></include>")
    code, summary = _still_in_a_child(tmp_path, engine, 0.5)
    assert code == 0
    happened = summary["expectations"]["results"][0]["happened"]
    closest = float(happened.split("came within ")[1].split(" m")[0])
    assert closest == pytest.approx(1.0 - 0.10, abs=0.02)  # the chassis front is 0.10 m ahead
    assert "of world model 'thing'" in happened


def _still_in_a_child(tmp_path: Path, engine: str, clearance: float) -> tuple[int, dict]:
    """The bundled robot standing 0.2 s at the origin of tmp_path/w.sdf with a clearance
    expectation, in a child process (a PyBullet crash is a segfault): its exit code and summary."""
    scenario = tmp_path / "s.yaml"
    scenario.write_text(f"version: 1\nworld: w.sdf\nduration: 0.2\nphysics: {{engine: {engine}}}\nrobots:\n"
                        "  - name: mobot\n    description: mobot\n    pose: {x: 0.0, y: 0.0, yaw: 0.0}\n"
                        f"expect:\n  - {{robot: mobot, clearance: {{min: {clearance}}}}}\n")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    done = subprocess.run([sys.executable, "-m", "mobot_cli", "run", str(scenario), "--out", str(tmp_path / "out"),
                           "--quiet"], capture_output=True, text=True, env=env, timeout=300)
    assert done.returncode in (0, 1), done.stderr[-2000:]
    return done.returncode, json.loads((tmp_path / "out" / "summary.json").read_text())


def _dense_floor(n: int) -> str:
    """A 4 m square floor of 2 n^2 triangles round the origin, and a 1 m high block (x 1.2-1.4,
    y -1..1) in the same mesh."""
    xs = np.linspace(-2.0, 2.0, n + 1)
    vertices = [(x, y, 0.0) for y in xs for x in xs]
    faces = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            faces += [(a, a + 1, a + n + 2), (a, a + n + 2, a + n + 1)]
    base = len(vertices)
    vertices += [(x, y, z) for x in (1.2, 1.4) for y in (-1.0, 1.0) for z in (0.0, 1.0)]
    faces += [(base + a, base + b, base + c) for a, b, c in CUBE_F]
    return obj(vertices, faces)


@pytest.mark.parametrize("engine", ["bullet", "kinematic"])
def test_clearance_over_a_floor_split_into_chunks_is_the_gap_to_the_block(tmp_path, engine):
    """51,200 floor triangles are split into three PyBullet bodies (20,000 a body): the robot stands
    on one, and the next one's floor triangles are floor too, not an obstacle 0.25 m away."""
    mesh_world(tmp_path, _dense_floor(160))
    code, summary = _still_in_a_child(tmp_path, engine, 1.5)
    assert code == 1  # the expectation fails, with the distance
    assert summary["robots"]["mobot"]["collisions"] == 0
    happened = summary["expectations"]["results"][0]["happened"]
    closest = float(happened.split("came within ")[1].split(" m")[0])
    assert closest == pytest.approx(1.2 - 0.10, abs=0.02)  # the chassis front is 0.10 m ahead


def test_a_static_triangle_mesh_is_asked_about_link_by_link(tmp_path, monkeypatch):
    """The careful path for meshes (PyBullet answers them a point per triangle, and one answer for
    a whole robot beside a dense mesh overflowed its buffer and crashed AWS's and Clearpath's
    offices) is taken for every static mesh body: each query of one names the robot's link."""
    from mobot_cli.scenario.prepare import prepare
    from mobot_cli.sim import clearance
    from mobot_cli.sim.engine import open_world
    from mobot_cli.sim.pb import p

    mesh_world(tmp_path, _dense_floor(40))
    (tmp_path / "s.yaml").write_text("version: 1\nworld: w.sdf\nduration: 0.2\nrobots:\n"
                                     "  - {name: mobot, description: mobot, pose: {x: 0.0, y: 0.0}}\n")
    plan = prepare(tmp_path / "s.yaml").plan
    asked = []
    real = p.getClosestPoints

    def spy(a, b, distance, **kwargs):
        asked.append((b, "linkIndexA" in kwargs))
        return real(a, b, distance, **kwargs)

    with open_world(plan.physics, plan.world) as world:
        world.spawn(plan.robots[0])
        body, meshes = world._robots["mobot"].body, world._meshes  # noqa: SLF001 - the world's own bookkeeping
        monkeypatch.setattr(p, "getClosestPoints", spy)
        distance, what = clearance.nearest(world._cid, body, 2.0, [], world.label, meshes)  # noqa: SLF001
    assert what.startswith("world model 'thing'") and distance == pytest.approx(1.1, abs=0.02)
    about_meshes = [by_link for b, by_link in asked if b in meshes]
    assert about_meshes and all(about_meshes)


def _blob(n: int, half: float) -> str:
    """An upright square of side 2 ``half`` at x = 0, 0.18-0.22 m up, of 2 n^2 triangles."""
    g = np.linspace(-half, half, n + 1)
    return _upright(g, 0.2 + g)


@pytest.mark.parametrize("blob_x, nearest", [(-0.6, "wall"), (-0.35, "blob")])
def test_a_dense_mesh_further_than_the_nearest_point_is_not_asked_for_its_triangles(
        tmp_path, monkeypatch, blob_x, nearest):
    """A 20,000-triangle blob 0.40 m behind the robot, a plain wall 0.399 m ahead: the blob lies
    within the radius that finds the wall (0.57 m), and was answered a point per triangle (40,000
    points, at every read). Asked nearest box first and only within the nearest point found, it
    costs nothing; moved nearer than the wall, it is the answer."""
    from mobot_cli.scenario.prepare import prepare
    from mobot_cli.sim import clearance
    from mobot_cli.sim.engine import open_world
    from mobot_cli.sim.pb import p

    (tmp_path / "wall.obj").write_text(_plate(2))
    (tmp_path / "blob.obj").write_text(_blob(100, 0.02))
    models = "".join(
        f"<model name='{name}'><static>true</static><pose>{x} 0 0 0 0 0</pose><link name='l'><collision name='c'>"
        f"<geometry><mesh><uri>{name}.obj</uri></mesh></geometry></collision></link></model>"
        for name, x in (("wall", 0.5), ("blob", blob_x)))
    (tmp_path / "w.sdf").write_text("<?xml version='1.0'?><sdf version='1.9'><world name='w'>"
                                    f"<include><uri>model://ground_plane</uri></include>{models}</world></sdf>")
    (tmp_path / "s.yaml").write_text("version: 1\nworld: w.sdf\nduration: 0.2\nrobots:\n"
                                     "  - {name: mobot, description: mobot, pose: {x: 0.0, y: 0.0}}\n")
    plan = prepare(tmp_path / "s.yaml").plan
    answered: dict[int, int] = {}
    real = p.getClosestPoints

    def spy(a, b, radius, **kwargs):
        points = real(a, b, radius, **kwargs)
        answered[b] = answered.get(b, 0) + len(points or ())
        return points

    with open_world(plan.physics, plan.world) as world:
        world.spawn(plan.robots[0])
        body, meshes = world._robots["mobot"].body, world._meshes  # noqa: SLF001 - the world's own bookkeeping
        blob = next(uid for uid in meshes if "'blob'" in world.label(uid))
        cid = world._cid  # noqa: SLF001
        links = range(-1, p.getNumJoints(body, physicsClientId=cid))
        exact = {}  # every triangle within 2 m, link by link
        for uid in meshes:
            points = [point for link in links for point in real(body, uid, 2.0, linkIndexA=link, physicsClientId=cid)]
            exact[world.label(uid).split("'")[1]] = min(point[8] for point in points)
        monkeypatch.setattr(p, "getClosestPoints", spy)
        found, what = clearance.nearest(cid, body, 2.0, [], world.label, meshes)
    assert exact["wall"] == pytest.approx(0.399) and (exact["blob"] < exact["wall"]) == (nearest == "blob")
    assert f"'{nearest}'" in what and found == exact[nearest]
    assert (answered.get(blob, 0) == 0) == (nearest == "wall")


# --- the same cells and triangles, faster ------------------------------------------------

point = st.tuples(st.floats(-1.5, 1.8, allow_nan=False), st.floats(-1.5, 1.8, allow_nan=False))
snapped = st.tuples(st.integers(-60, 72), st.integers(-60, 72)).map(lambda p: (p[0] * 0.025, p[1] * 0.025))
shape = st.lists(st.one_of(point, snapped), min_size=2, max_size=5)


@settings(max_examples=60, deadline=None)
@given(st.lists(shape, min_size=1, max_size=40))
def test_fill_shapes_sets_the_cells_fill_shape_sets(shapes):
    grid = Grid(-1.0, -1.3, 0.05, 50, 60)
    one, many = grid.empty(), grid.empty()
    for polygon in shapes:
        fill_shape(one, grid, polygon)
    fill_shapes(many, grid, shapes)
    assert (one == many).all()


triangle = st.lists(st.one_of(point, snapped), min_size=3, max_size=3)


@settings(max_examples=80, deadline=None)
@given(st.lists(triangle, min_size=1, max_size=30), st.one_of(point, snapped))
def test_a_point_in_a_mesh_shadows_triangles_is_in_one_of_its_polygons(triangles, xy):
    """obstacle_at reads a mesh's shadow as an array of triangles: the same answer as the
    even-odd test of each triangle as a polygon, on their edges and corners too."""
    from mobot_cli.assets.world.floorplan import MeshShadow
    from mobot_cli.assets.world.freespace import _holds
    from mobot_cli.common.polygon import contains

    shadow = MeshShadow(np.array(triangles, dtype=float), np.zeros((0, 2, 2)))
    one_by_one = any(_holds(polygon, *xy) for polygon in shadow.polygons())
    assert _holds(shadow, *xy) == one_by_one == any(contains(t, *xy) for t in triangles if _boxed(t, *xy))


def _boxed(polygon, x, y) -> bool:
    return min(p[0] for p in polygon) <= x <= max(p[0] for p in polygon) and \
        min(p[1] for p in polygon) <= y <= max(p[1] for p in polygon)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(*[st.floats(-1e3, 1e3, allow_nan=False)] * 3), min_size=3, max_size=12),
       st.lists(st.tuples(*[st.integers(0, 11)] * 3), max_size=12), st.booleans())
def test_plain_obj_reads_as_the_line_by_line_reader(vertices, faces, grouped):
    text = "# comment\n" + obj(vertices, faces) + ("g part\nf 1 2 3\n" if grouped else "")
    fast = meshfile._plain_obj(text)
    slow_v, groups = meshfile.obj_groups(text)
    slow_f = np.concatenate(groups) if groups else np.zeros((0, 3), dtype=int)
    assert fast is not None
    assert np.array_equal(fast[0], slow_v) and np.array_equal(fast[1], slow_f)
    assert meshfile._plain_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/2 3/3\n") is None  # texture indices


def test_read_mesh_keeps_a_file_until_it_changes(tmp_path):
    path = tmp_path / "m.obj"
    path.write_text(obj(CUBE_V, CUBE_F))
    vertices, faces = meshfile.read_mesh(str(path))
    assert meshfile.read_mesh(str(path))[0] is vertices and not vertices.flags.writeable
    path.write_text(obj(CUBE_V, CUBE_F[:2]) + "# edited\n")
    assert len(meshfile.read_mesh(str(path))[1]) == 2
    code, *_ = astuple(invoke(["check", mesh_world(tmp_path, obj(CUBE_V, CUBE_F), name="n.obj")]))
    assert code == 0


RAISED = ("<?xml version='1.0'?><sdf version='1.9'><world name='w'><include><uri>model://ground_plane</uri></include>"
          "<model name='building'><static>true</static><link name='l'>"
          "<collision name='floor'><pose>0 0 0.095 0 0 0</pose><geometry><box><size>6 6 0.19</size></box></geometry>"
          "</collision><collision name='crate'><pose>2 1 0.44 0 0 0</pose><geometry><box><size>0.5 0.5 0.5</size>"
          "</box></geometry></collision></link></model></world></sdf>")


def test_goals_on_a_raised_floor_slab_are_on_its_floor(tmp_path):
    """Gazebo's cafe stands its floor, a 0.19 m slab, on a ground plane: the robot spawned over it
    stands on it, and its goals are checked in the band above it (not inside the slab)."""
    (tmp_path / "w.sdf").write_text(RAISED)
    scenario = {"version": 1, "name": "cafe", "world": "w.sdf", "duration": 8, "physics": {"engine": "kinematic"},
                "robots": [{"name": "r", "pose": {"x": -1.0, "y": 0.0},
                            "commands": [{"at": 0.5, "goto": {"x": 1.0, "y": 0.0}}]}]}
    path = tmp_path / "s.yaml"
    path.write_text(json.dumps(scenario))
    done = invoke(["run", path, "--out", tmp_path / "run", "--quiet"])
    assert done.exit_code == 0, done.stderr
    goal = json.loads((tmp_path / "run" / "summary.json").read_text())["robots"]["r"]["goals"][0]
    assert goal["status"] == "reached" and goal["error"] < 0.1
    # a goal in the crate on the slab is still refused, naming it
    scenario["robots"][0]["commands"][0]["goto"] = {"x": 2.0, "y": 1.0}
    path.write_text(json.dumps(scenario))
    refused = invoke(["run", path, "--out", tmp_path / "refused"])
    assert refused.exit_code == 2 and "goto (2, 1) is inside world model 'building'" in refused.stderr
    assert "building::l::crate" in refused.stderr


@pytest.mark.parametrize("how", ["scenario", "--floor"])
def test_the_map_of_a_raised_floor_is_measured_from_it(tmp_path, how):
    """`mobot map` of the scenario (its robots' floor) or of the world with --floor 0.19: the
    slab's area free, the crate on it occupied; from the ground plane it was all occupied."""
    (tmp_path / "w.sdf").write_text(RAISED)
    (tmp_path / "s.yaml").write_text(json.dumps({"version": 1, "name": "cafe", "world": "w.sdf", "duration": 1,
                                                 "robots": [{"name": "r", "pose": {"x": -1.0, "y": 0.0}}]}))
    args = [tmp_path / "s.yaml"] if how == "scenario" else [tmp_path / "w.sdf", "--floor", "0.19"]
    done = invoke(["map", *args, "--out", tmp_path / "map", "--origin", "-3,-3", "--size", "6,6"])
    assert done.exit_code == 0, done.stderr
    assert "above the floor at z = 0.19 m" in done.stdout
    data = (tmp_path / "map" / "map.pgm").read_bytes()
    image = np.frombuffer(data[len(b"P5\n120 120\n255\n"):], dtype=np.uint8).reshape(120, 120)[::-1]
    # the crate's 0.5 m square round (2, 1): its 10 x 10 cells, and the cells its corners touch
    assert (image[75:85, 95:105] == 0).sum() == 100
    assert (image == 0).sum() == (image[74:86, 94:106] == 0).sum() <= 121
