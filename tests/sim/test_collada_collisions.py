"""Robots whose collision meshes are COLLADA files PyBullet's own reader cannot read.

Onshape exports place their geometry through <library_nodes> and <instance_node> (RoverRobotics'
wheels); PyBullet's COLLADA reader says "cannot extract mesh" and leaves the link without any
collision shape, so the robot fell through the floor and tipped over. Gazebo reads those files,
and so does mobot now: collision meshes reach PyBullet as OBJ files converted the way a world's
are (node transforms and <unit> applied).
"""

from __future__ import annotations

import pytest

from mobot_cli.plan import Physics, RobotPlan, SpawnPose, WorldPlan
from mobot_cli.sim.engine import open_world
from mobot_cli.sim.pb import p
from tests.collada import collada


def instanced_wheel(radius: float, width: float, unit: float) -> str:
    """A wheel (a cylinder about its z axis) in a COLLADA file that places it by <instance_node>,
    its numbers in ``unit`` metres."""
    import trimesh

    m = trimesh.creation.cylinder(radius=radius / unit, height=width / unit, sections=32)
    return collada(m.vertices.tolist(), m.faces.tolist(), unit, instanced=True)


ROBOT = """<?xml version="1.0"?>
<robot name="onshape_car">
  <link name="base_link">
    <inertial><origin xyz="0 0 0.08"/><mass value="5"/>
      <inertia ixx="0.05" ixy="0" ixz="0" iyy="0.05" iyz="0" izz="0.05"/></inertial>
    <collision><origin xyz="0 0 0.08"/><geometry><box size="0.3 0.2 0.08"/></geometry></collision>
  </link>
  {wheels}
  <link name="caster">
    <inertial><mass value="0.1"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial>
    <collision><geometry><sphere radius="0.025"/></geometry></collision>
  </link>
  <joint name="caster_joint" type="fixed"><parent link="base_link"/><child link="caster"/>
    <origin xyz="-0.12 0 0.025"/></joint>
  <gazebo><plugin name="diff" filename="libgazebo_ros_diff_drive.so">
    <left_joint>left_joint</left_joint><right_joint>right_joint</right_joint>
    <wheel_separation>0.26</wheel_separation><wheel_diameter>0.1</wheel_diameter>
  </plugin></gazebo>
</robot>
"""
WHEEL = """<link name="{side}_wheel">
    <inertial><mass value="0.5"/><inertia ixx="5e-4" ixy="0" ixz="0" iyy="5e-4" iyz="0" izz="5e-4"/></inertial>
    <collision><origin rpy="1.5708 0 0"/><geometry><mesh filename="{mesh}"/></geometry></collision>
  </link>
  <joint name="{side}_joint" type="continuous"><parent link="base_link"/><child link="{side}_wheel"/>
    <origin xyz="0.05 {y} 0.05"/><axis xyz="0 1 0"/></joint>"""


@pytest.fixture()
def car(tmp_path, monkeypatch) -> RobotPlan:
    from mobot_cli.assets.description.describe import load_robot

    monkeypatch.setenv("MOBOT_CACHE_DIR", str(tmp_path / "cache"))
    mesh = tmp_path / "wheel.dae"
    mesh.write_text(instanced_wheel(0.05, 0.03, 0.001))  # millimetres, as Blender and Onshape export
    wheels = "\n  ".join(WHEEL.format(side=side, y=y, mesh=mesh) for side, y in (("left", 0.13), ("right", -0.13)))
    path = tmp_path / "car.urdf"
    path.write_text(ROBOT.format(wheels=wheels))
    desc = load_robot(str(path))
    assert desc.bottom_z == pytest.approx(0.0, abs=1e-6)  # the wheels' bottoms, in metres
    assert desc.footprint[3] == pytest.approx(0.13 + 0.015, abs=1e-6)  # the left wheel's outer face
    return RobotPlan(name="car", namespace="/car", frame_prefix="car/", urdf=desc.urdf, root_link=desc.root_link,
                     pose=SpawnPose(z_auto=True), drive=desc.drive)


def test_pybullet_itself_cannot_read_the_wheels(tmp_path):
    """The premise: PyBullet's COLLADA reader leaves such a link without a collision shape."""
    mesh = tmp_path / "wheel.dae"
    mesh.write_text(instanced_wheel(0.05, 0.03, 0.001))
    urdf = tmp_path / "one.urdf"
    urdf.write_text(f'<?xml version="1.0"?><robot name="t"><link name="a"><inertial><mass value="1"/>'
                    f'<inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial><collision>'
                    f'<geometry><mesh filename="{mesh}"/></geometry></collision></link></robot>')
    cid = p.connect(p.DIRECT)
    try:
        body = p.loadURDF(str(urdf), physicsClientId=cid)
        assert p.getCollisionShapeData(body, -1, physicsClientId=cid) == ()
    finally:
        p.disconnect(physicsClientId=cid)


def test_a_robot_on_such_wheels_stands_on_them_and_drives(car):
    with open_world(Physics(rate_hz=240), WorldPlan()) as world:
        world.spawn(car)
        body, cid = world._robots["car"].body, world._cid  # noqa: SLF001 - the world's own bookkeeping
        wheels = [link for link in range(p.getNumJoints(body, physicsClientId=cid))
                  if p.getJointInfo(body, link, physicsClientId=cid)[12].decode().endswith("_wheel")]
        for link in wheels:  # an OBJ of the same triangles, in metres
            (shape,) = p.getCollisionShapeData(body, link, physicsClientId=cid)
            assert shape[4].decode().endswith(".obj")
            low, high = p.getAABB(body, link, physicsClientId=cid)
            assert high[2] - low[2] == pytest.approx(0.1, abs=0.01)  # the wheel's 0.1 m diameter
        for _ in range(120):
            world.step()
        before = world.read("car")
        world.set_command("car", 0.3, 0.0)
        for _ in range(480):
            world.step()
        after = world.read("car")
    assert after.true_x - before.true_x == pytest.approx(0.6, abs=0.06)  # 2 s at 0.3 m/s, the ramp aside
    assert abs(after.true_pitch) < 0.05 and after.true_z == pytest.approx(before.true_z, abs=0.005)
    assert before.true_z == pytest.approx(0.0, abs=0.005)  # on its wheels, not through the floor
