"""`drive:` in a scenario: naming wheel joints measures them, silences the missing-drive warning,
and every drive key (twist_feedback too) survives the resolved scenario's round trip."""

from __future__ import annotations

from pathlib import Path

import pytest

from mobot_cli.errors import ScenarioError
from mobot_cli.scenario.prepare import prepare

ROBOTS = Path(__file__).resolve().parents[1] / "sim" / "robots"
NO_DRIVE = "no drive wheels found: the robot will not move on commands"
INERTIAL = ('<inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" '
            'izz="0.01"/></inertial>')


@pytest.fixture()
def mesh_wheeled(tmp_path) -> Path:
    """A robot whose wheels collide as meshes: detection cannot tell them from other parts."""
    trimesh = pytest.importorskip("trimesh")
    trimesh.creation.cylinder(radius=0.06, height=0.03, sections=64).export(tmp_path / "tyre.stl")
    wheels = "".join(
        f'<link name="{side}_wheel">{INERTIAL}<collision><origin rpy="1.5707963 0 0"/>'
        f'<geometry><mesh filename="tyre.stl"/></geometry></collision></link>'
        f'<joint name="{side}_joint" type="continuous"><parent link="base"/>'
        f'<child link="{side}_wheel"/><origin xyz="0 {y} 0.06"/><axis xyz="0 1 0"/></joint>'
        for side, y in (("left", 0.17), ("right", -0.17)))
    caster = (f'<link name="caster">{INERTIAL}<collision><geometry><sphere radius="0.03"/>'
              '</geometry></collision></link><joint name="caster_joint" type="fixed">'
              '<parent link="base"/><child link="caster"/><origin xyz="-0.15 0 0.03"/></joint>')
    path = tmp_path / "meshy.urdf"
    path.write_text(f'<robot name="meshy"><link name="base">{INERTIAL}<collision>'
                    '<origin xyz="0 0 0.1"/><geometry><box size="0.4 0.25 0.06"/></geometry>'
                    f'</collision></link>{wheels}{caster}</robot>')
    return path


def scenario(tmp_path: Path, robot: str, drive: str = "") -> Path:
    path = tmp_path / "s.yaml"
    path.write_text(f"version: 1\nduration: 2\nrobots:\n  - name: r\n    description: {robot}\n"
                    + (f"    drive: {drive}\n" if drive else ""))
    return path


def test_named_joints_are_measured_and_silence_the_warning(tmp_path, mesh_wheeled):
    bare = prepare(scenario(tmp_path, mesh_wheeled.name)).plan
    assert bare.robots[0].drive is None
    assert any(NO_DRIVE in n for n in bare.notices)
    named = prepare(scenario(tmp_path, mesh_wheeled.name,
                             "{left_joints: [left_joint], right_joints: [right_joint]}"))
    drive = named.plan.robots[0].drive
    assert (drive.left_joints, drive.right_joints) == (("left_joint",), ("right_joint",))
    assert drive.wheel_radius == pytest.approx(0.06, abs=1e-6)
    assert drive.wheel_separation == pytest.approx(0.34)
    assert not any(NO_DRIVE in n for n in named.plan.notices)
    again = tmp_path / "again.yaml"
    again.write_text(named.resolved_yaml)
    assert prepare(again).plan.robots[0].drive == drive


def test_a_named_joint_that_does_not_exist_is_located(tmp_path, mesh_wheeled):
    with pytest.raises(ScenarioError) as err:
        prepare(scenario(tmp_path, mesh_wheeled.name,
                         "{left_joints: [left_wheel], right_joints: [right_joint]}"))
    assert err.value.message == "drive names left wheel joint 'left_wheel', which is not in the description"
    assert (err.value.location.line, err.value.location.key) == (6, "robots.r.drive")
    assert err.value.hint == "Valid: 'left_joint', 'right_joint'."


def test_suspended_wheels_need_no_drive_section(tmp_path):
    plan = prepare(scenario(tmp_path, ROBOTS / "wheeldrop.urdf.xacro")).plan
    drive = plan.robots[0].drive
    assert (drive.wheel_radius, drive.wheel_separation) == pytest.approx((0.035, 0.23))
    assert not any(NO_DRIVE in n for n in plan.notices)


@pytest.mark.parametrize("given, written", [("", None), ("{twist_feedback: false}", False),
                                            ("{twist_feedback: true}", True)])
def test_twist_feedback_round_trips(tmp_path, given, written):
    prepared = prepare(scenario(tmp_path, ROBOTS / "skid4.urdf.xacro", given))
    assert prepared.plan.robots[0].drive.twist_feedback is written
    assert ("twist_feedback" in prepared.resolved_yaml) is (written is not None)
    again = tmp_path / "again.yaml"
    again.write_text(prepared.resolved_yaml)
    assert prepare(again).plan.robots[0].drive == prepared.plan.robots[0].drive
