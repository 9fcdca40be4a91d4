"""A live client cannot take the server over: no code runs, no file outside the allowed folders is
read, no request or description crashes or stalls the world. Each exploit string is shown to work
against stock xacro (a user's own files keep that behaviour) and to be refused for a live spawn."""

from __future__ import annotations

import json
import os
import sys
import threading
import time
from pathlib import Path
from unittest import mock

import pytest
import zmq

from mobot_cli.assets import sandbox
from mobot_cli.assets.description.xacro import expand_file
from mobot_cli.assets.resources import ResourceResolver
from mobot_cli.errors import DescriptionError
from mobot_cli.live import protocol
from mobot_cli.live.schema import parse
from mobot_cli.live.spawning import load_plan
from tests.live.live_server import LiveProcess, fast_world

HEAD = '<?xml version="1.0"?>\n<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">\n'
SECRET = "SECRET-TOKEN-4711"


def robot(body: str) -> str:
    return f"{HEAD}{body}\n</robot>\n"


@pytest.fixture(scope="module")
def live(tmp_path_factory):
    with fast_world(tmp_path_factory) as server:
        yield server


@pytest.fixture(scope="module")
def outside(tmp_path_factory) -> Path:
    """A folder outside everything a live spawn may read, holding a secret."""
    folder = tmp_path_factory.mktemp("outside")
    (folder / "secret.yaml").write_text(f"token: {SECRET}\n")
    (folder / "secret.xacro").write_text(robot(f'<link name="{SECRET}"/>'))
    return folder


def raw_exchange(endpoint: str, frame: bytes, timeout_ms: int = 30_000) -> dict:
    socket = zmq.Context.instance().socket(zmq.DEALER)
    socket.setsockopt(zmq.LINGER, 0)
    socket.connect(endpoint)
    try:
        socket.send_multipart([b"", frame])
        assert socket.poll(timeout_ms), "no reply"
        return json.loads(socket.recv_multipart()[-1])
    finally:
        socket.close()


# -- finding 1: a non-finite number in a request killed the server ---------------------------

@pytest.mark.parametrize("frame", [
    b'{"op": "ping", "id": 1e999}',
    b'{"op": "ping", "id": [1, {"deep": -1e999}]}',
    b'{"op": "cmd", "name": "x", "linear": 1e400}',
    b'{"op": "spawn", "name": "r", "description": "mobot", "pose": {"x": Infinity}}',
    b'{"op": "list", "id": -Infinity}',
    b'{"op": "ping", "id": NaN}',
])
def test_non_finite_numbers_are_refused_and_the_server_lives(live, frame):
    reply = raw_exchange(live.endpoint, frame)
    assert (reply["ok"], reply["result"], reply["code"], reply["id"]) == (False, "INVALID_REQUEST", 900, None)
    assert "not finite" in reply["message"] or "not a number JSON allows" in reply["message"]
    assert live.process.poll() is None
    with live.client() as client:
        assert client.ping()["ok"]


def test_deep_nesting_is_refused(live):
    for depth in (40, 200_000):
        reply = raw_exchange(live.endpoint, b'{"op": "ping", "id": ' + b"[" * depth + b"]" * depth + b"}")
        assert reply["result"] == "INVALID_REQUEST" and "nests deeper than 32 levels" in reply["message"]


def test_the_reply_encoder_never_raises():
    class Odd:
        def __str__(self):
            raise RuntimeError("no text")

    for answer, echoed in (({"id": float("inf"), "x": 1}, None), ({"id": 3, "x": float("nan")}, 3),
                           ({"id": 3, "x": Odd()}, 3), ({"id": [[]], "x": {1: float("-inf")}}, [[]])):
        reply = json.loads(protocol.encode_reply(answer))
        assert (reply["result"], reply["code"], reply["id"]) == ("OPERATION_FAILED", 4, echoed)
    assert json.loads(protocol.encode_reply({"id": 1, "ok": True}))["ok"] is True


# -- finding 2: xacro in a spawn request ran code and read files ------------------------------

