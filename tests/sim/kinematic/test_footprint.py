"""Footprints (sim/kinematic/footprint.py): a lower bound of how far apart two robots are, which
lets the kinematic engine leave pairs unasked; and the engine moving robots exactly as it does
when it asks about every pair, whichever robot was spawned first."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.plan import Physics, SpawnPose, StaticBody, StaticShape, WorldPlan
from mobot_cli.scenario.prepare import prepare
from mobot_cli.sim.engine import open_world
from mobot_cli.sim.kinematic.footprint import gap
from mobot_cli.sim.pb import p
from tests.sim.test_contacts import box

REPO = Path(__file__).resolve().parents[3]
INERTIAL = '<inertial><mass value="{m}"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial>'


ROUND, SQUARE = '<cylinder radius="0.03" length="0.02"/>', '<box size="0.06 0.05 0.02"/>'  # wheels


def robot_urdf(wheel: str = ROUND, extra: str = "") -> str:
    """A light robot: a 0.20 x 0.16 m box on two wheels (``wheel``: their geometry) and a caster ball."""
    return f"""<?xml version="1.0"?>
<robot name="light">
  <link name="base_link">{INERTIAL.format(m=1.0)}
    <collision><origin xyz="0 0 0.04"/><geometry><box size="0.20 0.16 0.05"/></geometry></collision>
  </link>
  <link name="left_wheel">{INERTIAL.format(m=0.05)}<collision><geometry>{wheel}</geometry></collision></link>
  <link name="right_wheel">{INERTIAL.format(m=0.05)}<collision><geometry>{wheel}</geometry></collision></link>
  <link name="caster">{INERTIAL.format(m=0.02)}
    <collision><geometry><sphere radius="0.015"/></geometry></collision>
  </link>
  <joint name="left_wheel_joint" type="continuous">
    <parent link="base_link"/><child link="left_wheel"/>
    <origin xyz="0.03 0.09 0.03" rpy="-1.5708 0 0"/><axis xyz="0 0 1"/>
  </joint>
  <joint name="right_wheel_joint" type="continuous">
    <parent link="base_link"/><child link="right_wheel"/>
    <origin xyz="0.03 -0.09 0.03" rpy="-1.5708 0 0"/><axis xyz="0 0 1"/>
  </joint>
  <joint name="caster_joint" type="fixed">
    <parent link="base_link"/><child link="caster"/><origin xyz="-0.07 0 0.015"/>
  </joint>
  {extra}
