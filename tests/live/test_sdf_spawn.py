"""Gazebo SDF models spawned into a real `mobot serve`: from a model folder, a `model://` URI and
SDF text, driven by their DiffDrive system; and the same confinement as URDF and xacro spawns
(a model reads nothing outside the folders a live spawn may read, and a refusal says nothing of
what is there).

The model is tests/data/sdf_models/rover: a diff-drive rover written as gz-sim writes one (wheels
rolled about x, turning about their own z, the DiffDrive system), with a deck mesh it finds as
``model://rover/meshes/deck.obj``.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from mobot_cli.cli import invoke
from tests.live.live_server import REPO, fast_world

MODELS = REPO / "tests" / "data" / "sdf_models"
ROVER = MODELS / "rover"
SDF = (ROVER / "model.sdf").read_text()


@pytest.fixture(scope="module")
def live(tmp_path_factory):
    with fast_world(tmp_path_factory) as server:
        yield server


def drive_straight(client, name: str, start_x: float) -> float:
    """The ground-truth distance the robot covers for 0.3 m/s over 3 simulated s (0.9 m)."""
    before = client.odom(name)["truth"]
    assert before["x"] == pytest.approx(start_x, abs=0.01)
    client.cmd(name, linear=0.3, for_=3.0, wait=True, timeout=60)
    after = client.odom(name)["truth"]
    assert abs(after["roll"]) < 0.05 and abs(after["pitch"]) < 0.05  # on its wheels, not tipped
    return math.hypot(after["x"] - before["x"], after["y"] - before["y"])


@pytest.mark.parametrize("how", ["folder", "model.sdf", "model:// URI", "text"])
def test_an_sdf_model_spawns_and_drives(live, how):
    spawn = {"folder": {"description": str(ROVER)},
             "model.sdf": {"description": str(ROVER / "model.sdf")},
             "model:// URI": {"description": "model://rover", "base_dir": str(MODELS)},
             "text": {"urdf": SDF, "base_dir": str(MODELS)}}[how]  # base_dir: where model://rover is
    name = f"rover_{['folder', 'model.sdf', 'model:// URI', 'text'].index(how)}"
    x = 10.0 * (1 + ["folder", "model.sdf", "model:// URI", "text"].index(how))
    with live.client(timeout=90) as client:  # a cold load on a busy machine
        reply = client.spawn(name, pose={"x": x}, **spawn)
        assert reply["name"] == name
        # the DiffDrive system drives it: 0.3 m/s for 3 s (measured 0.892 m; the wheels slip a little)
        assert drive_straight(client, name, x) == pytest.approx(0.9, rel=0.03)


def test_the_cli_spawns_an_sdf_model_folder(live):
    done = invoke(["spawn", "cli_rover", "--file", str(ROVER), "-x", "60", "--endpoint", live.endpoint])
    assert done.exit_code == 0, done.stderr
    assert "spawned 'cli_rover'" in done.stdout


def test_sdf_text_without_its_models_names_what_is_missing(live):
    with live.client(timeout=90) as client:
        reply = client.call("spawn", name="lost", urdf=SDF)
    assert (reply["ok"], reply["result"]) == (False, "MISSING_ASSETS")
    assert reply["message"].startswith("robot 'lost': <sdf text>:") and "model 'rover' not found" in reply["message"]
    assert ".cache" not in reply["message"]  # the folder the text was written to is not one it may read


@pytest.mark.parametrize("text", [
    "<sdf version='1.9'><world name='w'><model name='m'><link name='l'/></model></world></sdf>",
    "<?xml version='1.0'?>\n<!-- a world -->\n<sdf version='1.6'>\n  <world name='default'/>\n</sdf>",
])
def test_an_sdf_world_is_not_a_robot(live, text, tmp_path):
    with live.client() as client:
        reply = client.call("spawn", name="w", urdf=text)
    assert (reply["ok"], reply["result"]) == (False, "UNSUPPORTED_FORMAT")
    assert "an SDF world, not a model" in reply["message"]
    world = tmp_path / "shop.world"
    world.write_text(text)
    with live.client() as client:
        reply = client.call("spawn", name="w", description=str(world))
    assert (reply["ok"], reply["result"]) == (False, "UNSUPPORTED_FORMAT") and "shop.world" in reply["message"]


@pytest.fixture(scope="module")
def outside(tmp_path_factory) -> Path:
    """A folder no spawn here may read, with a mesh and a model in it."""
    folder = tmp_path_factory.mktemp("outside")
    (folder / "secret.obj").write_text((ROVER / "meshes" / "deck.obj").read_text())
    (folder / "spy").mkdir()
    (folder / "spy" / "model.config").write_text("<model><name>spy</name><sdf>model.sdf</sdf></model>")
    (folder / "spy" / "model.sdf").write_text(SDF.replace('name="rover"', 'name="spy"'))
    return folder


@pytest.mark.parametrize("uri", ["{outside}/secret.obj", "file://{outside}/secret.obj", "/etc/passwd"])
def test_a_mesh_outside_the_allowed_folders_is_refused_alike_whether_there_or_not(live, outside, uri):
    there = uri.format(outside=outside)
    missing = there.replace("secret.obj", "absent.obj").replace("passwd", "no_such_file")
    replies = []
    with live.client(timeout=90) as client:
        for mesh in (there, missing):
            replies.append(client.call("spawn", name="spy", urdf=SDF.replace("model://rover/meshes/deck.obj", mesh),
                                       base_dir=str(MODELS)))
        assert client.ping()["ok"]
    assert [r["result"] for r in replies] == ["RESOURCE_PARSE_ERROR"] * 2
    assert "outside the folders a live spawn may read" in replies[0]["message"]
    assert replies[1]["message"] == replies[0]["message"].replace(there, missing).replace(
        there.removeprefix("file://"), missing.removeprefix("file://"))  # no existence oracle


def test_an_include_outside_the_allowed_folders_is_refused(live, outside):
    """<include> of a model folder by absolute path, and model://NAME found only outside."""
    include = f"<include><uri>file://{outside}/spy</uri><name>spy</name></include>\n    "
    by_path = SDF.replace('<link name="chassis">', include + '<link name="chassis">')
    by_name = by_path.replace(f"file://{outside}/spy", "model://spy")
    with live.client(timeout=90) as client:
        path_reply = client.call("spawn", name="inc", urdf=by_path, base_dir=str(MODELS))
        name_reply = client.call("spawn", name="inc", urdf=by_name, base_dir=str(MODELS))
    assert path_reply["result"] == "RESOURCE_PARSE_ERROR", path_reply
    assert "outside the folders a live spawn may read" in path_reply["message"]
    assert name_reply["result"] == "MISSING_ASSETS" and "model 'spy' not found" in name_reply["message"]
    assert str(outside) not in name_reply["message"]


