"""SDF worlds from small hand-written files: includes, poses, frames, geometry, bad input."""

from __future__ import annotations

import math
from dataclasses import astuple
from pathlib import Path

import pytest

from mobot_cli.assets.world import build as world_build
from mobot_cli.assets.world.worldplan import load_world
from mobot_cli.cli import invoke
from mobot_cli.errors import WorldError
from tests.collada import collada

CONFIG = '<?xml version="1.0"?><model><name>{name}</name><sdf version="1.5">old.sdf</sdf>' \
         '<sdf version="1.6">model.sdf</sdf></model>'


def sdf(body: str, version: str = "1.6") -> str:
    return f'<?xml version="1.0"?>\n<sdf version="{version}">\n{body}\n</sdf>\n'


def model_dir(root: Path, name: str, body: str) -> Path:
    folder = root / "models" / name
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "model.config").write_text(CONFIG.format(name=name))
    (folder / "model.sdf").write_text(sdf(body))
    (folder / "old.sdf").write_text("this is not read: model.config names a newer version")
    return folder


def world_file(root: Path, body: str, name: str = "w.world") -> Path:
    path = root / "worlds" / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(sdf(f"<world name='w'>\n{body}\n</world>"))
    return path


BOX = ("<model name='{name}'><static>{static}</static>{pose}<link name='l'>"
       "<collision name='c'><geometry><box><size>1 2 3</size></box></geometry></collision>"
       "</link></model>")


def box_model(name: str, pose: str = "", static: str = "true") -> str:
    return BOX.format(name=name, static=static, pose=f"<pose>{pose}</pose>" if pose else "")


def body(world, name):
    return next(b for b in world.plan.bodies if b.name == name)


# --- includes and poses ------------------------------------------------------------------

def test_wrapper_model_with_include_composes_poses(tmp_path):
    """The AWS layout: <model><static/><include/><pose/></model>, the model's own pose inside."""
    model_dir(tmp_path, "crate", box_model("crate", "1 0 0 0 0 0", static="false"))
    path = world_file(tmp_path, "<model name='crate_1'><static>true</static>"
                                "<include><uri>model://crate</uri></include>"
                                "<pose frame=''>0 5 0 0 0 1.5707963267948966</pose></model>")
    world = load_world(str(path), tmp_path)
    crate = body(world, "crate_1")
    assert crate.xyz == pytest.approx((0.0, 5.0, 0.0))
    shape = crate.shapes[0]
    assert shape.kind == "box" and shape.size == (1.0, 2.0, 3.0)
    assert shape.xyz == pytest.approx((1.0, 0.0, 0.0))  # the included model's pose, in the wrapper
    assert world.summary["models"] == 1 and world.summary["held_fixed"] == 0  # the wrapper is static
    assert world.summary["bounds"]["min"] == pytest.approx([-1.0, 5.5, -1.5])
    assert world.summary["bounds"]["max"] == pytest.approx([1.0, 6.5, 1.5])


def test_include_name_pose_and_static_override_the_model(tmp_path):
    model_dir(tmp_path, "crate", box_model("crate", "9 9 9 0 0 0", static="false"))
    path = world_file(tmp_path, "<include><uri>model://crate</uri><name>a</name><pose>1 2 0 0 0 0</pose>"
                                "<static>true</static></include>"
                                "<include><uri>model://crate</uri><name>b</name></include>")
    world = load_world(str(path), tmp_path)
    assert body(world, "a").xyz == pytest.approx((1.0, 2.0, 0.0))  # include pose replaces the model's
    assert body(world, "b").xyz == pytest.approx((9.0, 9.0, 9.0))  # none given: the model's own
    assert world.summary["held_fixed"] == 1  # b is not static and has no joints


def test_nested_models_relative_to_and_frames(tmp_path):
    path = world_file(tmp_path, """
      <model name='outer'><static>true</static><pose>10 0 0 0 0 0</pose>
        <frame name='corner'><pose>1 1 0 0 0 0</pose></frame>
        <link name='base'><pose relative_to='corner'>0 0 1 0 0 0</pose>
          <collision name='c'><geometry><sphere><radius>0.5</radius></sphere></geometry></collision></link>
        <model name='inner'><pose>0 0 2 0 0 3.141592653589793</pose>
          <link name='l'><pose>1 0 0 0 0 0</pose>
            <collision name='c'>
              <geometry><cylinder><radius>0.1</radius><length>1</length></cylinder></geometry></collision>
          </link></model>
      </model>""", "frames.sdf")
    world = load_world(str(path), tmp_path)
    shapes = {s.kind: s for s in body(world, "outer").shapes}
    assert shapes["sphere"].xyz == pytest.approx((1.0, 1.0, 1.0))
    assert shapes["cylinder"].xyz == pytest.approx((-1.0, 0.0, 2.0), abs=1e-9)  # turned by the nested pose
    assert world.summary["links"] == 2