</robot>
"""


# A link on a prismatic joint, with no collision shape: nothing of the robot's geometry changes,
# but the robot has no footprint (footprint.py), so the engine asks about it every time.
SLIDER = f"""<link name="slider">{INERTIAL.format(m=0.01)}</link>
  <joint name="slider_joint" type="prismatic"><parent link="base_link"/><child link="slider"/>
    <axis xyz="0 0 1"/><limit lower="0" upper="0.1" effort="1" velocity="1"/></joint>"""


def plan_of(tmp_path: Path, urdf: str, poses, commands: str, world: str = "empty", seconds: float = 6.0):
    (tmp_path / "light.urdf").write_text(urdf)
    listed = ", ".join(f"[{x}, {y}, {yaw}]" for x, y, yaw in poses)
    (tmp_path / "fleet.yaml").write_text(
        f"version: 1\nname: fleet\nworld: {world}\nduration: {seconds}\nsettle: 0\n"
        f"physics: {{rate_hz: 10, engine: kinematic}}\nrobots:\n  - name: r_{{i}}\n    description: light.urdf\n"
        f"    count: {len(poses)}\n    poses: [{listed}]\n    commands: {commands}\n")
    return prepare(tmp_path / "fleet.yaml").plan


@pytest.fixture(scope="module", params=["light", "box_wheels", "bundled"])
def pair(request, tmp_path_factory):
    """Two robots of a kind in an empty kinematic world, and their Movers."""
    tmp = tmp_path_factory.mktemp(request.param)
    if request.param == "bundled":
        robot = prepare(REPO / "scenarios" / "quickstart.yaml").plan.robots[0]
        robots = [replace(robot, name=name, namespace="/" + name, frame_prefix=name + "/",
                          pose=SpawnPose((x, 0.0, 0.0), z_auto=True)) for name, x in (("a", 0.0), ("b", 3.0))]
    else:
        wheel = SQUARE if request.param == "box_wheels" else ROUND
        robots = plan_of(tmp, robot_urdf(wheel), [(0.0, 0.0, 0.0), (3.0, 0.0, 0.7)], "[]").robots
    with open_world(Physics(rate_hz=10, engine="kinematic"), WorldPlan()) as world:
        for robot in robots:
            world.spawn(robot)
        movers = [world._movers[robot.name] for robot in robots]
        assert all(m.rect is not None for m in movers)
        yield world, movers


pose_st = st.tuples(st.floats(-0.6, 0.6), st.floats(-0.6, 0.6), st.floats(-math.pi, math.pi))


@settings(max_examples=150, deadline=None)
@given(poses=st.tuples(pose_st, pose_st), wheels=st.lists(st.floats(-7.0, 7.0), min_size=8, max_size=8))
def test_two_robots_are_never_nearer_than_their_footprints_say(pair, poses, wheels):
    world, movers = pair
    cid = world.client_id
    for mover, (x, y, yaw) in zip(movers, poses):
        mover.place(x, y, mover.z, yaw)
        for index, angle in zip(mover.robot.joints.values(), wheels):  # wheels turned anyhow
            p.resetJointState(mover.robot.body, index, angle, physicsClientId=cid)
    bound = gap(movers[0].rect, *poses[0], movers[1].rect, *poses[1])
    points = p.getClosestPoints(movers[0].robot.body, movers[1].robot.body, 2.0, physicsClientId=cid)
    assert points and min(c[8] for c in points) >= bound
    for mover in movers:
        mover.sync(full=True)  # back where the engine keeps it


def test_a_footprint_is_as_tight_as_the_robot_and_its_wheels(tmp_path):
    """The light robot's rectangle is its box and wheels (0.2 x 0.2 m) within a millimetre, at any
    spawn yaw; square wheels turning round their axle widen it to their reach."""
    rects = {}
    for name, wheel in (("round", ROUND), ("square", SQUARE)):
        plan = plan_of(tmp_path, robot_urdf(wheel), [(0.0, 0.0, 0.0), (2.0, 0.0, 2.0)], "[]")
        with open_world(plan.physics, plan.world) as world:
            for robot in plan.robots:
                world.spawn(robot)
            rects[name] = [world._movers[r.name].rect for r in plan.robots]
    for rect in rects["round"]:
        assert rect == pytest.approx((-0.1, -0.1, 0.1, 0.1), abs=0.0015)
    reach = math.sqrt(0.03 ** 2 + 0.025 ** 2 + 0.01 ** 2)  # a box wheel's corner from its axle's centre
    for rect in rects["square"]:
        assert rect == pytest.approx((-0.1, -0.09 - reach, 0.1, 0.09 + reach), abs=0.0015)


def test_robots_that_can_change_shape_or_are_tilted_have_no_footprint(tmp_path):
    plan = plan_of(tmp_path, robot_urdf(extra=SLIDER), [(0.0, 0.0, 0.0)], "[]")
    with open_world(plan.physics, plan.world) as world:
        world.spawn(plan.robots[0])
        assert world._movers[plan.robots[0].name].rect is None
    tilted = plan_of(tmp_path, robot_urdf(), [(0.0, 0.0, 0.0)], "[]").robots[0]
    tilted = replace(tilted, pose=SpawnPose((0.0, 0.0, 0.2), (math.sin(0.1), 0.0, 0.0, math.cos(0.1)), z_auto=False))
    with open_world(plan.physics, plan.world) as world:
        world.spawn(tilted)
        assert world._movers[tilted.name].rect is None


def trace(plan, steps: int):
    """Every robot's pose and touches after each step, and the collisions counted."""
    out = []
    with open_world(plan.physics, plan.world) as world:
        for robot in plan.robots:
            world.spawn(robot)
        for robot in plan.robots:
            command = robot.commands[0]
            world.set_command(robot.name, command.linear, command.angular)
        for _ in range(steps):
            world.step()
            out.append([(m.x, m.y, m.yaw, sorted(m.touches)) for m in world._order])
        return out, [world.read(r.name).collisions for r in plan.robots]


