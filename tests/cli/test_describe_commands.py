"""`check`, `run`, `xacro` and `inspect` on descriptions that used to fail or mislead:
a 20 kB SDF robot, a robot without collision geometry, a xacro file whose meshes are missing."""

from __future__ import annotations

import json
from pathlib import Path

from mobot_cli.cli import invoke
from mobot_cli.errors import SimulationFault
from mobot_cli.plan import Physics, RobotPlan, SpawnPose, WorldPlan
from mobot_cli.sim.bullet.world import World

SDF_INERTIAL = ("<inertial><mass>{m}</mass><inertia><ixx>0.01</ixx><ixy>0</ixy><ixz>0</ixz><iyy>0.01</iyy>"
                "<iyz>0</iyz><izz>0.01</izz></inertia></inertial>")
URDF_INERTIAL = ('<inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/>'
                 '</inertial>')


def big_sdf_robot(path: Path, decorations: int = 50, name: str = "decor_link") -> Path:
    """A diff-drive SDF model with many small visual parts: 22 kB, as a detailed real robot is."""
    parts = [f"<link name='base_link'><pose>0 0 0.1 0 0 0</pose>{SDF_INERTIAL.format(m=5)}<collision name='c'>"
             "<geometry><box><size>0.5 0.3 0.1</size></box></geometry></collision></link>",
             f"<link name='caster'><pose>0.2 0 0.03 0 0 0</pose>{SDF_INERTIAL.format(m=0.1)}<collision name='c'>"
             "<geometry><sphere><radius>0.03</radius></sphere></geometry></collision></link>"
             "<joint name='caster_joint' type='fixed'><parent>base_link</parent><child>caster</child></joint>"]
    for side, y in (("left", 0.18), ("right", -0.18)):
        parts.append(f"<link name='{side}_wheel'><pose>0 {y} 0.1 -1.5707963 0 0</pose>{SDF_INERTIAL.format(m=0.5)}"
                     "<collision name='c'><geometry><cylinder><radius>0.1</radius><length>0.04</length></cylinder>"
                     f"</geometry></collision></link><joint name='{side}_wheel_joint' type='revolute'>"
                     f"<parent>base_link</parent><child>{side}_wheel</child><axis><xyz>0 0 1</xyz></axis></joint>")
    for i in range(decorations):
        parts.append(f"<link name='{name}_{i:03d}'><pose>{-0.2 + 0.008 * i:.3f} 0 0.16 0 0 0</pose>"
                     f"{SDF_INERTIAL.format(m=0.01)}<visual name='v'><geometry><box><size>0.01 0.01 0.01</size>"
                     f"</box></geometry></visual></link><joint name='decor_joint_{i:03d}' type='fixed'>"
                     f"<parent>base_link</parent><child>{name}_{i:03d}</child></joint>")
    path.write_text("<?xml version='1.0'?><sdf version='1.6'><model name='big'>" + "".join(parts)
                    + "<plugin name='dd' filename='libgazebo_ros_diff_drive.so'><left_joint>left_wheel_joint"
                      "</left_joint><right_joint>right_wheel_joint</right_joint><wheel_separation>0.36"
                      "</wheel_separation><wheel_diameter>0.2</wheel_diameter></plugin></model></sdf>")
    return path


def drive_scenario(tmp_path: Path, description: str, extra: str = "") -> Path:
    path = tmp_path / "s.yaml"
    path.write_text(f"version: 1\nworld: empty\nduration: 2.5\n{extra}robots:\n"
                    f"  - name: r\n    description: {description}\n    pose: {{x: 0.0, y: 0.0}}\n"
                    "    commands:\n      - {at: 0.5, linear: 0.25, for: 2.0}\n")
    return path


def test_a_20_kb_sdf_robot_checks_and_runs(tmp_path):
    """Its one-line URDF used to be cut by PyBullet's reader: run failed, check said ok."""
    sdf = big_sdf_robot(tmp_path / "big.sdf")
    assert sdf.stat().st_size > 20_000
    checked = invoke(["check", str(sdf), "--json"])
    assert checked.exit_code == 0, checked.stderr
    assert json.loads(checked.stdout)["links"] == 54
    done = invoke(["run", str(drive_scenario(tmp_path, "big.sdf")), "--out", str(tmp_path / "run"), "--quiet"])
    assert done.exit_code == 0, done.stderr
    x = json.loads((tmp_path / "run" / "summary.json").read_text())["robots"]["r"]["final_pose"]["x"]
    assert 0.47 < x < 0.51  # 0.25 m/s for 2 s