def exploits(marker: Path, outside: Path) -> dict[str, str]:
    """Exploit descriptions: each writes ``marker`` or reads the secret with stock xacro."""
    secret = outside / "secret.yaml"
    return {
        "dollar-eval builtins": robot(
            f"""<xacro:property name="cmd" value="eval open('{marker}', 'w').write('owned')"/>\n"""
            '<link name="$(${cmd})"/>'),
        "comprehension hides dunders": robot(
            f"""<link name="${{[c.__init__.__globals__['system']('echo owned > {marker}') """
            "for c in [0] for c in c.__class__.__base__.__subclasses__() if c.__name__ == '_wrap_close']}\"/>"),
        # A lambda's body is a code object of its own, which stock xacro does not look into on any
        # Python (a comprehension is one only before 3.12, which inlines it: PEP 709).
        "lambda hides dunders": robot(
            f"""<link name="${{(lambda: [c.__init__.__globals__['system']('echo owned > {marker}') """
            "for c in (0).__class__.__base__.__subclasses__() if c.__name__ == '_wrap_close'])()}\"/>"),
        "python.vars": robot(
            "<link name=\"${[s for s in [python.vars(python.type)['__subclasses__'](python.int.mro()[-1])] "
            "for w in s if w.__name__ == '_wrap_close'][0]}\"/>"),
        "generator frame": robot(
            '<link name="${[f for g in [(x for x in [1])] for f in [g.gi_frame.f_back]]}"/>'),
        "str.format": robot(
            '<xacro:property name="fmt" value="{0.__init__.__globals__[os].environ}"/>\n'
            '<link name="${fmt.format(xacro.fatal)}"/>'),
        "load_yaml": robot(f"""<link name="${{xacro.load_yaml('{secret}')['token']}}"/>"""),
        "load_yaml /etc/passwd": robot("""<link name="${xacro.load_yaml('/etc/passwd')}"/>"""),
        "include": robot(f'<xacro:include filename="{outside / "secret.xacro"}"/>'),
        "glob include": robot(f'<xacro:include filename="{outside}/*.xacro"/>'),
    }


def test_the_exploits_work_against_stock_xacro(tmp_path, outside):
    """The control: unconfined (a user's own files), the same strings run code and read the secret."""
    marker = tmp_path / "marker"
    cases = exploits(marker, outside)
    hidden = "comprehension hides dunders" if sys.version_info < (3, 12) else "lambda hides dunders"
    for name in ("dollar-eval builtins", hidden):
        marker.unlink(missing_ok=True)
        path = tmp_path / f"{name.replace(' ', '_')}.urdf.xacro"
        path.write_text(cases[name])
        try:
            expand_file(path, {}, ResourceResolver(tmp_path))
        except DescriptionError:
            pass  # the link name is junk; the code ran before that
        assert marker.exists(), name
    path = tmp_path / "yaml.urdf.xacro"
    path.write_text(cases["load_yaml"])
    assert SECRET in expand_file(path, {}, ResourceResolver(tmp_path)).text


@pytest.mark.parametrize("name", ["dollar-eval builtins", "comprehension hides dunders", "lambda hides dunders",
                                  "python.vars",
                                  "generator frame", "str.format", "load_yaml", "load_yaml /etc/passwd",
                                  "include", "glob include"])
def test_live_spawns_refuse_the_exploits(live, tmp_path, outside, name):
    marker = tmp_path / "marker"
    with live.client() as client:
        reply = client.call("spawn", name="evil", urdf=exploits(marker, outside)[name])
        assert client.ping()["ok"]
    assert (reply["ok"], reply["result"], reply["code"]) == (False, "RESOURCE_PARSE_ERROR", 106), reply
    text = json.dumps(reply)
    assert SECRET not in text and "root:" not in text and "/usr/bin" not in text  # no file, no os.environ
    assert not marker.exists()


