"""PyBullet's ray batches: more rays than one batch holds are all answered."""

from __future__ import annotations

import numpy as np

from mobot_cli.sim.pb import p
from mobot_cli.sim.sensing import lidar


def test_more_rays_than_one_batch_all_come_back():
    cid = p.connect(p.DIRECT)
    try:
        shape = p.createCollisionShape(p.GEOM_BOX, halfExtents=(0.5, 0.5, 0.5), physicsClientId=cid)
        box = p.createMultiBody(0.0, shape,
                                basePosition=(2.0, 0.0, 0.0), physicsClientId=cid)
        n = 2 * lidar.MAX_BATCH + 5
        starts = np.zeros((n, 3))
        ends = np.tile([4.0, 0.0, 0.0], (n, 1))
        found = lidar._batch(cid, starts, ends, mask=-1)
        assert found.shape == (n, 2)
        assert np.all(found[:, 0] == box) and np.allclose(found[:, 1], 1.5 / 4.0, atol=1e-6)
    finally:
        p.disconnect(cid)
