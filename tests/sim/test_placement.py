"""The shapes that measure a spawned robot give the same closest points as plane bodies did.

Spawns measure a robot against planes: six half-spaces for its exact bounds and, in a world
without a ground plane, a horizontal plane far below. They used to be temporary bodies (~7 ms
each to create); they are now shapes placed in the query. Runs must stay byte-identical, so
the points must be the same to the last bit, for real robots turned every way.
"""

from __future__ import annotations

import math

import pytest

from mobot_cli.plan import Physics, WorldPlan
from mobot_cli.sim import placement
from mobot_cli.sim.bullet.urdf_file import urdf_path
from mobot_cli.sim.bullet.world import URDF_FLAGS, World
from mobot_cli.sim.pb import p
from tests.sim.test_fidelity import robot_plans  # noqa: F401  (the corpus robots, a fixture)

NORMALS = [(1.0, 0.0, 0.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, 1.0),
           (0.0, 0.0, -1.0)]


def _plane_body_points(cid: int, body: int, normal, at, distance: float) -> list:
    """What mobot measured before: a plane body made, asked and removed."""
    shape = p.createCollisionShape(p.GEOM_PLANE, planeNormal=list(normal), physicsClientId=cid)
    plane = p.createMultiBody(0.0, shape, basePosition=list(at), physicsClientId=cid)
    try:
        return p.getClosestPoints(body, plane, distance, physicsClientId=cid)
    finally:
        p.removeBody(plane, physicsClientId=cid)


def _numbers(point) -> tuple:
    """A closest point without its body B and link B: link A, positions, normal, distance."""
    return (point[3],) + tuple(point[5:])


@pytest.mark.parametrize("name", ["mobot", "burger", "husky", "jackal", "linorobot2_4wd"])
def test_shape_probes_equal_plane_bodies_to_the_bit(robot_plans, name):  # noqa: F811
    plan = robot_plans[name]
    with World(Physics(), WorldPlan(ground_plane=False)) as world:
        cid = world.client_id
        uid = p.loadURDF(str(urdf_path(plan.urdf)), [0.3, -0.2, 0.4], p.getQuaternionFromEuler([0.3, -0.2, 2.0]),
                         flags=URDF_FLAGS, physicsClientId=cid)
        probes = placement.Probes(cid)
        pos = p.getBasePositionAndOrientation(uid, physicsClientId=cid)[0]
        compared = 0
        for normal in NORMALS:
            at = [c - 100.0 * n for c, n in zip(pos, normal)]  # 100 m away, facing the robot
            old = _plane_body_points(cid, uid, normal, at, 200.0)
            new = probes.closest(uid, normal, at, 200.0)
            # Body and link B differ (no body); the link on the robot and every number must not.
            assert [_numbers(pt) for pt in new] == [_numbers(pt) for pt in old]
            compared += len(old)
        below = (0.0, 0.0, placement.PROBE_Z)
        old = _plane_body_points(cid, uid, (0.0, 0.0, 1.0), below, 1400.0)
        assert [_numbers(pt) for pt in probes.closest(uid, (0.0, 0.0, 1.0), below, 1400.0)] == \
            [_numbers(pt) for pt in old]
        assert compared >= 6 and math.isfinite(old[0][8])