@pytest.mark.parametrize("body, message", [
    ('<link name="${().__class__}"/>', "uses the attribute '__class__'"),
    ('<link name="${[x.__class__ for x in [1]]}"/>', "uses the attribute '__class__'"),
    ('<link name="${(lambda _x: 1)(2)}"/>', "uses the name '_x'"),
    ('<link name="${python.list(x for x in [1])}"/>', "uses a generator expression"),
    ("<link name=\"${'a'.format_map}\"/>", "uses the attribute 'format_map'"),
    ('<link name="$(env HOME)"/>', "$(env HOME) is not available to a live spawn"),
])
def test_refusals_say_why(live, body, message):
    with live.client() as client:
        reply = client.call("spawn", name="evil", urdf=robot(body))
    assert reply["result"] == "RESOURCE_PARSE_ERROR" and message in reply["message"], reply["message"]


def test_meshes_outside_the_allowed_folders_are_refused(live, outside):
    mesh = outside / "part.stl"
    mesh.write_text("solid x\nendsolid x\n")
    body = (f'<link name="a"><visual><geometry><mesh filename="file://{mesh}"/></geometry></visual>'
            '<collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>')
    with live.client() as client:
        reply = client.call("spawn", name="evil", urdf=robot(body))
        missing = client.call("spawn", name="evil", urdf=robot(body.replace("part.stl", "none.stl")))
    assert reply["result"] == "MISSING_ASSETS"
    assert "which is outside the folders a live spawn may read" in reply["message"]
    assert missing["message"] == reply["message"].replace("part.stl", "none.stl")  # no existence oracle


def test_optenv_takes_its_default_in_a_live_spawn(live):
    """The server's environment is not read: $(optenv HOME x) is x, not the server's HOME."""
    body = '<link name="$(optenv HOME nohome)"><inertial><mass value="1"/>' \
           '<inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>' \
           '<collision><geometry><box size="0.2 0.2 0.1"/></geometry></collision></link>'  # rests, never falls
    with live.client(timeout=90) as client:  # a cold load on a busy machine
        client.spawn("envless", urdf=robot(body), pose={"x": 40.0})
        assert client.odom("envless")["child_frame_id"] == "envless/nohome"


def test_a_package_with_includes_and_yaml_loads_confined(live, tmp_path):
    """Legitimate xacro still works: relative includes, $(find), load_yaml and math in its package."""
    package = tmp_path / "my_bot"
    (package / "urdf").mkdir(parents=True)
    (package / "package.xml").write_text("<package><name>my_bot</name></package>")
    (package / "config.yaml").write_text("wheel: {radius: 0.05}\n")
    (package / "urdf" / "parts.xacro").write_text(
        HEAD.replace('name="r" ', "") + '<xacro:macro name="box" params="n"><link name="${n}">'
        '<inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>'
        '<collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision>'  # rests, never falls
        "</link></xacro:macro></robot>")
    (package / "urdf" / "bot.urdf.xacro").write_text(robot(
        '<xacro:include filename="parts.xacro"/>\n'
        "<xacro:property name=\"r\" value=\"${xacro.load_yaml('$(find my_bot)/config.yaml')['wheel']['radius']}\"/>\n"
        '<xacro:box n="base_${python.int(r * 1000 * math.cos(0))}"/>'))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    with live.client(timeout=90) as client:  # a cold load on a busy machine
        reply = client.spawn("pkg_bot", description=str(package / "urdf" / "bot.urdf.xacro"),
                             base_dir=str(elsewhere), pose={"x": 44.0})
        assert client.odom(reply["name"])["child_frame_id"] == "pkg_bot/base_50"


def test_the_request_base_dir_widens_what_a_text_spawn_may_read(live, tmp_path):
    (tmp_path / "dims.yaml").write_text("size: 7\n")
    # A collision box: a link with none falls through the floor and, in a --fast world, out of it
    # (a fault that removes it) within a fraction of a second, which a busy machine's next
    # request may not beat.
    body = (f"""<link name="part_${{xacro.load_yaml('{tmp_path}/dims.yaml')['size']}}"><inertial><mass value="1"/>"""
            '<inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>'
            '<collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision></link>')
    with live.client(timeout=90) as client:  # a cold load on a busy machine
        refused = client.call("spawn", name="dims", urdf=robot(body))
        client.spawn("dims", urdf=robot(body), base_dir=str(tmp_path), pose={"x": 48.0})
        assert client.odom("dims")["child_frame_id"] == "dims/part_7"
    assert refused["result"] == "RESOURCE_PARSE_ERROR" and "outside the folders" in refused["message"]


