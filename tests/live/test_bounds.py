"""What one spawn may cost the world (issue 26 item 5): mesh faces and links per robot, robots per
world, each refused with LIMIT_EXCEEDED naming its `mobot serve` option; a big mesh within the
bound is counted and checked in a loader process while the world goes on stepping."""

from __future__ import annotations

import threading
from pathlib import Path

import numpy as np
import pytest

from mobot_cli.cli import invoke
from mobot_cli.common.meshfile import count_faces
from tests.live.live_server import LiveProcess

MAX_FACES, MAX_LINKS, MAX_ROBOTS = 60_000, 5, 4


def sheet(path: Path, faces: int) -> Path:
    """An OBJ of ``faces`` triangles: a bumpy 0.4 m square (a hostile client's heavy mesh)."""
    n = int((faces / 2) ** 0.5) + 2
    x, y = np.meshgrid(np.linspace(-0.2, 0.2, n), np.linspace(-0.2, 0.2, n), indexing="ij")
    z = 0.01 * np.sin(40 * x) * np.cos(40 * y)
    idx = np.arange(n * n).reshape(n, n) + 1
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    tris = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])[:faces]
    with open(path, "w") as obj:
        np.savetxt(obj, np.stack([x.ravel(), y.ravel(), z.ravel()], 1), fmt="v %.5f %.5f %.5f")
        np.savetxt(obj, tris, fmt="f %d %d %d")
    return path


def urdf(mesh: Path | None = None, links: int = 1) -> str:
    inertial = ('<inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" '
                'iyz="0"/></inertial>')
    shape = f'<mesh filename="{mesh}"/>' if mesh else '<box size="0.2 0.2 0.2"/>'
    body = [f'<link name="l0">{inertial}<collision><geometry>{shape}</geometry></collision></link>']
    for i in range(1, links):
        body.append(f'<link name="l{i}">{inertial}<collision><geometry><box size="0.1 0.1 0.1"/>'
                    f'</geometry></collision></link><joint name="j{i}" type="fixed"><parent link="l{i - 1}"/>'
                    f'<child link="l{i}"/></joint>')
    return '<?xml version="1.0"?><robot name="r">' + "".join(body) + "</robot>"


@pytest.fixture(scope="module")
def bounded(tmp_path_factory):
    server = LiveProcess("--fast", "--max-faces", str(MAX_FACES), "--max-links", str(MAX_LINKS),
                         "--max-robots", str(MAX_ROBOTS), cache_dir=tmp_path_factory.getbasetemp() / "mobot-cache")
    yield server
    assert server.process.poll() is None, f"the server died: {server.output()}"
    server.kill()


def test_faces_are_counted_in_obj_stl_and_collada(tmp_path):
    assert count_faces(str(sheet(tmp_path / "s.obj", 5000))) == 5000
    (tmp_path / "quad.obj").write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")
    assert count_faces(str(tmp_path / "quad.obj")) == 2  # a polygon counts as its fan
    (tmp_path / "b.stl").write_bytes(bytes(80) + (7).to_bytes(4, "little") + bytes(50 * 7))
    assert count_faces(str(tmp_path / "b.stl")) == 7
    (tmp_path / "a.stl").write_text("solid s\n" + "facet normal 0 0 1\nendfacet\n" * 3 + "endsolid s\n")
    assert count_faces(str(tmp_path / "a.stl")) == 3
    (tmp_path / "m.dae").write_text('<COLLADA><triangles material="x" count="12"/><polylist count="30">'
                                    "</polylist></COLLADA>")
    assert count_faces(str(tmp_path / "m.dae")) == 42


def test_a_mesh_beyond_the_face_bound_is_refused(bounded, tmp_path):
    mesh = sheet(tmp_path / "heavy.obj", MAX_FACES + 1000)
    with bounded.client(timeout=600) as client:
        reply = client.call("spawn", name="heavy", urdf=urdf(mesh), base_dir=str(tmp_path))
        assert reply["result"] == "LIMIT_EXCEEDED", reply
        assert f"more than {MAX_FACES} faces" in reply["message"] and "--max-faces" in reply["message"]
        assert "heavy" not in {r["name"] for r in client.list()}


def test_a_robot_beyond_the_link_bound_is_refused(bounded, tmp_path):
    with bounded.client(timeout=600) as client:
        reply = client.call("spawn", name="long", urdf=urdf(links=MAX_LINKS + 1), base_dir=str(tmp_path))
        assert reply["result"] == "LIMIT_EXCEEDED", reply
        assert f"{MAX_LINKS + 1} links" in reply["message"] and "--max-links" in reply["message"]
        client.request("spawn", name="short", urdf=urdf(links=MAX_LINKS), pose={"x": 5.0})
        client.delete("short")


def test_a_big_allowed_mesh_loads_while_the_world_steps(bounded, tmp_path):
    mesh = sheet(tmp_path / "big.obj", MAX_FACES - 1000)
    reply: dict = {}
    with bounded.client(timeout=600) as client:
        thread = threading.Thread(target=lambda: reply.update(bounded.client(timeout=600).call(
            "spawn", name="big", urdf=urdf(mesh), base_dir=str(tmp_path), pose={"x": -5.0})))
        thread.start()
        steps = []
        while thread.is_alive():
            steps.append(client.ping()["step"])
        thread.join()
        assert reply["ok"], reply
        # Counted, expanded and checked in a loader: the world's step counter moved meanwhile.
        assert len(set(steps)) >= 3 and steps[-1] > steps[0], steps
        client.delete("big")


def test_spawns_beyond_the_robot_bound_are_refused(bounded, tmp_path):
    with bounded.client(timeout=600) as client:
        alive = len(client.list())
        for i in range(MAX_ROBOTS - alive):
            client.request("spawn", name=f"r{i}", urdf=urdf(), pose={"x": 2.0 * i, "y": 10.0})
        reply = client.call("spawn", name="one_too_many", urdf=urdf(), pose={"y": -10.0})
        assert reply["result"] == "LIMIT_EXCEEDED", reply
        assert f"at most {MAX_ROBOTS}" in reply["message"] and "--max-robots" in reply["message"]
        client.delete("r0")  # room again
        client.request("spawn", name="again", urdf=urdf(), pose={"y": -10.0})
        for name in [f"r{i}" for i in range(1, MAX_ROBOTS - alive)] + ["again"]:
            client.delete(name)


@pytest.mark.parametrize("option", ["--max-faces", "--max-links", "--max-robots"])
def test_a_bound_below_one_is_a_usage_error(option):
    outcome = invoke(["serve", option, "0"])
    assert outcome.exit_code == 2 and "Traceback" not in outcome.stderr
    assert outcome.stderr.startswith(f"mobot: error: {option} 0 must be at least 1"), outcome.stderr
