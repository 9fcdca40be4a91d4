"""Skid steer on arcs: the body twist loop holds the commanded radius and speed.

A 1 m-radius arc at two speeds; the ground truth's fitted circle and mean forward speed over
the steady part (after the first quarter) must match the command within 5 % and 3 %. The
corpus's skid-steer robots (at their test speed and half of it, as the README's table), and
four-wheel robots of our own that the fixed separation multiplier alone gets wrong (a long
wheelbase, a centre of mass ahead of the axles), at 0.3 and 0.5 m/s.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from mobot_cli.plan import RobotPlan, SpawnPose
from mobot_cli.sim.bullet.twist_trim import LIMITS, TwistTrim
from tests.sim.test_fidelity import CASES, drive, robot_plans  # noqa: F401 - a fixture

SKID4 = Path(__file__).parent / "robots" / "skid4.urdf.xacro"
SPEEDS = (0.3, 0.5)
OWN = {"long": {"wheelbase": "0.7", "track": "0.5"}, "nose_heavy": {"com_x": "0.1"}}


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
        for name, args in OWN.items():
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


@pytest.mark.parametrize("name", list(OWN))
def test_open_loop_misses_the_arc(own_plans, name):
    """The class of problem: the fixed multiplier alone drives these arcs > 5 % off."""
    plan = own_plans[name]
    assert max(len(plan.drive.left_joints), len(plan.drive.right_joints)) > 1
    open_loop = replace(plan, drive=replace(plan.drive, twist_feedback=False))
    radius, _ = arc(open_loop, 0.5)
    assert abs(radius - 1.0) > 0.05


def test_trim_adapts_only_near_the_command():
    trim = TwistTrim()
    assert not trim.update((0.5, 0.0), (0.1, 0.0), 0.02)  # 80 % short: blocked or starting
    assert trim.linear == 1.0
    assert trim.update((0.5, 0.5), (0.45, 0.55), 0.02)  # 10 % slow, 10 % over-turning
    assert trim.linear > 1.0 and trim.angular < 1.0
    assert not trim.update((0.0, 0.0), (0.3, 0.2), 0.02)  # a zero command compares nothing
    for _ in range(1000):
        trim.update((0.5, -0.5), (0.36, -0.36), 0.02)
    assert (trim.linear, trim.angular) == (LIMITS[1], LIMITS[1])
