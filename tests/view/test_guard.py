"""The view obeys only its owner: raw HTTP and websocket clients, as another local user or a
DNS-rebinding web page would come, are refused with 403 and read nothing; with the token they get
the page. Whatever a client sets into the page's widgets is bounded by the server.
"""

from __future__ import annotations

import socket
import time
import urllib.error
import urllib.request

import pytest

viser = pytest.importorskip("viser", reason="the view extra (viser) is not installed")
websockets = pytest.importorskip("websockets.sync.client")  # both come with viser
msgspec = pytest.importorskip("msgspec")
InvalidStatus = pytest.importorskip("websockets.exceptions").InvalidStatus


@pytest.fixture
def page():
    from mobot_cli.view.page import close_page, open_page

    server = open_page(0)
    yield server
    close_page(server)


def http_get(port: int, path: str, **headers: str) -> tuple[int, bytes, dict]:
    request = urllib.request.Request(f"http://127.0.0.1:{port}{path}", headers=headers)
    try:
        with urllib.request.urlopen(request, timeout=20) as reply:
            return reply.status, reply.read(), dict(reply.headers)
    except urllib.error.HTTPError as exc:
        return exc.code, exc.read(), dict(exc.headers)


def open_socket(port: int, path: str, host: str = "127.0.0.1", **kwargs):
    """A websocket to the page; ``host`` names it in the handshake, the socket goes to 127.0.0.1."""
    return websockets.connect(f"ws://{host}:{port}{path}", subprotocols=[f"viser-v{viser.__version__}"],
                              sock=socket.create_connection(("127.0.0.1", port), timeout=20),
                              open_timeout=20, **kwargs)


def test_the_printed_address_carries_a_fresh_token(page):
    from mobot_cli.view.page import close_page, open_page, url

    other = open_page(0)
    try:
        first, second = url(page), url(other)
    finally:
        close_page(other)
    assert first.startswith(f"http://127.0.0.1:{page.get_port()}/?token=")
    token = first.split("token=")[1]
    assert len(token) >= 40 and token != second.split("token=")[1]


@pytest.mark.parametrize("path, headers, why", [
    ("/", {}, "no valid token"),
    ("/?token=wrong", {}, "no valid token"),
    ("/?token={token}", {"Host": "evil.example:{port}"}, "wrong Host"),  # DNS rebinding
    ("/?token={token}", {"Host": "127.0.0.1:1"}, "wrong Host"),
    ("/?token={token}", {"Origin": "http://evil.example"}, "foreign Origin"),
    ("/", {"Cookie": "mobot-view-{port}=wrong"}, "no valid token"),
])
def test_a_page_request_without_the_owners_credentials_gets_403_and_no_page(page, path, headers, why):
    port, token = page.get_port(), page.mobot_guard.token
    headers = {k: v.format(port=port, token=token) for k, v in headers.items()}
    status, body, reply_headers = http_get(port, path.format(token=token), **headers)
    assert status == 403 and why in body.decode()
    assert len(body) < 200 and "Set-Cookie" not in reply_headers  # the page's 800 kB never left


def test_the_token_opens_the_page_and_leaves_a_cookie_for_its_websocket(page):
    port, token = page.get_port(), page.mobot_guard.token
    status, body, headers = http_get(port, f"/?token={token}")
    assert status == 200 and body.startswith(b"<!doctype html>") and len(body) > 100_000
    cookie = headers["Set-Cookie"]
    assert cookie.startswith(f"mobot-view-{port}={token};") and "HttpOnly" in cookie and "SameSite=Strict" in cookie
    assert http_get(port, "/", Cookie=f"mobot-view-{port}={token}")[0] == 200


@pytest.mark.parametrize("path, kwargs", [
    ("/", {}),
    ("/?token=wrong", {}),
    ("/?token={token}", {"origin": "http://evil.example"}),
    ("/?token={token}", {"origin": "http://127.0.0.1:{port}.evil.example"}),
    ("/?token={token}", {"additional_headers": {"Host": "evil.example:{port}"}}),  # two Hosts
    ("/?token={token}", {"host": "evil.example"}),  # DNS rebinding: the attacker's name, our address
])
def test_a_websocket_without_the_owners_credentials_is_refused_before_any_scene_data(page, path, kwargs):
    port, token = page.get_port(), page.mobot_guard.token
    page.scene.add_frame("/secret_pose", position=(1.0, 2.0, 3.0))
    kwargs = {k: ({h: v.format(port=port) for h, v in value.items()} if isinstance(value, dict)
                  else value.format(port=port)) for k, value in kwargs.items()}
    refused = page.mobot_guard.refused
    with pytest.raises(InvalidStatus) as caught:
        open_socket(port, path.format(token=token), **kwargs)
    assert caught.value.response.status_code == 403
    assert b"secret_pose" not in caught.value.response.body
    assert page.mobot_guard.refused == refused + 1