def test_model_config_picks_the_newest_sdf(tmp_path):
    model_dir(tmp_path, "crate", box_model("crate"))  # old.sdf is garbage: reading it would fail
    path = world_file(tmp_path, "<include><uri>model://crate</uri></include>")
    assert len(load_world(str(path), tmp_path).plan.bodies) == 1


def test_search_paths_from_the_environment(tmp_path, monkeypatch):
    elsewhere = tmp_path / "elsewhere"
    model_dir(elsewhere, "crate", box_model("crate"))
    path = world_file(tmp_path / "w", "<include><uri>model://crate</uri></include>")
    with pytest.raises(WorldError, match="model 'crate' not found. Folders searched: "):
        load_world(str(path), tmp_path / "w")
    for var in ("GAZEBO_MODEL_PATH", "GZ_SIM_RESOURCE_PATH", "MOBOT_RESOURCE_PATH"):
        monkeypatch.setenv(var, str(elsewhere / "models"))
        assert len(load_world(str(path), tmp_path / "w").plan.bodies) == 1
        monkeypatch.delenv(var)


def test_ground_plane_and_other_planes(tmp_path):
    path = world_file(tmp_path, """
      <include><uri>model://ground_plane</uri></include>
      <model name='ramp'><static>true</static><pose>0 0 1 0.3 0 0</pose><link name='l'>
        <collision name='c'><geometry><plane><normal>0 0 1</normal></plane></geometry></collision>
      </link></model>""")
    world = load_world(str(path), tmp_path)
    assert world.plan.ground_plane  # the bundled ground_plane model: the simulation's own plane
    ramp = body(world, "ramp")
    assert [s.kind for s in ramp.shapes] == ["plane"] and ramp.xyz == pytest.approx((0, 0, 1))


# --- geometry -----------------------------------------------------------------------------

def test_collada_unit_and_node_transform_are_applied(tmp_path):
    """A 100 x 200 x 50 cm box whose node moves it 100 cm up becomes 1 x 2 x 0.5 m at z 1..1.5."""
    folder = model_dir(tmp_path, "cm_box", "<model name='cm_box'><static>true</static><link name='l'>"
                       "<collision name='c'><geometry><mesh><uri>model://cm_box/box.dae</uri>"
                       "<scale>2 1 1</scale></mesh></geometry></collision></link></model>")
    (folder / "box.dae").write_text(_collada_box(meter=0.01, size=(100, 200, 50), lift=100))
    path = world_file(tmp_path, "<include><uri>model://cm_box</uri></include>")
    world = load_world(str(path), tmp_path)
    shape = body(world, "cm_box").shapes[0]
    assert shape.kind == "mesh" and shape.mesh.endswith(".obj") and shape.size == (2.0, 1.0, 1.0)
    bounds = world.summary["bounds"]
    assert bounds["min"] == pytest.approx([-1.0, -1.0, 1.0]) and bounds["max"] == pytest.approx([1.0, 1.0, 1.5])
    assert world.summary["meshes"] == {"files": 1, "converted": 1, "triangles": 12}


def test_unsupported_geometry_is_left_out_with_a_warning(tmp_path):
    path = world_file(tmp_path, """
      <model name='terrain'><static>true</static><link name='l'><collision name='c'>
        <geometry><heightmap><uri>file://hm.png</uri></heightmap></geometry></collision></link></model>
      <model name='curb'><static>true</static><link name='l'><collision name='c'>
        <geometry><polyline><point>0 0</point><point>1 0</point><height>0.1</height></polyline></geometry>
      </collision></link></model>""" + box_model("crate"))
    world = load_world(str(path), tmp_path)
    assert [b.name for b in world.plan.bodies] == ["crate"]
    text = "\n".join(world.notices)
    assert "<heightmap> geometry, which mobot does not simulate" in text
    assert "<polyline> without three distinct points: it is left out" in text  # a line has no area


