"""Classes of problems found on public Gazebo worlds mobot had not been tried on (worlds written here)."""

from __future__ import annotations

import pytest

from mobot_cli.assets.world.worldplan import load_world
from tests.assets.test_world_sdf import body, world_file

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