def test_confinement_is_only_for_live_spawns(tmp_path, outside):
    """A user's own file may still load a yaml anywhere; inside confined() it may not."""
    path = tmp_path / "own.urdf.xacro"
    path.write_text(exploits(tmp_path / "m", outside)["load_yaml"])
    assert SECRET in expand_file(path, {}, ResourceResolver(tmp_path)).text
    with sandbox.confined([tmp_path], [path]), pytest.raises(sandbox.OutsideRoots):
        expand_file(path, {}, ResourceResolver(tmp_path))
    assert SECRET in expand_file(path, {}, ResourceResolver(tmp_path)).text  # the cache keeps them apart


# -- finding 3: a hostile description froze the world -----------------------------------------

@pytest.fixture(scope="module")
def paced(tmp_path_factory):
    """A real-time server with short load limits (the bundled robot's cache made warm first)."""
    cache = tmp_path_factory.getbasetemp() / "mobot-cache"
    with mock.patch.dict(os.environ, {"MOBOT_CACHE_DIR": str(cache)}):
        load_plan(parse({"op": "spawn", "name": "warm", "description": "mobot"}), 240)
    server = LiveProcess("--load-timeout", "2", "--load-memory", "256", cache_dir=cache)
    yield server
    assert server.process.poll() is None, f"the server died: {server.output()}"
    server.kill()


def pace_during(server, urdf: str) -> tuple[dict, list[float], float, float]:
    """(the hostile spawn's reply, the world's simulated times in the pings it answered while the
    load ran, the longest a ping waited, how long the load took). Compared with one another, not
    with the wall clock: a busy machine slows the world and the load alike."""
    answer: dict = {}
    thread = threading.Thread(target=lambda: answer.update(raw_exchange(
        server.endpoint, json.dumps({"op": "spawn", "name": "hostile", "urdf": urdf}).encode(), 600_000)))
    with server.client(timeout=600) as client:
        client.ping()
        started = time.monotonic()
        thread.start()
        during: list[float] = []
        longest = 0.0
        while thread.is_alive():
            sent = time.monotonic()
            t = client.ping()["t"]
            longest = max(longest, time.monotonic() - sent)
            if thread.is_alive():
                during.append(t)
            time.sleep(0.02)
        took = time.monotonic() - started
    thread.join()
    return answer, during, longest, took


@pytest.mark.parametrize("expression, message", [
    # The attacker's: seconds of big-int arithmetic, stopped at 2 s of CPU time (or 6 s of wall time
    # when a busy machine gives the loader less than a third of a core). Endless loops: test_live_loader.
    ("7**(10**7)", "; it was stopped"),
    ("'x' * (2**30)", "needs more memory than a live spawn may use"),
])
def test_a_hostile_description_never_stalls_the_world(paced, expression, message):
    reply, during, longest, took = pace_during(paced, robot(f'<link name="${{{expression}}}"/>'))
    assert reply["result"] == "RESOURCE_PARSE_ERROR", reply
    if message:
        assert message in reply["message"]
    # Stalled by a loader in its own thread, the world would answer no ping until the load was over,
    # and that one ping would have waited as long as the load (bench/bench_live.py measures the pace).
    assert longest < max(0.5, took / 2), f"a ping waited {longest:.2f} s of the load's {took:.2f} s"
    if "stopped" in message:  # seconds of CPU: the world answered ping after ping, its clock moving
        assert len(during) >= 5 and during[-1] > during[0], (during, took)
    with paced.client(timeout=600) as client:  # the next spawn finds a loader (a warm one: bench_live)
        client.spawn(f"after_{len(expression)}", description="mobot", pose={"x": 3.0 * len(expression), "y": 30.0})