def test_lights_gui_physics_plugins_are_one_summary_line(tmp_path):
    path = world_file(tmp_path, "<light name='a' type='point'/><light name='b' type='point'/><gui/><scene/>"
                                "<physics type='ode'><max_step_size>0.001</max_step_size></physics>"
                                "<plugin name='p' filename='x.so'/>" + box_model("crate"))
    world = load_world(str(path), tmp_path)
    lines = [n for n in world.notices if "ignored" in n]
    assert lines == ["w.world: ignored 2 lights, gui, physics (max_step_size 0.001 s; mobot steps at "
                     "physics.rate_hz), 1 plugin, scene (mobot simulates collision geometry)"]


def test_state_poses_move_models_as_gazebo_classic_does(tmp_path):
    path = world_file(tmp_path, box_model("crate", "1 0 0 0 0 0")
                      + "<state world_name='w'><model name='crate'><pose>4 5 0 0 0 0</pose></model></state>")
    world = load_world(str(path), tmp_path)
    assert body(world, "crate").xyz == pytest.approx((4.0, 5.0, 0.0))
    assert world.summary["state_poses"] == 1


def test_absurd_pose_is_left_out_with_a_warning(tmp_path):
    path = world_file(tmp_path, box_model("book", "1 1 343582.7 0 0 0") + box_model("crate"))
    world = load_world(str(path), tmp_path)
    assert [b.name for b in world.plan.bodies] == ["crate"]
    assert world.summary["skipped_models"] == ["book"]
    assert any("'book' is placed at (1.0, 1.0, 343582.7)" in n for n in world.notices)


# --- bad input ----------------------------------------------------------------------------

@pytest.mark.parametrize("text, message, line", [
    ("<world name='w'><model name='m'><link name='l'></model></world>", "malformed XML: Opening and ending tag "
     "mismatch", 3),
    ("<world name='w'>" + box_model("m", "0 0 nan 0 0 0") + "</world>", "pose '0 0 nan 0 0 0' has a non-finite", 3),
    ("<world name='w'>" + box_model("m", "0 0 0") + "</world>", "pose '0 0 0' needs 6 numbers, got 3", 3),
    ("<world name='w'><include><uri></uri></include></world>", "<include> has no <uri>", 3),
    ("<world name='w'><model name='m'><link name='l'><pose relative_to='x'>0 0 0 0 0 0</pose></link></model>"
     "</world>", "link 'l' is placed relative to 'x', which this model does not have", 3),
    ("<world name='w'><model name='m'><link name='l'><collision name='c'><geometry><box><size>1 0 1</size>"
     "</box></geometry></collision></link></model></world>", "size of zero or less", 3),
])
def test_malformed_worlds_are_located_errors(tmp_path, text, message, line):
    path = tmp_path / "bad.world"
    path.write_text(f'<?xml version="1.0"?>\n<sdf version="1.6">\n{text}\n</sdf>\n')
    with pytest.raises(WorldError, match=message.replace("(", r"\(")) as info:
        load_world(str(path), tmp_path)
    assert info.value.location.file is not None and Path(info.value.location.file).name == "bad.world"
    assert info.value.location.line == line


def test_include_cycle_names_the_chain(tmp_path):
    model_dir(tmp_path, "a", "<model name='a'><include><uri>model://b</uri></include></model>")
    model_dir(tmp_path, "b", "<model name='b'><include><uri>model://a</uri></include></model>")
    path = world_file(tmp_path, "<include><uri>model://a</uri></include>")
    with pytest.raises(WorldError, match=r"include cycle: a/model.sdf -> b/model.sdf -> a/model.sdf"):
        load_world(str(path), tmp_path)


def test_missing_mesh_is_an_error_or_skipped_when_asked(tmp_path):
    path = world_file(tmp_path, "<model name='m'><static>1</static><link name='l'><collision name='c'>"
                                "<geometry><mesh><uri>meshes/gone.stl</uri></mesh></geometry></collision>"
                                "</link></model>" + box_model("crate"))
    with pytest.raises(WorldError, match=r"mesh 'meshes/gone.stl' not found. Folders searched: ") as info:
        load_world(str(path), tmp_path)
    assert info.value.location.line == 4 and "--skip-missing" in info.value.hint
    world = load_world(str(path), tmp_path, skip_missing=True)
    assert [b.name for b in world.plan.bodies] == ["crate"]
    assert any("collision 'c' left out: mesh 'meshes/gone.stl' not found" in n for n in world.notices)


