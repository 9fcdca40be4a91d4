"""Holonomic bases against closed-form motion, on both engines.

Robots of our own: the bundled `mecanum` (robots/mecanum: gz-sim's MecanumDrive plugin; rollers
as anisotropic friction without a plugin; gazebo_ros planar_move) and mecanum_gz.sdf (an SDF
model as gz-sim's mecanum example lays it out). A twist (vx, vy, wz) held for t seconds moves
the body by gz-math's exact integration; the ground truth must match it (sideways 1 m and the
diagonal within 2 %, a 90 deg turn in place within 1 deg), the encoder odometry must match the
ground truth, and the wheel joints must turn at MecanumDrive's speeds.

Measured (PyBullet, 240 Hz): sideways 1 m -> 1.0000 m, x drift < 1e-4 m; diagonal (1, 1) m ->
(1.0000, 1.0000); turn in place 90.00 deg; an arc (0.2, 0.1, 0.3) for 5 s -> (0.3532, 0.9528)
against (0.3552, 0.9520) closed form (the first step's ramp-in); odometry within 2 mm of truth;
roll and pitch stay below 0.001 deg. Pushed sideways into a wall it stops there (no climbing,
no tipping).
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from mobot_cli.plan import Physics, RobotPlan, SpawnPose, StaticBody, StaticShape, WorldPlan
from mobot_cli.sim.engine import open_world
from mobot_cli.sim.holonomic import mecanum_wheel_speeds, planar

ROBOTS = Path(__file__).parent / "robots"
RATE = 240
ENGINES = ("bullet", "kinematic")


def _plan(name: str, description: str, args: dict | None = None) -> RobotPlan:
    from mobot_cli.assets.description.describe import load_robot

    desc = load_robot(str(ROBOTS / description) if "." in description else description, args or {})
    return RobotPlan(name=name, namespace=f"/{name}", frame_prefix=f"{name}/", urdf=desc.urdf,
                     root_link=desc.root_link, pose=SpawnPose(z_auto=True), drive=desc.drive)


@pytest.fixture(scope="module")
def plans(tmp_path_factory):
    mp = pytest.MonkeyPatch()
    mp.setenv("MOBOT_CACHE_DIR", str(tmp_path_factory.mktemp("holonomic-cache")))
    try:
        return {"plugin": _plan("plugin", "mecanum", {"drive": "plugin"}),
                "rollers": _plan("rollers", "mecanum", {"drive": "rollers"}),
                "planar": _plan("planar", "mecanum", {"drive": "planar"}),
                "sdf": _plan("sdf", "mecanum_gz.sdf")}
    finally:
        mp.undo()


def drive(plan: RobotPlan, twist: tuple[float, float, float], seconds: float, engine: str = "bullet",
          bodies: tuple = ()):
    """Settle, hold (vx, vy, wz) for ``seconds``, stop and settle; (before, after, worst tilt deg)."""
    vx, vy, wz = twist
    with open_world(Physics(rate_hz=RATE, engine=engine), WorldPlan(bodies=bodies)) as world:
        world.spawn(plan)
        for _ in range(RATE // 2):
            world.step()
        before = world.read(plan.name)
        world.set_command(plan.name, vx, wz, linear_y=vy)
        tilt = 0.0
        for i in range(round(seconds * RATE)):
            world.step()
            if i % 12 == 0:
                state = world.read(plan.name)
                tilt = max(tilt, abs(state.true_roll), abs(state.true_pitch))
        assert world.read(plan.name).cmd_linear_y == vy
        world.set_command(plan.name, 0.0, 0.0)
        for _ in range(RATE // 2):
            world.step()
        return before, world.read(plan.name), math.degrees(tilt)


def moved(before, after) -> tuple[float, float, float]:
    """Ground-truth motion in the starting body frame: (forward, left, turn)."""
    dx, dy = after.true_x - before.true_x, after.true_y - before.true_y
    c, s = math.cos(before.true_yaw), math.sin(before.true_yaw)
    turn = (after.true_yaw - before.true_yaw + math.pi) % (2 * math.pi) - math.pi
    return c * dx + s * dy, -s * dx + c * dy, turn


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("name", ["plugin", "rollers", "planar", "sdf"])
def test_sideways_one_metre(plans, name, engine):
    before, after, tilt = drive(plans[name], (0.0, 0.25, 0.0), 4.0, engine)
    forward, left, turn = moved(before, after)
    assert left == pytest.approx(1.0, rel=0.02)
    assert abs(forward) < 0.01 and abs(math.degrees(turn)) < 0.5
    assert tilt < 1.0
    # odometry (encoder, or the model's pose for planar_move) agrees with the ground truth
    assert after.odom_y - before.odom_y == pytest.approx(left, abs=0.005)
    assert after.odom_x - before.odom_x == pytest.approx(forward, abs=0.005)


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("name", ["plugin", "sdf"])
def test_diagonal(plans, name, engine):
    before, after, tilt = drive(plans[name], (0.2, 0.2, 0.0), 5.0, engine)
    forward, left, turn = moved(before, after)
    assert forward == pytest.approx(1.0, rel=0.02)
    assert left == pytest.approx(1.0, rel=0.02)
    assert abs(math.degrees(turn)) < 0.5 and tilt < 1.0


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("name", ["plugin", "rollers", "sdf"])
def test_turn_in_place(plans, name, engine):
    before, after, _ = drive(plans[name], (0.0, 0.0, 0.5), math.pi, engine)
    forward, left, turn = moved(before, after)
    assert math.degrees(turn) == pytest.approx(90.0, abs=1.0)
    assert math.hypot(forward, left) < 0.01
    assert math.degrees(after.odom_yaw - before.odom_yaw) == pytest.approx(math.degrees(turn), abs=0.5)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_base_without_wheels_moved_by_planar_move_drives_diagonally(tmp_path, monkeypatch, engine):
    """No wheel joint at all (neobotix's mpo_700: its wheels are fixed joints): held commanded for
    longer than the stall watch waits (1 s), PyBullet's answer for no joints (None) once ended
    the run with a traceback."""
    monkeypatch.setenv("MOBOT_CACHE_DIR", str(tmp_path))
    plan = _plan("box", "planar_box.urdf")
    assert plan.drive is not None and plan.drive.kind == "omni" and not plan.drive.left_joints
    before, after, tilt = drive(plan, (0.2, 0.2, 0.0), 2.0, engine)
    forward, left, turn = moved(before, after)
    assert forward == pytest.approx(0.4, rel=0.03) and left == pytest.approx(0.4, rel=0.03)
    assert abs(math.degrees(turn)) < 0.5 and tilt < 1.0
    assert after.odom_y - before.odom_y == pytest.approx(left, abs=0.005)  # the model's pose


@pytest.mark.parametrize("engine", ENGINES)
def test_arc_with_sideways_matches_the_exact_integration(plans, engine):
    vx, vy, wz, t = 0.2, 0.1, 0.3, 5.0
    before, after, _ = drive(plans["plugin"], (vx, vy, wz), t, engine)
    want_x, want_y, want_yaw = planar(0.0, 0.0, 0.0, vx * t, vy * t, wz * t)
    forward, left, turn = moved(before, after)
    assert (forward, left) == pytest.approx((want_x, want_y), abs=0.03 * math.hypot(want_x, want_y))
    assert turn == pytest.approx(want_yaw, abs=math.radians(1.0))
    # encoder odometry integrates what the wheels did: within 1 cm of the ground truth
    assert math.hypot(after.odom_x - before.odom_x - forward, after.odom_y - before.odom_y - left) < 0.01


@pytest.mark.parametrize("engine", ENGINES)
def test_wheels_turn_at_mecanum_drive_speeds(plans, engine):
    plan = plans["plugin"]
    spec = plan.drive
    vx, vy, wz = 0.1, 0.2, -0.4
    with open_world(Physics(rate_hz=RATE, engine=engine), WorldPlan()) as world:
        world.spawn(plan)
        for _ in range(RATE // 2):
            world.step()
        world.set_command(plan.name, vx, wz, linear_y=vy)
        for _ in range(RATE):
            world.step()
        rates = world.read(plan.name).joint_velocities
    fl, fr, bl, br = mecanum_wheel_speeds(vx, vy, wz, spec.wheel_separation, spec.wheelbase, spec.wheel_radius)
    (front_left, back_left), (front_right, back_right) = spec.left_joints, spec.right_joints
    got = [rates[front_left], rates[front_right], rates[back_left], rates[back_right]]
    assert got == pytest.approx([fl, fr, bl, br], abs=0.02 * max(abs(fl), abs(fr), abs(bl), abs(br)))


@pytest.mark.parametrize("engine", ENGINES)
def test_a_wall_stops_it_without_lifting_or_tipping(plans, engine):
    wall = StaticBody(name="wall", xyz=(0.0, 0.6, 0.25), shapes=(StaticShape(kind="box", size=(2.0, 0.1, 0.5)),))
    before, after, tilt = drive(plans["plugin"], (0.0, 0.5, 0.0), 3.0, engine, bodies=(wall,))
    # the wheels' outer faces (y = 0.27) stop at the wall's face (y = 0.55)
    assert after.true_y == pytest.approx(0.28, abs=0.01)
    assert after.true_z == pytest.approx(before.true_z, abs=0.002) and tilt < 1.0


@pytest.mark.parametrize("engine", ENGINES)
def test_a_diff_robot_refuses_a_sideways_command(engine, tmp_path, monkeypatch):
    monkeypatch.setenv("MOBOT_CACHE_DIR", str(tmp_path))
    plan = _plan("skid", "skid4.urdf.xacro")
    with open_world(Physics(rate_hz=RATE, engine=engine), WorldPlan()) as world:
        world.spawn(plan)
        with pytest.raises(ValueError, match="cannot move sideways"):
            world.set_command("skid", 0.1, 0.0, linear_y=0.2)
        assert world.read("skid").cmd_linear == 0.0  # refused: nothing changed
        world.set_command("skid", 0.1, 0.0)  # a plain twist still goes
        assert world.read("skid").cmd_linear == 0.1


@pytest.fixture(scope="module")
def linorobot2_mecanum(corpus, tmp_path_factory):
    """linorobot2's mecanum base: gazebo_ros planar_move, which mobot once drove as skid steer."""
    from mobot_cli.assets.description.describe import load_robot

    mp = pytest.MonkeyPatch()
    mp.setenv("MOBOT_RESOURCE_PATH", str(corpus / "linorobot2"))
    mp.setenv("MOBOT_CACHE_DIR", str(tmp_path_factory.mktemp("linorobot2-cache")))
    try:
        desc = load_robot(str(corpus / "linorobot2/linorobot2_description/urdf/robots/mecanum.urdf.xacro"), {})
    finally:
        mp.undo()
    return RobotPlan(name="lino", namespace="/lino", frame_prefix="lino/", urdf=desc.urdf,
                     root_link=desc.root_link, pose=SpawnPose(z_auto=True), drive=desc.drive)


def test_corpus_linorobot2_mecanum_is_omni_and_moves_sideways(linorobot2_mecanum):
    drive_spec = linorobot2_mecanum.drive
    assert drive_spec.kind == "omni" and drive_spec.odometry == "ground_truth"
    assert len(drive_spec.left_joints) == len(drive_spec.right_joints) == 2
    before, after, tilt = drive(linorobot2_mecanum, (0.0, 0.25, 0.0), 4.0)
    forward, left, turn = moved(before, after)
    assert left == pytest.approx(1.0, rel=0.02) and abs(forward) < 0.01 and tilt < 1.0
    before, after, _ = drive(linorobot2_mecanum, (0.2, -0.2, 0.0), 5.0)
    assert moved(before, after)[:2] == pytest.approx((1.0, -1.0), rel=0.02)
    before, after, _ = drive(linorobot2_mecanum, (0.0, 0.0, 0.5), math.pi)
    assert math.degrees(moved(before, after)[2]) == pytest.approx(90.0, abs=1.0)


def test_acceleration_limit_ramps_the_twist(plans):
    """max_wheel_acceleration 10 rad/s^2 at r = 0.05 m: 0.5 m/s^2 at the rim, so 0.25 m/s takes 0.5 s."""
    from dataclasses import replace

    plan = replace(plans["plugin"], drive=replace(plans["plugin"].drive, max_wheel_acceleration=10.0))
    with open_world(Physics(rate_hz=RATE), WorldPlan()) as world:
        world.spawn(plan)
        for _ in range(RATE // 2):
            world.step()
        start = world.read(plan.name).true_y
        world.set_command(plan.name, 0.0, 0.0, linear_y=0.25)
        for _ in range(RATE // 4):
            world.step()
        quarter = world.read(plan.name)
        for _ in range(RATE):
            world.step()
        late = world.read(plan.name)
    # after 0.25 s: half the speed, 0.5 * 0.5 * 0.25^2 = 1.6 cm; a second later at full speed
    assert quarter.true_y - start == pytest.approx(0.0156, abs=0.002)
    assert (late.true_y - quarter.true_y) == pytest.approx(0.0625 - 0.0156 + 0.25 * 0.75, abs=0.005)
