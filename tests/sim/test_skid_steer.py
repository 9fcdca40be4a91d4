"""Skid steer on arcs: the body twist loop holds the commanded radius and speed.

A 1 m-radius arc at two speeds; the ground truth's fitted circle and mean forward speed over
the steady part (after the first quarter) must match the command within 5 % and 3 %. The
corpus's skid-steer robots (at their test speed and half of it, as the README's table), and
four-wheel robots of our own that the fixed separation multiplier alone gets wrong (a long
wheelbase, a centre of mass ahead of the axles), at 0.3 and 0.5 m/s. Bases up to twice as long
as wide turn 90 deg in place, and an arc right after a turn is the arc a fresh robot drives.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from mobot_cli.plan import Physics, RobotPlan, SpawnPose, WorldPlan
from mobot_cli.sim.bullet.twist_trim import LIMITS, TwistTrim
from mobot_cli.sim.bullet.world import World
from tests.sim.test_fidelity import CASES, RATE, drive, robot_plans, turned  # noqa: F401 - a fixture

SKID4 = Path(__file__).parent / "robots" / "skid4.urdf.xacro"
SPEEDS = (0.3, 0.5)
OWN = {"long": {"wheelbase": "0.7", "track": "0.5"}, "nose_heavy": {"com_x": "0.1"}}
# Wheelbase / track 1.6 and 2.0 (track 0.5 m): before friction.skid_axial_fraction they turned
# 96 and 10 deg of a commanded 90 (0.5 rad/s).
LONG = {"1.6": {"wheelbase": "0.8", "track": "0.5"}, "2.0": {"wheelbase": "1.0", "track": "0.5"}}


def circle_radius(points) -> float:
    """Radius of the least-squares circle through the points."""
    xy = np.array(points)
    a = np.column_stack([2 * xy[:, 0], 2 * xy[:, 1], np.ones(len(xy))])
    cx, cy, c = np.linalg.lstsq(a, (xy ** 2).sum(axis=1), rcond=None)[0]
    return float(math.sqrt(c + cx * cx + cy * cy))


def arc(plan: RobotPlan, speed: float, radius: float = 1.0) -> tuple[float, float]:
    """(fitted radius, mean forward speed) on three quarters of a circle."""
    w = speed / radius
    _, samples, _ = drive(plan, speed, w, 1.5 * math.pi / w)
    steady = samples[len(samples) // 4:]
    return (circle_radius([(s.true_x, s.true_y) for s in steady]),
            sum(s.true_vx for s in steady) / len(steady))


@pytest.fixture(scope="module")
def own_plans(tmp_path_factory):
    from mobot_cli.assets.description.describe import load_robot

    mp = pytest.MonkeyPatch()
    mp.setenv("MOBOT_CACHE_DIR", str(tmp_path_factory.mktemp("skid-cache")))
    try:
        plans = {}
        for name, args in {**OWN, **LONG, "square": {}}.items():
            desc = load_robot(str(SKID4), args)
            plans[name] = RobotPlan(name=name, namespace=f"/{name}", frame_prefix=f"{name}/",
                                    urdf=desc.urdf, root_link=desc.root_link,
                                    pose=SpawnPose(z_auto=True), drive=desc.drive)
    finally:
        mp.undo()
    return plans


SKID = [name for name, case in CASES.items() if case.skid]


@pytest.mark.parametrize("fraction", [0.5, 1.0])
@pytest.mark.parametrize("name", SKID)
def test_corpus_skid_steer_holds_arc_radius_and_speed(robot_plans, name, fraction):  # noqa: F811 - the fixture imported above
    speed = CASES[name].speed * fraction
    radius, v = arc(robot_plans[name], speed)
    assert radius == pytest.approx(1.0, rel=0.05)
    assert v == pytest.approx(speed, rel=0.03)


@pytest.mark.parametrize("speed", SPEEDS)
@pytest.mark.parametrize("name", list(OWN))
def test_own_skid_steer_holds_arc_radius_and_speed(own_plans, name, speed):
    radius, v = arc(own_plans[name], speed)
    assert radius == pytest.approx(1.0, rel=0.05)
    assert v == pytest.approx(speed, rel=0.03)


def test_open_loop_misses_the_arc(own_plans):
    """The class of problem: the fixed multiplier alone drives this arc > 5 % off."""
    name = "nose_heavy"  # the long base's open-loop arc is within 2.2 % since its friction fix
    plan = own_plans[name]
    assert max(len(plan.drive.left_joints), len(plan.drive.right_joints)) > 1
    open_loop = replace(plan, drive=replace(plan.drive, twist_feedback=False))
    radius, _ = arc(open_loop, 0.5)
    assert abs(radius - 1.0) > 0.05


@pytest.mark.parametrize("rate", [0.5, 1.0])
@pytest.mark.parametrize("name", list(LONG))
def test_long_skid_base_turns_ninety_degrees_in_place(own_plans, name, rate):
    before, _, after = drive(own_plans[name], 0.0, rate, (math.pi / 2) / rate)
    assert turned(before, after) == pytest.approx(90.0, abs=3.0)


def after_a_turn(plan: RobotPlan, turn_first: bool, heading: float, seconds: float):
    """A 1 m arc at 0.3 m/s for ``seconds`` from ``heading``, after a 90 deg turn in place or
    fresh: (fitted radius of its last three quarters, degrees turned, the heading it began at)."""
    plan = replace(plan, pose=replace(plan.pose, quat=(0.0, 0.0, math.sin(heading / 2), math.cos(heading / 2))))
    with World(Physics(rate_hz=RATE), WorldPlan()) as world:
        world.spawn(plan)
        for _ in range(RATE // 2):
            world.step()
        if turn_first:
            world.set_command(plan.name, 0.0, 0.5)
            for _ in range(round(math.pi * RATE)):
                world.step()
        start = world.read(plan.name)
        world.set_command(plan.name, 0.3, 0.3)
        points = []
        steps = round(seconds * RATE)
        for i in range(steps):
            world.step()
            if i % 12 == 0 and i > steps // 4:
                state = world.read(plan.name)
                points.append((state.true_x, state.true_y))
        world.set_command(plan.name, 0.0, 0.0)
        for _ in range(RATE):
            world.step()
        return circle_radius(points), turned(start, world.read(plan.name)), start.true_yaw


def over_turning(plan: RobotPlan) -> RobotPlan:
    """The base with a separation multiplier of 2 (as a user may set it): it over-turns by half."""
    return replace(plan, drive=replace(plan.drive, wheel_separation_multiplier=2.0))


def test_arc_after_a_turn_is_the_fresh_arc(own_plans):
    """Rotating faster than the next command asks once froze the loop (it adapted only within
    30 % of the command): this arc was 35.9 % tight after a turn, 0.03 % fresh.

    The fresh arc starts at the heading the turn ended at: PyBullet's friction pyramid alone
    moves a fitted radius by up to 2.5 % with the heading."""
    plan = over_turning(own_plans["square"])
    after, _, heading = after_a_turn(plan, True, 0.0, 1.5 * math.pi / 0.3)
    fresh, _, _ = after_a_turn(plan, False, heading, 1.5 * math.pi / 0.3)
    assert after == pytest.approx(fresh, rel=0.03)
    assert fresh == pytest.approx(1.0, rel=0.05)


@pytest.mark.parametrize("name", ["square", "2.0"])
def test_quarter_arc_after_a_turn_turns_as_a_fresh_one(own_plans, name):
    """Gains learnt turning in place are not the arc's: with one pair for every command this
    quarter arc turned 3.4 deg (square) and 2.6 deg (wheelbase/track 2) less after a turn."""
    plan = over_turning(own_plans[name])
    _, after, heading = after_a_turn(plan, True, 0.0, (math.pi / 2) / 0.3)
    _, fresh, _ = after_a_turn(plan, False, heading, (math.pi / 2) / 0.3)
    assert after == pytest.approx(fresh, abs=1.0)


def test_trim_adapts_only_near_the_command():
    trim = TwistTrim()
    assert not trim.update((0.5, 0.0), (0.1, 0.0), 0.02)  # 80 % short: blocked or starting
    assert trim.gains_for(0.5, 0.0) == (1.0, 1.0)
    assert trim.update((0.5, 0.5), (0.45, 0.55), 0.02)  # 10 % slow, 10 % over-turning
    linear, angular = trim.gains_for(0.5, 0.5)
    assert linear > 1.0 and angular < 1.0
    assert not trim.update((0.0, 0.0), (0.3, 0.2), 0.02)  # a zero command compares nothing
    for _ in range(1000):
        trim.update((0.5, -0.5), (0.36, -0.36), 0.02)
    assert trim.gains_for(0.5, -0.5) == (LIMITS[1], LIMITS[1])


def test_trim_learns_each_command_shape_apart():
    """What a turn in place taught does not carry into an arc, a straight line or reverse."""
    trim = TwistTrim(half_track=0.25)
    for _ in range(100):
        trim.update((0.0, 0.5), (0.0, 0.4), 0.02)  # in place, 20 % short
    assert trim.gains_for(0.0, 0.5)[1] > 1.2
    assert trim.gains_for(0.0, -0.8)[1] > 1.2  # the same shape turning the other way, faster
    for arc in ((0.3, 0.3), (0.5, 0.0), (-0.3, 0.3)):
        assert trim.gains_for(*arc) == (1.0, 1.0)
    assert trim.shape(0.3, 0.3) == trim.shape(0.6, 0.6) != trim.shape(0.3, 0.6)