def test_file_name_case_mismatch_names_both_names(tmp_path):
    folder = tmp_path / "worlds" / "meshes"
    folder.mkdir(parents=True)
    (folder / "box.stl").write_bytes(b"")
    path = world_file(tmp_path, "<model name='m'><static>1</static><link name='l'><collision name='c'>"
                                "<geometry><mesh><uri>meshes/Box.STL</uri></mesh></geometry></collision>"
                                "</link></model>")
    with pytest.raises(WorldError, match=r"'meshes/Box.STL' not found: .*has 'box.stl', which differs only "
                                         r"in case from 'Box.STL'"):
        load_world(str(path), tmp_path)


def test_fuel_include_needs_a_local_copy(tmp_path, monkeypatch):
    uri = "https://fuel.gazebosim.org/1.0/OpenRobotics/models/Ground Plane"
    path = world_file(tmp_path, f"<include><uri>{uri}</uri></include>" + box_model("crate"))
    monkeypatch.setenv("HOME", str(tmp_path / "home"))  # no Fuel cache of the user's
    with pytest.raises(WorldError, match=f"'{uri}' is on Gazebo Fuel and mobot never downloads: it needs a "
                                         "local copy") as info:
        load_world(str(path), tmp_path)
    assert "gz fuel download" in info.value.hint and "--skip-missing" in info.value.hint
    assert len(load_world(str(path), tmp_path, skip_missing=True).plan.bodies) == 1
    cached = tmp_path / "home/.gz/fuel/fuel.gazebosim.org/openrobotics/models/ground plane/3"
    cached.mkdir(parents=True)
    (cached / "model.config").write_text(CONFIG.format(name="gp"))
    (cached / "model.sdf").write_text(sdf(box_model("gp")))
    assert {b.name for b in load_world(str(path), tmp_path).plan.bodies} == {"gp", "crate"}


def test_unknown_bundled_world_suggests_one():
    with pytest.raises(WorldError, match="'hosue' is neither a bundled world") as info:
        load_world("hosue")
    assert "Did you mean 'house'?" in info.value.hint


# --- cache --------------------------------------------------------------------------------

def test_warm_load_reads_the_cache_and_an_edit_invalidates_it(tmp_path, monkeypatch):
    folder = model_dir(tmp_path, "crate", box_model("crate"))
    path = world_file(tmp_path, "<include><uri>model://crate</uri></include>")
    first = load_world(str(path), tmp_path)
    calls = []
    real = world_build.build_world
    monkeypatch.setattr(world_build, "build_world", lambda *a: calls.append(a) or real(*a))
    assert load_world(str(path), tmp_path) == first and calls == []
    (folder / "model.sdf").write_text(sdf(box_model("crate", "3 0 0 0 0 0")))
    assert body(load_world(str(path), tmp_path), "crate").xyz == pytest.approx((3.0, 0.0, 0.0))
    assert len(calls) == 1


def test_mobot_check_prints_the_world_summary(tmp_path):
    path = world_file(tmp_path, box_model("crate", "1 2 1.5 0 0 0") + "<light name='a' type='point'/>")
    code, out, err = astuple(invoke(["check", path]))
    assert code == 0
    assert out.splitlines() == [
        f"ok: world 'w' ({path})",
        "  models   1 (1 static)",
        "  shapes   1 collision shape in 1 link: box 1",
        "  meshes   none",
        "  ground   no ground plane: floors are world geometry",
        "  robots   none",
        "  ignored  light",
        "  extent   x 0.50..1.50, y 1.00..3.00, z 0.00..3.00 m (1.00 x 2.00 x 3.00 m)"]
    assert "ignored 1 light" in err
    missing = invoke(["check", tmp_path / "nope.world"])
    assert (missing.exit_code, missing.stdout) == (2, "") and missing.stderr.startswith("mobot: error: ")


def _collada_box(meter: float, size, lift: float) -> str:
    x, y, z = (s / 2 for s in size)
    corners = [(sx * x, sy * y, sz * z) for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
    faces = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
             (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]
    return collada(corners, faces, meter, matrix=f"1 0 0 0 0 1 0 0 0 0 1 {lift + z:g} 0 0 0 1")


def test_pose_helpers_round_trip():
    from mobot_cli.assets.world.pose import parse_pose, rpy, xyz_quat

    m = parse_pose("1 2 3 0.1 -0.2 0.3")
    assert rpy(m) == pytest.approx((0.1, -0.2, 0.3))
    xyz, quat = xyz_quat(parse_pose("0 0 0 0 0 90", degrees=True))
    assert quat == pytest.approx((0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4)))
    assert xyz_quat(parse_pose("1 2 3 0 0 0 1", quaternion=True))[0] == (1.0, 2.0, 3.0)