def test_check_fails_exactly_where_run_fails(tmp_path):
    """A link name longer than a line PyBullet reads: the same located error from both commands."""
    sdf = big_sdf_robot(tmp_path / "long.sdf", decorations=2, name="d" * 5000)
    checked = invoke(["check", str(sdf)])
    assert checked.exit_code == 2 and checked.stdout == ""
    assert checked.stderr.startswith(f"mobot: error: {sdf}: attribute name= of <link> (5004 bytes) in <link "
                                     'name="dddd')
    assert ("is longer than mobot can write in a line PyBullet reads whole (3840 bytes). Shorten the value"
            in checked.stderr)
    ran = invoke(["run", str(drive_scenario(tmp_path, "long.sdf")), "--out", str(tmp_path / "run"), "--quiet"])
    assert ran.exit_code == 2 and checked.stderr.split(": ", 2)[2] in ran.stderr


def urdf(tmp_path: Path, body: str, name: str = "r.urdf.xacro") -> Path:
    path = tmp_path / name
    path.write_text(f'<?xml version="1.0"?>\n<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">\n'
                    f'<link name="base_link">{URDF_INERTIAL}{body}</link>\n</robot>\n')
    return path


def test_xacro_skip_missing_leaves_a_missing_mesh_as_written_with_a_warning(tmp_path):
    path = urdf(tmp_path, '<visual><geometry><mesh filename="package://nowhere/meshes/body.stl"/></geometry>'
                          '</visual><collision><geometry><box size="0.3 0.2 0.1"/></geometry></collision>')
    refused = invoke(["xacro", str(path)])
    assert refused.exit_code == 2 and "package 'nowhere' (for 'package://nowhere/meshes/body.stl') not found" \
        in refused.stderr
    done = invoke(["xacro", str(path), "--skip-missing"])
    assert done.exit_code == 0
    assert '<mesh filename="package://nowhere/meshes/body.stl"/>' in done.stdout
    assert done.stderr == (f"mobot: warning: {path}: 1 mesh cannot be found and is left as written (skip_missing; "
                           "a run leaves their visuals and collisions out): package://nowhere/meshes/body.stl\n")


def test_a_visual_only_robot_is_refused_by_check_and_run_naming_its_missing_collisions(tmp_path):
    path = urdf(tmp_path, '<visual><geometry><box size="0.3 0.2 0.1"/></geometry></visual>', "v.urdf")
    message = "the robot has no collision geometry: nothing would hold it up"
    checked = invoke(["check", str(path)])
    assert checked.exit_code == 2 and message in checked.stderr and "floor under" not in checked.stderr
    ran = invoke(["run", str(drive_scenario(tmp_path, "v.urdf")), "--out", str(tmp_path / "run"), "--quiet"])
    assert ran.exit_code == 2 and message in ran.stderr


def test_a_robot_whose_collision_meshes_are_all_skipped_is_refused_naming_that(tmp_path):
    path = urdf(tmp_path, '<visual><geometry><box size="0.3 0.2 0.1"/></geometry></visual><collision><geometry>'
                          '<mesh filename="package://nowhere/meshes/hull.stl"/></geometry></collision>', "m.urdf")
    for command in (["check", str(path), "--skip-missing"],
                    ["run", str(drive_scenario(tmp_path, "m.urdf")), "--out", str(tmp_path / "run"),
                     "--quiet", "--skip-missing"]):
        done = invoke(command)
        assert done.exit_code == 2, done.stderr
        assert ("the robot has no collision geometry left: its collision meshes cannot be found and were left "
                "out (skip_missing), so nothing would hold it up. Make the collision meshes findable") in done.stderr
    assert invoke(["check", str(path), "--skip-missing"]).stderr.startswith(f"mobot: error: {path}: the robot")


def test_the_physics_says_a_falling_robot_has_no_collision_geometry(tmp_path):
    """The last line of defence, for text that reaches the physics unchecked: not 'is there a floor?'."""
    text = ('<?xml version="1.0"?><robot name="ghost"><link name="base_link">' + URDF_INERTIAL
            + '<visual><geometry><box size="0.3 0.2 0.1"/></geometry></visual></link></robot>')
    ghost = RobotPlan(name="ghost", namespace="/ghost", frame_prefix="ghost/", urdf=text, root_link="base_link",
                      pose=SpawnPose(xyz=(0.0, 0.0, 0.5)), drive=None)
    with World(Physics(), WorldPlan()) as world:
        world.spawn(ghost)
        try:
            for _ in range(5 * 240):
                world.step()
        except SimulationFault as fault:
            assert str(fault).startswith("robot 'ghost' fell out of the world (z = -10.")
            assert str(fault).endswith(": it has no collision geometry, so nothing holds it up. Add <collision> "
                                       "to its links (a box the size of its body will do).")
        else:
            raise AssertionError("the robot without collision geometry did not fall")
