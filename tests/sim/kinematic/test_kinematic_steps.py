"""The kinematic engine's shortcuts give exactly what the plain per-step computation gives:
numbers worked out once per change of the wheel rates, blocked robots not moved again, the
robot pair filter, contact samples told in a lump, all states of a log row read at once."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.plan import Physics, SpawnPose, WorldPlan
from mobot_cli.scenario.prepare import prepare
from mobot_cli.sim.contacts import CONTACT_SLOP, ContactCounter
from mobot_cli.sim.drive import arc, body_twist, ramp, wheel_speeds, wrap_angle
from mobot_cli.sim.engine import open_world
from mobot_cli.sim.kinematic.pairs import robot_pairs
from mobot_cli.timeline.records import Sample
from tests.sim.test_contacts import box

REPO = Path(__file__).resolve().parents[3]
RATE = 10
SCRIPT = [(0.4, 0.2, 12), (0.0, 0.0, 8), (-0.3, -0.5, 10), (0.0, 0.9, 5), (0.25, 0.0, 9)]  # linear, angular, steps


@pytest.fixture(scope="module")
def bundled():
    """The bundled robot (quickstart's plan: its wheels ramp at 40 rad/s^2, 30 rad/s at most)."""
    return prepare(REPO / "scenarios" / "quickstart.yaml").plan.robots[0]


class Reference:
    """The plain computation of one robot's step, written out as the engine did before it kept
    anything between steps: ramp the rates, the body's arc, each wheel, the encoder odometry."""

    def __init__(self, drive, x: float, y: float, yaw: float, wheels: list[str]):
        self.radius, self.sep, self.dt = drive.wheel_radius, drive.wheel_separation, 1.0 / RATE
        self.max_step = drive.max_wheel_acceleration * self.dt
        self.x, self.y, self.yaw, self.v, self.w = x, y, yaw, 0.0, 0.0
        self.odom = (0.0, 0.0, 0.0)
        self.rates = self.goal = (0.0, 0.0)
        self.wheels = wheels  # left, right
        self.positions = dict.fromkeys(wheels, 0.0)
        self.velocities = dict.fromkeys(wheels, 0.0)

    def command(self, linear: float, angular: float) -> None:
        self.goal = wheel_speeds(linear, angular, self.sep, self.radius, self.radius)

    def step(self) -> None:
        if self.rates != self.goal:
            self.rates = tuple(ramp(r, g, self.max_step) for r, g in zip(self.rates, self.goal))
        left, right = self.rates
        if left == 0.0 and right == 0.0:
            if self.v or self.w:
                self.v = self.w = 0.0
                self.velocities = dict.fromkeys(self.velocities, 0.0)
            return
        r = self.radius * self.dt
        distance, turn = body_twist(left * r, right * r, self.sep)
        self.x, self.y, self.yaw = arc(self.x, self.y, self.yaw, distance, turn)
        self.v, self.w = distance / self.dt, turn / self.dt
        for name, rate in zip(self.wheels, (left, right)):
            self.positions[name] += rate * self.dt
            self.velocities[name] = rate
        self.odom = arc(*self.odom, *body_twist(left * r, right * r, self.sep))

    def expected(self) -> dict:
        return {"true_x": self.x, "true_y": self.y, "true_yaw": wrap_angle(self.yaw), "true_vx": self.v,
                "true_wz": self.w, "odom_x": self.odom[0], "odom_y": self.odom[1],
                "odom_yaw": wrap_angle(self.odom[2]), "odom_vx": self.v, "odom_wz": self.w,
                "joint_positions": dict(self.positions), "joint_velocities": dict(self.velocities)}


def observed(state) -> dict:
    return {key: getattr(state, key) for key in ("true_x", "true_y", "true_yaw", "true_vx", "true_wz", "odom_x",
                                                 "odom_y", "odom_yaw", "odom_vx", "odom_wz", "joint_positions",
                                                 "joint_velocities")}


def test_every_step_in_open_space_is_the_plain_computation_exactly(bundled):
    robot = replace(bundled, pose=SpawnPose((1.0, -2.0, 0.0), z_auto=True))
    wheels = list(robot.drive.left_joints + robot.drive.right_joints)
    with open_world(Physics(rate_hz=RATE, engine="kinematic"), WorldPlan()) as world:
        world.spawn(robot)
        start = world.read(robot.name)
        assert start.true_yaw == 0.0
        reference = Reference(robot.drive, start.true_x, start.true_y, 0.0, wheels)
        states, expected = [], []
        for linear, angular, steps in SCRIPT:
            world.set_command(robot.name, linear, angular)
            reference.command(linear, angular)
            for _ in range(steps):
                world.step()
                reference.step()
                states.append(world.read(robot.name))
                expected.append(reference.expected())
                assert observed(states[-1]) == expected[-1], len(states)
        # Every state is a snapshot: none changed as the robot went on (wheel rates share a dict
        # between the states of one rate, and it is never changed in place).
        assert [observed(s) for s in states] == expected
        assert len({id(s.joint_positions) for s in states}) == len(states)
        # It ramped (40 rad/s^2 at the wheels), stopped, reversed and turned in place on the way.
        speeds = [s.true_vx for s in states]
        assert 0.0 < speeds[0] < speeds[1] < 0.4 and min(speeds) < -0.25 and speeds[-1] > 0.2
        assert states[19].true_vx == 0.0 and states[19].joint_velocities == dict.fromkeys(wheels, 0.0)


def test_a_robot_held_against_a_wall_stays_exactly_as_it_was(bundled):
    wall = box("wall", (0.1, 2.0, 0.5), (1.0, 0.0, 0.25))
    robot = replace(bundled, drive=replace(bundled.drive, max_wheel_acceleration=None))
    with open_world(Physics(rate_hz=RATE, engine="kinematic"), WorldPlan(bodies=(wall,))) as world:
        world.spawn(robot)
        world.set_command(robot.name, 0.5, 0.1)
        for _ in range(40):
            world.step()
        held = [world.read(robot.name)]
        for _ in range(30):  # pushing on at the same rates
            world.step()
            held.append(world.read(robot.name))
        assert all(state == held[0] for state in held)
        assert held[0].true_vx == held[0].true_wz == 0.0 and held[0].collisions == 1
        assert set(held[0].joint_velocities.values()) == {0.0}
        assert 0.75 < held[0].true_x < 0.95 - 0.15 + 0.04  # its front (0.15 m ahead, turned a little) at the wall
        # Held at other rates, turning the other way: still still, and its zero turn rate now has
        # that sign, as the plain computation gives it (the CSV shows -0.000000).
        world.set_command(robot.name, 0.5, -0.1)
        world.step()
        turned = world.read(robot.name)
        assert (turned.true_x, turned.true_y, turned.true_wz) == (held[0].true_x, held[0].true_y, 0.0)
        assert math.copysign(1.0, turned.true_wz) == -1.0 == -math.copysign(1.0, held[0].true_wz)
        world.set_command(robot.name, -0.3, 0.0)  # other rates: it moves again, at once
        world.step()
        after = world.read(robot.name)
        assert after.true_vx == pytest.approx(-0.3) and after.true_x < held[0].true_x
        assert after.joint_positions["left_wheel_joint"] == pytest.approx(
            held[0].joint_positions["left_wheel_joint"] - 0.3 / 0.05 / RATE)


def brute_force_pairs(movers, moves, reach, measured):
    """The pair filter's rule, on every pair, as the engine first wrote it."""
    n = len(movers)
    xy = np.array([(m.x, m.y) for m in movers])
    travel = np.array([m.travel for m in movers])
    bound = np.zeros(n)
    for mover in moves:
        bound[mover.index] = mover.bound
    margin = bound[:, None] + bound[None, :] + CONTACT_SLOP
    gap = np.hypot(xy[:, None, 0] - xy[None, :, 0], xy[:, None, 1] - xy[None, :, 1]) \
        - reach[:, None] - reach[None, :]
    left = measured - travel[:, None] - travel[None, :]
    close = (gap <= margin) & (left <= margin)
    np.fill_diagonal(close, False)
    rows = np.zeros(n, dtype=bool)
    rows[[mover.index for mover in moves]] = True
    return {(i, j) for i, j in zip(*np.nonzero(close & rows[:, None]))}


class FakeMover:
    __slots__ = ("index", "x", "y", "travel", "bound", "touches")

    def __init__(self, index, x, y, travel, bound):
        self.index, self.x, self.y, self.travel, self.bound = index, x, y, travel, bound
        self.touches = set()


robot_st = st.tuples(st.floats(-2.0, 2.0), st.floats(-2.0, 2.0), st.floats(0.1, 0.4), st.floats(0.0, 2.0),
                     st.one_of(st.just(0.0), st.floats(0.0, 0.06)), st.booleans())


@settings(max_examples=300, deadline=None)
@given(robots=st.lists(robot_st, min_size=2, max_size=14), data=st.data())
def test_the_robot_pair_filter_finds_the_pairs_the_rule_on_every_pair_finds(robots, data):
    movers = [FakeMover(i, x, y, travel, bound) for i, (x, y, _, travel, bound, _) in enumerate(robots)]
    moves = [(m, (m.bound, 0.0)) for m, r in zip(movers, robots) if r[5]] or [(movers[0], None)]
    n = len(movers)
    reach = np.array([r[2] for r in robots])
    measured = np.array(data.draw(st.lists(st.one_of(st.just(-math.inf), st.floats(-0.01, 3.0)),
                                           min_size=n * n, max_size=n * n))).reshape(n, n)
    measured = np.minimum(measured, measured.T)  # the engine keeps it symmetric
    found = robot_pairs(movers, reach, measured, moves)  # without footprints: the circles' rule
    pairs = {(a.index, b.index) for a, others in found.items() for b in others}
    assert pairs == brute_force_pairs(movers, [m for m, _ in moves], reach, measured)
    assert all(others == sorted(others, key=lambda m: m.index) for others in found.values())


@settings(max_examples=200, deadline=None)
@given(samples=st.lists(st.one_of(st.none(), st.sampled_from(["a", "b", "ab"])), max_size=60))
def test_samples_told_idle_in_a_lump_count_as_empty_samples_one_by_one(samples):
    robot = SimpleNamespace(name="r", collisions=0)
    lumped_robot = SimpleNamespace(name="r", collisions=0)
    one_by_one, lumped, idle = ContactCounter(3), ContactCounter(3), 0
    for touched in samples:
        pairs = [(robot, ("body", body)) for body in touched or ""]
        one_by_one.record(pairs)
        if not touched:
            idle += 1
            continue
        if idle:
            lumped.idle(idle)
            idle = 0
        lumped.record([(lumped_robot, ("body", body)) for body in touched])
    assert lumped_robot.collisions == robot.collisions


def test_a_sample_is_an_immutable_record():
    sample = Sample(4, {})
    assert (sample.step, sample.states, sample.complete) == (4, {}, True)
    with pytest.raises(AttributeError):
        sample.step = 5


@pytest.mark.parametrize("engine", ["bullet", "kinematic"])
def test_the_states_of_a_log_row_are_each_robots_read(bundled, engine):
    robots = [replace(bundled, name=f"r{i}", namespace=f"/r{i}", frame_prefix=f"r{i}/",
                      pose=SpawnPose((0.0, 1.0 * i, 0.0), z_auto=True)) for i in range(3)]
    with open_world(Physics(rate_hz=RATE * 24 if engine == "bullet" else RATE, engine=engine), WorldPlan()) as world:
        for robot in robots:
            world.spawn(robot)
            world.set_command(robot.name, 0.2 * len(robot.name), 0.1)
        for _ in range(5):
            world.step()
        names = [robot.name for robot in robots]
        states = world.states(names)
        assert list(states) == names
        assert states == {name: world.read(name) for name in names}
        assert states["r2"].true_y == pytest.approx(2.0, abs=0.1) and states["r2"].true_vx > 0.0


def test_static_bodies_left_out_of_a_query_are_those_it_would_find_nothing_of():
    from mobot_cli.sim.kinematic.collide import QUERY_REACH, distances

    plan = prepare(REPO / "scenarios" / "house.yaml", ["physics.engine=kinematic"]).plan
    rng = np.random.default_rng(5)
    asked = kept = 0
    with open_world(plan.physics, plan.world) as world:
        world.spawn(plan.robots[0])
        mover, near = world._movers[plan.robots[0].name], world._near[plan.robots[0].name]
        for _ in range(300):
            x, y, yaw = rng.uniform(-5.8, 5.8), rng.uniform(-4.8, 4.8), rng.uniform(-math.pi, math.pi)
            # Near's box is taken up to NEAR_MARGIN / 2 away from where the robot is asked about.
            kx, ky = x + rng.uniform(-0.17, 0.17), y + rng.uniform(-0.17, 0.17)
            near.key = None
            near.around(kx, ky, mover.z, mover.reach, mover.height, mover.floor, mover.z + mover.above)
            mover.place(x, y, mover.z, yaw)
            within = near.within(x, y, mover.reach + QUERY_REACH)
            every = distances(world.client_id, mover.robot.body, near.bodies, [], QUERY_REACH, mover.floor)
            assert distances(world.client_id, mover.robot.body, within, [], QUERY_REACH, mover.floor) == every
            assert set(within) <= set(near.bodies)
            asked, kept = asked + len(near.bodies), kept + len(within)
        mover.sync()
    assert asked > 300 and kept < 0.6 * asked  # most bodies near enough to look at are too far to ask