@pytest.mark.parametrize("axis, expected", [
    ("<xyz>0 0 1</xyz>", "0 0 1"),  # SDF 1.6+: the joint frame, which the URDF keeps
    ("<xyz>0 1 0</xyz><use_parent_model_frame>true</use_parent_model_frame>", "0 0 1"),
    ("<xyz expressed_in='__model__'>0 1 0</xyz>", "0 0 1"),
])
def test_sdf_robot_joint_axes_end_up_in_the_joint_frame(tmp_path, axis, expected):
    import xml.etree.ElementTree as ET

    from mobot_cli.assets.description.sdf import expand_sdf
    from mobot_cli.assets.resources import ResourceResolver

    (tmp_path / "r.sdf").write_text(sdf(f"""<model name='r'>
      <link name='base'><collision name='c'><geometry><box><size>0.3 0.2 0.1</size></box></geometry></collision></link>
      <link name='wheel'><pose>0 0.15 0 -1.5707963267948966 0 0</pose>
        <collision name='c'>
          <geometry><cylinder><radius>0.05</radius><length>0.02</length></cylinder></geometry></collision></link>
      <joint name='j' type='revolute'><parent>base</parent><child>wheel</child><axis>{axis}</axis></joint>
    </model>""", version="1.8"))
    expansion = expand_sdf(tmp_path / "r.sdf", ResourceResolver(tmp_path))
    joint = ET.fromstring(expansion.text).find("joint")
    assert joint.get("type") == "continuous"  # SDF's default +-1e16 limits: it turns freely
    assert joint.find("axis").get("xyz") == expected
    assert joint.find("origin").get("xyz") == "0 0.15 0"
    assert any("has no <inertial>" in str(n) for n in expansion.notices)


@pytest.mark.parametrize("canonical, link", [("", "blade::plate"), (" canonical_link='tip'", "blade::tip")])
def test_a_joint_may_name_a_nested_model_for_its_canonical_link(tmp_path, canonical, link):
    """SDF 1.8 (gz-sim's lift_drag_nested.sdf): <child>blade</child> names the nested model's
    canonical link, its canonical_link or else its first link."""
    import xml.etree.ElementTree as ET

    from mobot_cli.assets.description.sdf import expand_sdf
    from mobot_cli.assets.resources import ResourceResolver

    box = "<collision name='c'><geometry><box><size>0.2 0.2 0.2</size></box></geometry></collision>"
    inner = ("plate", "tip") if link == "blade::plate" else ("tip", "plate")  # the canonical link first
    (tmp_path / "r.sdf").write_text(sdf(f"""<model name='r'>
      <link name='base'>{box}</link>
      <model name='blade'{canonical}><pose>0.5 0 0 0 0 0</pose>
        <link name='plate'>{box}</link><link name='tip'><pose>0.3 0 0 0 0 0</pose>{box}</link>
        <joint name='inner' type='fixed'><parent>{inner[0]}</parent><child>{inner[1]}</child></joint></model>
      <joint name='j' type='fixed'><parent>base</parent><child>blade</child></joint>
    </model>""", version="1.8"))
    robot = ET.fromstring(expand_sdf(tmp_path / "r.sdf", ResourceResolver(tmp_path)).text)
    joint = robot.find("joint[@name='j']")
    assert joint.find("parent").get("link") == "base" and joint.find("child").get("link") == link
    assert joint.find("origin").get("xyz") == "0.5 0 0"  # the joint's frame: its child frame, the nested model's
    tip = robot.find("link[@name='blade::tip']/collision/origin")
    assert tip.get("xyz") == ("0.3 0 0" if link == "blade::tip" else "0 0 0")  # the tip 0.8 m out either way


# --- what Gazebo accepts ------------------------------------------------------------------

def test_a_comment_before_the_declaration_is_read_as_gazebo_reads_it(tmp_path):
    """Gazebo's cafe.world starts with a comment; libxml2 refuses that, tinyxml2 reads on."""
    path = tmp_path / "cafe.world"
    text = sdf("<world name='w'>\n" + box_model("table") + "\n</world>")
    path.write_text("<!-- Gazebo's cafe world -->\n\n" + text)
    world = load_world(str(path), tmp_path)
    assert [b.name for b in world.plan.bodies] == ["table"]
    path.write_text("\ufeff  <!-- a\nlong comment -->\n" + text.replace("</world>", "<bad>\n</world>"))
    with pytest.raises(WorldError, match="malformed XML: Opening and ending tag mismatch: bad line 7 ") as info:
        load_world(str(path), tmp_path)
    assert info.value.location.line == 8  # lines count as in the file: </world> closes <bad>