def test_an_entity_bomb_behind_a_doctype_is_refused_as_sdf(live):
    """A billion laughs in the DOCTYPE of SDF text: read as SDF (past its prolog), refused by the
    XML parser's amplification limit, named as SDF text; the world answers on."""
    entities = '<!ENTITY a "aaaaaaaaaa">' + "".join(
        f'<!ENTITY {b} "{("&" + a + ";") * 10}">' for a, b in zip("abcde", "bcdef"))
    bomb = f'<?xml version="1.0"?>\n<!DOCTYPE sdf [{entities}]>\n<sdf version="1.9"><model name="&f;"/></sdf>'
    with live.client() as client:
        reply = client.call("spawn", name="bomb", urdf=bomb)
        assert client.ping()["ok"]
    assert reply["result"] == "RESOURCE_PARSE_ERROR" and reply["message"].startswith("robot 'bomb': <sdf text>")
    assert "entity" in reply["message"]


def test_sdf_text_with_an_entity_is_refused_not_spawned_as_a_default_box(live):
    """An entity of the DOCTYPE is not expanded (as Gazebo's reader does not): refused, naming it."""
    text = ('<?xml version="1.0"?><!DOCTYPE sdf [<!ENTITY d "0.3">]><sdf version="1.9"><model name="m"><link name="l">'
            '<collision name="c"><geometry><box><size>&d; 1 1</size></box></geometry></collision></link></model></sdf>')
    with live.client() as client:
        reply = client.call("spawn", name="ent", urdf=text)
        assert client.ping()["ok"]
    assert reply["result"] == "RESOURCE_PARSE_ERROR", reply
    assert "the XML entity &d; is not expanded" in reply["message"]


def test_features_list_sdf(live):
    with live.client() as client:
        assert "sdf" in client.features()["spawn_formats"]