@pytest.mark.parametrize("how", ["query", "cookie", "own origin"])
def test_the_owners_websocket_gets_the_scene(page, how):
    port, token = page.get_port(), page.mobot_guard.token
    page.scene.add_frame("/owned_pose", position=(1.0, 2.0, 3.0))
    path, kwargs = {"query": (f"/?token={token}", {}),
                    "cookie": ("/", {"additional_headers": {"Cookie": f"mobot-view-{port}={token}"}}),
                    "own origin": (f"/?token={token}", {"origin": f"http://127.0.0.1:{port}"})}[how]
    with open_socket(port, path, **kwargs) as connection:
        assert len(connection.recv(timeout=20)) > 0  # the scene's backlog starts coming


def _send(connection, uuid: str, value) -> None:
    connection.send(msgspec.msgpack.encode({"type": "GuiUpdateMessage", "uuid": uuid, "updates": {"value": value}}))


def _hello(connection) -> None:
    """What a browser sends first (its camera): viser counts a client as connected from then on."""
    connection.send(msgspec.msgpack.encode({
        "type": "ViewerCameraMessage", "wxyz": [1.0, 0.0, 0.0, 0.0], "position": [3.0, 3.0, 3.0], "fov": 1.0,
        "near": 0.01, "far": 100.0, "image_height": 700, "image_width": 1000, "look_at": [0.0, 0.0, 0.0],
        "up_direction": [0.0, 0.0, 1.0]}))


def _wait_for(predicate, what: str) -> None:
    deadline = time.monotonic() + 60  # only catches what never happens, busy machine or not
    while not predicate():
        assert time.monotonic() < deadline, what
        time.sleep(0.02)


def test_a_hostile_page_client_cannot_step_without_bound_or_drive_fast_and_pause_stops_stepping(page):
    """A client with the token sets 10^12 steps and 1000 m/s into the widgets: bounded at the server."""
    from mobot_cli.live.lockstep import Lockstep
    from mobot_cli.view.controls import MAX_ANGULAR, MAX_LINEAR, GateControl, add_controls

    gate, sent = Lockstep(paused=True), []
    add_controls(page, GateControl(gate, lambda *args: sent.append(args)), lambda: "r1", rate_hz=240,
                 max_steps=5000)
    # The widgets' ids, which a page learns from the scene it is sent.
    uuids = {handle.label: uuid for uuid, handle in page.gui._gui_input_handle_from_uuid.items()}  # noqa: SLF001
    with open_socket(page.get_port(), f"/?token={page.mobot_guard.token}") as connection:
        _hello(connection)
        _send(connection, uuids["steps per Step"], 10**12)
        _send(connection, uuids["world"], "Step")
        _wait_for(lambda: gate.budget > 0, "the Step click never arrived")
        assert gate.budget == 5000  # one click's maximum, not 10^12
        _send(connection, uuids["world"], "Step")
        _wait_for(lambda: gate.budget == 10_000, "the second Step click never arrived")
        _send(connection, uuids["world"], "Pause")
        _wait_for(lambda: gate.budget == 0, "Pause left steps owed")
        assert gate.paused and gate.hold()  # nothing more is stepped

        _send(connection, uuids["speed (m/s)"], 1000.0)
        _send(connection, uuids["turn (rad/s)"], float("inf"))
        _send(connection, uuids["drive"], "▲")
        _wait_for(lambda: len(sent) == 1, "the pad's click never arrived")
        _send(connection, uuids["drive"], "◀")
        _wait_for(lambda: len(sent) == 2, "the pad's second click never arrived")
    assert sent[0][:3] == ("r1", MAX_LINEAR, 0.0) and MAX_LINEAR == 2.0
    assert sent[1][:3] == ("r1", 0.0, 0.0)  # inf is no speed: the pad turns at 0, not at inf
    assert MAX_ANGULAR == 3.0