def test_a_zero_in_a_mesh_scale_leaves_that_collision_out(tmp_path):
    path = world_file(tmp_path, "<model name='decal'><static>1</static><link name='l'><collision name='c'>"
                                "<geometry><mesh><uri>meshes/gone.stl</uri><scale>1 0 1</scale></mesh>"
                                "</geometry></collision></link></model>" + box_model("crate"))
    world = load_world(str(path), tmp_path)  # not even --skip-missing is needed
    assert [b.name for b in world.plan.bodies] == ["crate"]
    assert [n.split(": ", 1)[1] for n in world.notices if "scale" in n] == [
        "collision 'c': mesh 'meshes/gone.stl' has a zero in its <scale> (1 0 1), which flattens it: "
        "left out"]


def test_a_plane_with_a_size_is_a_thin_box_of_that_size(tmp_path):
    """A poster on a wall (facing -x at x = 2) and a finite platform; a plane without a size,
    and the ground plane (size 100 x 100 at z = 0), stay infinite."""
    path = world_file(tmp_path, """
      <include><uri>model://ground_plane</uri></include>
      <model name='poster'><static>true</static><pose>2 0 0.4 0 0 0</pose><link name='l'>
        <collision name='c'><geometry><plane><normal>-1 0 0</normal><size>1.5 0.8</size></plane>
        </geometry></collision></link></model>
      <model name='platform'><static>true</static><pose>5 5 0.19 0 0 0.5</pose><link name='l'>
        <collision name='c'><geometry><plane><normal>0 0 1</normal><size>3 2</size></plane>
        </geometry></collision></link></model>
      <model name='wall'><static>true</static><pose>-4 0 0 0 0 0</pose><link name='l'>
        <collision name='c'><geometry><plane><normal>1 0 0</normal></plane></geometry></collision>
      </link></model>""")
    world = load_world(str(path), tmp_path)
    assert world.plan.ground_plane
    poster, platform, wall = (body(world, n) for n in ("poster", "platform", "wall"))
    (shape,) = poster.shapes
    assert (shape.kind, shape.size) == ("box", (1.5, 0.8, world_build.THIN_PLANE))
    # its face on the plane, the box behind it; 1.5 m wide (y), 0.8 m tall (z)
    assert world.summary["bounds"]["min"] == pytest.approx([2.0, -0.75, 0.0])
    assert platform.shapes[0].kind == "box" and platform.shapes[0].size[:2] == (3.0, 2.0)
    assert platform.shapes[0].xyz == pytest.approx((0.0, 0.0, -world_build.THIN_PLANE / 2))
    assert [s.kind for s in wall.shapes] == ["plane"]


def test_many_missing_includes_make_one_warning(tmp_path, monkeypatch):
    """Models named once, folders listed once; three or fewer keep a warning each."""
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    fuel = "https://fuel.gazebosim.org/1.0/OpenRobotics/models/{}"
    includes = ([f"<include><name>t{i}</name><uri>{fuel.format('Table')}</uri></include>" for i in range(5)]
                + [f"<include><name>c{i}</name><uri>{fuel.format('Chair')}/2</uri></include>" for i in range(3)]
                + [f"<include><name>s{i}</name><uri>model://shelf</uri></include>" for i in range(2)])
    path = world_file(tmp_path, "".join(includes) + box_model("crate"))
    world = load_world(str(path), tmp_path, skip_missing=True)
    (notice,) = [n for n in world.notices if "left out" in n]
    folders = notice.split("Folders searched: ")[1]
    assert notice.startswith(f"{path}: 10 includes and meshes left out (skip_missing): 8 from Gazebo Fuel "
                             "without a local copy (mobot never downloads; `gz fuel download -u URL` fills "
                             "~/.gz/fuel): Chair x3, Table x5; 2 models not found: shelf x2. Folders searched: ")
    assert folders.split("; ")[:2] == [str(tmp_path / "worlds"), str(tmp_path)]
    assert notice.count(f"{tmp_path}; ") == 1  # each folder once
    few = world_file(tmp_path, "\n".join(includes[:2]) + box_model("crate"), name="few.world")
    notices = load_world(str(few), tmp_path, skip_missing=True).notices
    assert sum("include left out" in n for n in notices) == 2