def packed(count: int, seed: int) -> list[tuple[float, float, float]]:
    """Robots 0.3 m apart on a grid with yaws drawn from the seed."""
    import random

    rng = random.Random(seed)
    return [(round(0.3 * (k % 6) - 0.75, 3), round(0.3 * (k // 6) - 0.75, 3), round(rng.uniform(-3.0, 3.0), 2))
            for k in range(count)]


@pytest.mark.parametrize("seed", [1, 2])
def test_a_packed_fleet_moves_exactly_as_when_every_pair_is_asked(tmp_path, seed):
    """36 light robots 0.3 m apart among walls pushing into each other: with footprints the
    engine asks PyBullet about far fewer pairs, and every pose, touch and collision is the same
    as for the same robots without a footprint (asked about every pair the circles keep)."""
    world = WorldPlan(bodies=(box("wall_a", (0.1, 3.0, 0.5), (1.25, 0.0, 0.25)),
                              box("wall_b", (3.0, 0.1, 0.5), (0.0, -1.25, 0.25))))
    commands = "[{at: 0, linear: 0.3, angular: 0.6}]"
    runs = []
    for extra in ("", SLIDER):
        plan = plan_of(tmp_path, robot_urdf(extra=extra), packed(36, seed), commands)
        plan = replace(plan, world=world)
        runs.append(trace(plan, 40))
    (with_footprints, hits), (without, hits_without) = runs
    assert sum(hits) > 0  # they do collide
    assert hits == hits_without
    assert with_footprints == without


def test_a_blocked_robot_moves_once_the_robot_in_its_way_has_left_whichever_was_spawned_first(tmp_path):
    """A drives into B and is held; at 1 s A slows and B drives off. In the step B leaves, A is
    asked (its command changed) before or after B moves, as they were spawned; asked before, A
    is held in that step and follows B in the next, as the distance between them then says (it
    used to be held one step more: B's move counted as before A's query, in the same step)."""
    a, b = (0.0, 0.0, 0.0), (0.4, 0.0, 0.0)
    commands = "[{at: 0, linear: 0.3, angular: 0.0}]"
    tracks = []
    for order in ((a, b), (b, a)):
        plan = plan_of(tmp_path, robot_urdf(), list(order), commands)
        with open_world(plan.physics, plan.world) as world:
            for robot in plan.robots:
                world.spawn(robot)
            first = plan.robots[order.index(a)].name
            second = plan.robots[order.index(b)].name
            world.set_command(first, 0.3, 0.0)
            world.set_command(second, 0.0, 0.0)
            xs = []
            for step in range(20):
                if step == 10:
                    world.set_command(first, 0.25, 0.0)
                    world.set_command(second, 0.3, 0.0)
                world.step()
                xs.append((world.read(first).true_x, world.read(second).true_x))
            tracks.append(xs)
    (spawned_first, spawned_second), held = tracks, tracks[0][9][0]
    assert spawned_first[8][0] == spawned_second[8][0] == held  # A was held by B
    # B leaves in step 11: A, asked after B moved, follows in that step; asked before, in the next
    assert spawned_second[10][0] == pytest.approx(held + 0.025, abs=1e-9)
    assert spawned_first[10][0] == held
    assert spawned_first[11][0] == pytest.approx(held + 0.025, abs=1e-9)
    assert [b for _, b in spawned_first] == [b for _, b in spawned_second]


def test_static_walls_keep_their_place_in_a_packed_fleet(tmp_path):
    """A wall is still in the way of robots whose footprints are far from every other robot."""
    world = WorldPlan(bodies=(StaticBody(name="wall", shapes=(StaticShape(kind="box", size=(0.1, 2.0, 0.5)),),
                                         xyz=(0.6, 0.0, 0.25)),))
    plan = plan_of(tmp_path, robot_urdf(), [(0.0, 0.0, 0.0), (0.0, 0.6, 0.0)], "[{at: 0, linear: 0.3, angular: 0.0}]")
    plan = replace(plan, world=world)
    (poses, hits) = trace(plan, 30)
    assert poses[-1][0][0] == pytest.approx(0.6 - 0.05 - 0.1, abs=0.002)  # against the wall
    assert hits[0] == 1


def test_answers_at_a_pose_are_kept_for_the_robots_that_have_not_moved_since():
    """seen.py: at a pose asked before, the static answer and the distances of robots not moved
    since are given back; a robot that moved, a lower bound, a mover's body or a new epoch are
    asked again."""
    from types import SimpleNamespace

    from mobot_cli.sim.kinematic.seen import Seen

    def robot(body, moved):
        return SimpleNamespace(robot=SimpleNamespace(body=body), moved=moved)

    seen, key = Seen(), (1.0, 2.0, 0.1, 0.3, 0.0)
    seen.start(epoch=0, clock=10)
    assert seen.recall(key, [robot(5, 3)], {}) == (None, {})
    # asked about statics 1, 2 (touching 2) and robots 5, 6, 7 (7 only bounded), and mover body 9
    seen.keep(key, (0.02, {5: -0.0005, 6: 0.2, 7: 0.3, 9: 0.1}, {2, 5}), [5, 6, 7, 9], {7: 0.3}, [9])
    seen.start(epoch=0, clock=14)
    static, before = seen.recall(key, [robot(5, 9), robot(6, 12), robot(7, 1)], {})
    assert static == (0.02, frozenset({2})) and before == {5: -0.0005}  # 6 moved at 12, after 10
    assert seen.recall((1.0, 2.0, 0.1, 0.3, 0.01), [robot(5, 9)], {}) == (None, {})  # another floor
    seen.start(epoch=1, clock=15)  # a sensor turned the wheels, a robot was spawned...
    assert seen.recall(key, [robot(5, 9)], {}) == (None, {})
