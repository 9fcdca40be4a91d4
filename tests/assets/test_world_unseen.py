"""Classes of problems found on public Gazebo worlds mobot had not been tried on (worlds written here)."""

from __future__ import annotations

from dataclasses import astuple

import pytest
from hypothesis import given
from hypothesis import strategies as st

from mobot_cli.assets.world.pose import stream_numbers
from mobot_cli.assets.world.worldplan import load_world
from mobot_cli.cli import invoke
from mobot_cli.errors import WorldError
from tests.assets.test_world_sdf import body, box_model, world_file

# gazebo_ros_pkgs' elevator.world (SDF 1.5) has a link and a prismatic joint both named 'door':
# before SDF 1.7 links and joints had names of their own, and Gazebo classic loads it.
SAME_NAME = """
  <model name='lift'><static>true</static><pose>1 0 0 0 0 0</pose>
    <link name='car'><pose>0 0 0.5 0 0 0</pose>
      <collision name='c'><geometry><box><size>2 2 0.1</size></box></geometry></collision></link>
    <link name='door'><pose>1 -0.5 1 0 0 0</pose>
      <collision name='c'><geometry><box><size>0.1 1 2</size></box></geometry></collision></link>
    <link name='sign'><pose relative_to='door'>0 0 1.5 0 0 0</pose>
      <collision name='c'><geometry><sphere><radius>0.1</radius></sphere></geometry></collision></link>
    <joint name='door' type='prismatic'><parent>car</parent><child>door</child>
      <axis><xyz>0 1 0</xyz><limit><lower>0</lower><upper>1</upper></limit></axis></joint>
    <joint name='sign' type='fixed'><parent>door</parent><child>sign</child></joint>
  </model>"""


@pytest.mark.parametrize("version", ["1.5", "1.6"])
def test_a_joint_may_share_its_name_with_a_link(tmp_path, version):
    text = SAME_NAME
    if version == "1.5":  # SDF 1.5 said frame= where 1.6+ says relative_to=
        text = text.replace("relative_to=", "frame=")
    path = world_file(tmp_path, text, "elevator.world")
    path.write_text(path.read_text().replace('version="1.6"', f'version="{version}"'))
    world = load_world(str(path), tmp_path)
    shapes = {s.kind: s.xyz for s in body(world, "lift").shapes}
    assert world.summary["links"] == 3
    # in the model frame; relative to the link 'door', not to the joint
    assert shapes["sphere"] == pytest.approx((1.0, -0.5, 2.5))
    boxes = sorted(s.xyz for s in body(world, "lift").shapes if s.kind == "box")
    assert boxes == [pytest.approx((0.0, 0.0, 0.5)), pytest.approx((1.0, -0.5, 1.0))]


# leo_gz_worlds' marsyard: the whole floor is a <heightmap>, which mobot does not simulate.
HEIGHTMAP = """
  <model name='terrain'><static>true</static><link name='l'>
    <collision name='ground'><geometry><heightmap><uri>hm.png</uri><size>50 50 5</size><pos>0 0 0</pos>
    </heightmap></geometry></collision></link></model>"""


def test_a_heightmap_floor_is_named_where_the_robots_have_nothing_to_stand_on(tmp_path):
    world = load_world(str(world_file(tmp_path, HEIGHTMAP, "mars.sdf")), tmp_path)
    notices = [str(n) for n in world.notices]
    assert any("'ground' uses <heightmap> geometry, which mobot does not simulate" in n for n in notices)
    assert any(n.endswith("nothing to stand on (heightmap geometry left out)") for n in notices), notices
    assert world.plan.bodies == ()


def test_a_robot_spawned_over_a_left_out_heightmap_hears_it_may_have_been_the_floor(tmp_path):
    world_file(tmp_path, HEIGHTMAP, "mars.sdf")
    (tmp_path / "s.yaml").write_text("version: 1\nduration: 1\nworld: worlds/mars.sdf\nrobots:\n"
                                     "  - {name: rover}\n")
    code, out, err = astuple(invoke(["run", tmp_path / "s.yaml", "--out", tmp_path / "r"]))
    assert code == 2
    assert "robots have nothing to stand on (heightmap geometry left out)" in err
    assert err.endswith("a Fuel model or a <heightmap> that was left out may have been its floor).\n")


# A world Gazebo classic saved, then edited (dynamic_logistics_warehouse): '41.632-0.191335' in a
# <state> pose. Gazebo reads poses with a C++ stream, which reads that as 41.632 and -0.191335.
def test_a_pose_with_numbers_run_together_is_read_as_gazebo_reads_it(tmp_path):
    text = box_model("tile", "0.5 41.632-0.191335 0 -0 1.5")
    world = load_world(str(world_file(tmp_path, text, "glued.world")), tmp_path)
    tile = body(world, "tile")
    assert tile.xyz == pytest.approx((0.5, 41.632, -0.191335))
    warning = next(str(n) for n in world.notices if "runs numbers together" in str(n))
    assert "glued.world:4, key 'model[tile].pose'" in warning
    assert warning.endswith("read as Gazebo reads it: '0.5 41.632 -0.191335 0 -0 1.5'")


@pytest.mark.parametrize("pose", ["1 2 3 0 0", "1 2 x 0 0 0", "1 2 3 0 0 0 0", "1 2-3-4 0 0 0"])
def test_a_pose_that_is_not_six_numbers_even_read_as_a_stream_is_an_error(tmp_path, pose):
    path = world_file(tmp_path, box_model("tile", pose), "bad.world")
    with pytest.raises(WorldError, match=r"pose '.*' (needs 6 numbers|could not convert)"):
        load_world(str(path), tmp_path)


@given(st.lists(st.floats(-1e6, 1e6, allow_nan=False), min_size=1, max_size=8), st.randoms())
def test_stream_numbers_splits_what_a_stream_splits(values, rnd):
    texts = [repr(v) for v in values]
    joined = "".join(t if i == 0 or (t[0] == "-" and rnd.random() < 0.5) else " " + t
                     for i, t in enumerate(texts))
    assert [float(t) for t in stream_numbers(joined)] == values
    assert stream_numbers(joined + " 1x") is None