def test_an_entity_of_the_doctype_is_refused_not_read_as_nothing(tmp_path):
    """Gazebo's SDF reader does not expand a DOCTYPE's entities; mobot's parser leaves them
    unexpanded (no entity bombs, no files read through them), so a <size>&d; 1 1</size> read
    as text would be a box of nothing, built as a default one: it is refused, naming the entity."""
    world = tmp_path / "w.sdf"
    world.write_text('<?xml version="1.0"?><!DOCTYPE sdf [<!ENTITY d "2">]>\n<sdf version="1.6"><world name="w">'
                     '<model name="m"><static>true</static><link name="l"><collision name="c"><geometry><box>'
                     '<size>&d; 1 1</size></box></geometry></collision></link></model></world></sdf>')
    with pytest.raises(WorldError, match=r"the XML entity &d; is not expanded") as info:
        load_world(str(world), tmp_path)
    assert info.value.location.line == 2


@pytest.mark.parametrize("joint, kind", [
    ("<joint name='j' type='revolute'><parent>world</parent><child>l</child>"
     "<axis><xyz>0 0 1</xyz><limit><lower>0</lower><upper>0</upper></limit></axis></joint>", "fixed"),
    ("<joint name='j' type='fixed'><parent>world</parent><child>l</child></joint>", "fixed"),
    ("<joint name='j' type='revolute'><parent>world</parent><child>l</child>"  # a door on its hinge
     "<axis><xyz>0 0 1</xyz><limit><lower>-1</lower><upper>1</upper></limit></axis></joint>", "anchored"),
    ("<link name='flap'><collision name='c'><geometry><box><size>0.1 0.1 0.1</size></box></geometry></collision>"
     "</link><joint name='j' type='revolute'><parent>l</parent><child>flap</child>"
     "<axis><xyz>0 0 1</xyz><limit><lower>-1</lower><upper>1</upper></limit></axis></joint>", "robot"),
])
def test_a_model_hung_from_world_is_scenery(tmp_path, joint, kind):
    """husarion_office's glass walls: a non-static model held by a zero-range revolute joint to
    `world` is a wall, not a robot to leave out (its planned goto drove through it); gz-sim's
    pendulum (or a door) hangs from the world by a joint that moves: held still where it starts,
    not a robot that falls when spawned free. A model whose own joints move is a robot."""
    wall = ("<model name='glass'><pose>2 0 0 0 0 0</pose><link name='l'><pose>0 0 1.1 0 0 0</pose>"
            "<inertial><mass>50</mass></inertial><collision name='c'><geometry><box><size>0.03 3 2.2</size>"
            f"</box></geometry></collision></link>{joint}</model>")
    world = load_world(str(world_file(tmp_path, wall)), tmp_path)
    assert (world.plan.robot_models == ("glass",)) is (kind == "robot")
    assert any(b.name == "glass" for b in world.plan.bodies) is (kind != "robot")
    said = " ".join(world.notices)
    assert ("model(s) without joints that move are held fixed" in said) is (kind == "fixed")
    assert ("1 model(s) hang from the world by a joint that moves" in said) is (kind == "anchored")


CUBE = ([(x, y, z) for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 1.0)],
        [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
         (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)])


@pytest.mark.parametrize("part, center, bounds", [
    ("Steering_Wheel", "true", ([-10.0, -10.0, -10.0], [10.0, 10.0, 10.0])),  # centred on its box
    ("Steering_Wheel", "false", ([100.0, 0.0, 50.0], [120.0, 20.0, 70.0])),  # where its node puts it
    ("Wheel", "false", ([0.0, 0.0, 0.0], [300.0, 100.0, 100.0])),  # no such part: the whole mesh, said
])
def test_a_submesh_collision_collides_with_that_part_alone(tmp_path, part, center, bounds):
    """rmf_demos' Caddy collides its steering wheel with <submesh> Steering_Wheel of the whole
    cart's mesh: it was the whole cart, 3.6 m long, sticking out of the robot. Now the part, in
    centimetres as the file's <unit> says, centred when <center> asks."""
    from tests.collada import collada_parts

    vertices, faces = CUBE
    (tmp_path / "worlds").mkdir()
    (tmp_path / "worlds" / "cart.dae").write_text(collada_parts({
        "Body": ([(300 * x, 100 * y, 100 * z) for x, y, z in vertices], faces, None),
        "Steering_Wheel": ([(20 * x, 20 * y, 20 * z) for x, y, z in vertices], faces,
                           "1 0 0 100 0 1 0 0 0 0 1 50 0 0 0 1")}, meter=0.01))
    path = world_file(tmp_path, "<model name='cart'><static>true</static><link name='l'><collision name='wheel'>"
                                f"<geometry><mesh><uri>cart.dae</uri><submesh><name>{part}</name>"
                                f"<center>{center}</center></submesh></mesh></geometry></collision></link></model>")
    world = load_world(str(path), tmp_path)
    low, high = ([v / 100 for v in corner] for corner in bounds)
    box = world.summary["bounds"]
    assert box["min"] == pytest.approx(low) and box["max"] == pytest.approx(high)
    said = [n for n in world.notices if "<submesh>" in n]
    if part == "Wheel":
        assert said and "selects <submesh> 'Wheel' of 'cart.dae', which has no part of that name (its parts: " \
            "'Body', 'Steering_Wheel'): mobot collides with the whole mesh" in said[0]
    else:
        assert not said


