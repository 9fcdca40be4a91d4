"""Movers in a live world: spawn_mover and delete_mover, seen in the robot's scan at once."""

from __future__ import annotations

import tempfile
import threading
import time

import numpy as np
import pytest

from mobot_cli.errors import LiveWorldError
from mobot_cli.live.client import Client
from mobot_cli.live.server import LiveServer
from tests.sim.sensor_world import lidar, one_robot, planned


@pytest.fixture(scope="module")
def endpoint(tmp_path_factory):
    """A live world in this process (--fast) with one robot whose lidar looks around it."""
    folder = tmp_path_factory.mktemp("movers")
    plan, _ = planned(one_robot(folder, x=0.0, y=0.0, yaw=0.0, duration=1000.0), "mobot",
                      lidar(xyz=(0.0, 0.0, 0.3), range_max=3.0))
    where = f"ipc://{tempfile.mkdtemp(prefix='mobot-m-')}/s.sock"
    server = LiveServer(plan, where, rtf=None)
    thread = threading.Thread(target=server.serve, daemon=True)
    thread.start()
    deadline = time.monotonic() + 60
    while True:
        try:
            with Client(where, timeout=0.5) as client:
                client.ping()
                break
        except LiveWorldError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.05)
    yield where
    with Client(where) as client:
        client.stop()
    thread.join(timeout=30)


def ahead(client: Client) -> float:
    """The scan's range straight ahead, from a scan taken after the request."""
    step = client.ping()["step"]
    while True:
        reply = client.request("scan", name="mobot")
        if reply["step"] > step + 24:
            ranges = np.array([np.inf if r is None else r for r in reply["ranges"]], dtype=float)
            return float(ranges[len(ranges) // 2])
        time.sleep(0.02)


def test_a_mover_spawned_in_front_is_seen_and_gone_once_deleted(endpoint):
    with Client(endpoint) as client:
        assert ahead(client) > 2.9  # the room's wall, at the lidar's 3 m range (a return or none)
        reply = client.spawn_mover("post", shape="cylinder", size=[0.2, 1.0], path=[[1.0, 0.0], [1.0, 0.001]],
                                   speed=0.001)
        assert reply["ok"] and reply["name"] == "post"
        assert abs(ahead(client) - 0.8) < 0.02  # its near side, 1 m ahead less its radius
        refused = client.call("spawn_mover", mover={"name": "post", "region": [0, 1, 0, 1]})
        assert (refused["ok"], refused["result"]) == (False, "NAME_NOT_UNIQUE")
        bad = client.call("spawn_mover", mover={"name": "x", "shape": "cone", "region": [0, 1, 0, 1]})
        assert not bad["ok"] and "shape" in bad["message"]
        assert client.delete_mover("post")["ok"]
        assert ahead(client) > 2.9  # the wall again
        gone = client.call("delete_mover", name="post")
        assert (gone["ok"], gone["result"]) == (False, "NOT_FOUND")