ZERO = "<axis><xyz>0 0 1</xyz><limit><lower>0</lower><upper>0</upper></limit></axis>"
TURNS = "<axis><xyz>0 0 1</xyz><limit><lower>-1</lower><upper>1</upper></limit></axis>"


@pytest.mark.parametrize("first, second, kept", [
    ("type='fixed'>", f"type='revolute'>{ZERO}", "j1"),  # osrf's turtlebot: two that cannot move
    ("type='fixed'>", f"type='revolute'>{TURNS}", "j2"),  # the one that moves stays
    (f"type='revolute'>{TURNS}", f"type='revolute'>{TURNS}", None),  # a loop that moves: refused
])
def test_a_link_held_by_two_joints_keeps_one_when_the_other_cannot_move(tmp_path, first, second, kept):
    """osrf's turtlebot bolts its rack on by two zero-range revolute joints, a loop SDF allows and
    Gazebo loads: the one that adds nothing is left out, with a warning. Two that move stay refused."""
    from mobot_cli.assets.description.sdf import expand_sdf
    from mobot_cli.assets.resources import ResourceResolver
    from mobot_cli.errors import DescriptionError

    (tmp_path / "r.sdf").write_text(sdf(f"""<model name='r'>
      <link name='base'><collision name='c'><geometry><box><size>0.3 0.2 0.1</size></box></geometry></collision></link>
      <link name='rack'><pose>0 0 0.2 0 0 0</pose><collision name='c'><geometry><box><size>0.2 0.2 0.01</size>
        </box></geometry></collision></link>
      <joint name='j1' {first}<parent>base</parent><child>rack</child></joint>
      <joint name='j2' {second}<parent>base</parent><child>rack</child></joint>
    </model>""", version="1.8"))
    if kept is None:
        with pytest.raises(DescriptionError, match="link 'rack' is the child of two joints that move"):
            expand_sdf(tmp_path / "r.sdf", ResourceResolver(tmp_path))
        return
    expansion = expand_sdf(tmp_path / "r.sdf", ResourceResolver(tmp_path))
    dropped = "j2" if kept == "j1" else "j1"
    assert f"joint '{dropped}' also holds link 'rack', which joint '{kept}' holds: it cannot move, so it is " \
        "left out" in " ".join(str(n) for n in expansion.notices)
    assert f'name="{dropped}"' not in expansion.text and f'name="{kept}"' in expansion.text


def test_a_world_robot_without_wheels_is_named_as_the_worlds_in_the_error(tmp_path):
    """The error named the bundled 'mobot' (the description a listed world robot does not give)."""
    import yaml

    arm = ("<model name='arm'><link name='l'><collision name='c'><geometry><box><size>0.2 0.2 0.2</size></box>"
           "</geometry></collision></link><link name='flap'><pose>0 0 0.3 0 0 0</pose><collision name='c'><geometry>"
           "<box><size>0.1 0.1 0.1</size></box></geometry></collision></link><joint name='j' type='revolute'>"
           "<parent>l</parent><child>flap</child><axis><xyz>0 0 1</xyz><limit><lower>-1</lower><upper>1</upper>"
           "</limit></axis></joint></model>")
    path = world_file(tmp_path, "<include><uri>model://ground_plane</uri></include>" + arm)
    robot = {"name": "arm", "commands": [{"at": 0.5, "linear": 0.1}]}
    (tmp_path / "s.yaml").write_text(yaml.safe_dump({"version": 1, "name": "s", "world": str(path), "duration": 2,
                                                     "robots": [robot]}))
    done = invoke(["check", tmp_path / "s.yaml"])
    assert done.exit_code == 2 and "robot 'arm' has commands but no drive wheels were detected in world model 'arm'" \
        in done.stderr
