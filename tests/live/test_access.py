"""Who can reach a live world and what it leaves behind: CURVE on TCP, ipc paths that are not
sockets, bounded history lines and a bounded cache of spawned descriptions."""

from __future__ import annotations

import json
import os
import shutil
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest
import zmq
from zmq.auth import create_certificates, load_certificate

from mobot_cli.common import cache
from mobot_cli.errors import UsageError
from mobot_cli.live import keys
from mobot_cli.live.client import Client
from mobot_cli.sim.bullet import urdf_file
from tests.live.live_server import REPO, LiveProcess


@pytest.fixture(scope="module")
def tcp(tmp_path_factory):
    server = LiveProcess("--fast", endpoint="tcp://127.0.0.1:*",
                         cache_dir=tmp_path_factory.getbasetemp() / "mobot-cache")
    yield server
    assert server.process.poll() is None, f"the server died: {server.output()}"
    server.kill()


def silent(socket: zmq.Socket, endpoint: str, wait_ms: int = 2000) -> bool:
    """True when a ping over ``socket`` gets no reply within ``wait_ms``."""
    socket.setsockopt(zmq.LINGER, 0)
    socket.connect(endpoint)
    try:
        socket.send_multipart([b"", b'{"op": "ping"}'], zmq.NOBLOCK)
    except zmq.Again:
        return True  # the handshake never completed: nothing could even be queued
    try:
        return socket.poll(wait_ms) == 0
    finally:
        socket.close()


def test_tcp_serves_only_authorised_clients(tcp):
    with Client(tcp.endpoint, timeout=10) as client:  # this user's own key: authorised
        assert client.ping()["ok"]
    plain = zmq.Context.instance().socket(zmq.DEALER)
    assert silent(plain, tcp.endpoint)
    stranger = zmq.Context.instance().socket(zmq.DEALER)
    public, secret = zmq.curve_keypair()
    stranger.curve_publickey, stranger.curve_secretkey = public, secret
    stranger.curve_serverkey = keys.server_public()
    assert silent(stranger, tcp.endpoint)
    with Client(tcp.endpoint, timeout=10) as client:  # the server kept serving
        assert client.ping()["ok"]
    assert "authorized/NAME.key" in tcp.output() and "server.key" in tcp.output()


def test_authorising_another_machine(tcp, tmp_path, monkeypatch):
    """Its client.key copied into authorized/, our server.key copied there: no restart needed."""
    other = tmp_path / "other-machine"
    other.mkdir(mode=0o700)
    create_certificates(other, "client")
    os.chmod(other / "client.key_secret", 0o600)
    monkeypatch.setenv("MOBOT_KEYS_DIR", str(other))
    monkeypatch.setenv("MOBOT_SERVER_KEY", str(tmp_path / "copied-server.key"))
    with pytest.raises(Exception, match="no server public key"):
        Client(tcp.endpoint, timeout=2).ping()
    monkeypatch.undo()
    shutil.copy(keys.keys_dir() / "server.key", tmp_path / "copied-server.key")
    monkeypatch.setenv("MOBOT_KEYS_DIR", str(other))
    monkeypatch.setenv("MOBOT_SERVER_KEY", str(tmp_path / "copied-server.key"))
    socket = zmq.Context.instance().socket(zmq.DEALER)
    keys.secure_client(socket)
    assert silent(socket, tcp.endpoint)  # not yet authorised
    monkeypatch.undo()
    shutil.copy(other / "client.key", keys.keys_dir() / "authorized" / "other.key")
    monkeypatch.setenv("MOBOT_KEYS_DIR", str(other))
    monkeypatch.setenv("MOBOT_SERVER_KEY", str(tmp_path / "copied-server.key"))
    with Client(tcp.endpoint, timeout=10) as client:
        assert client.ping()["ok"]


def test_cli_commands_use_curve_on_tcp(tcp):
    done = subprocess.run([sys.executable, "-m", "mobot_cli", "list", "--endpoint", tcp.endpoint, "--json"],
                          capture_output=True, text=True, cwd=REPO, timeout=60)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["result"] == "OK"


def test_keys_are_private(tmp_path, monkeypatch):
    monkeypatch.setenv("MOBOT_KEYS_DIR", str(tmp_path / "keys"))
    public, secret = keys.client_pair()
    assert load_certificate(tmp_path / "keys" / "client.key_secret") == (public, secret)
    assert stat.S_IMODE((tmp_path / "keys").stat().st_mode) == 0o700
    assert stat.S_IMODE((tmp_path / "keys" / "client.key_secret").stat().st_mode) == 0o600
    assert keys.client_pair() == (public, secret)  # made once
    os.chmod(tmp_path / "keys" / "client.key_secret", 0o644)
    with pytest.raises(UsageError, match="can be read by other users"):
        keys.client_pair()
    os.chmod(tmp_path / "keys", 0o777)
    with pytest.raises(UsageError, match="writable by other users, who could authorise their own keys"):
        keys.server_pair()


# -- finding 4: an ipc endpoint on an existing file --------------------------------------------

def serve_at(path: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mobot_cli", "serve", "--endpoint", f"ipc://{path}"],
                          capture_output=True, text=True, cwd=REPO, timeout=60)


def test_serve_leaves_a_regular_file_alone(tmp_path):
    victim = tmp_path / "notes.txt"
    victim.write_text("keep me\n")
    done = serve_at(victim)
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith(f"mobot: error: {victim}: endpoint ipc://{victim} names a file that is "
                                  "not a socket; mobot serve only replaces a stale socket and leaves it untouched")
    assert victim.read_text() == "keep me\n"


def test_serve_refuses_a_folder_and_a_symlink(tmp_path):
    folder = tmp_path / "folder.sock"
    folder.mkdir()
    (folder / "inside").write_text("x")
    done = serve_at(folder)
    assert done.returncode == 2 and "names a folder" in done.stderr and "Traceback" not in done.stderr
    assert (folder / "inside").read_text() == "x"
    target = tmp_path / "target"
    target.write_text("target\n")
    link = tmp_path / "link.sock"
    link.symlink_to(target)
    done = serve_at(link)
    assert done.returncode == 2 and "names a symbolic link" in done.stderr
    assert link.is_symlink() and target.read_text() == "target\n"


# -- finding 11: records a client could blow up --------------------------------------------------

def test_history_lines_stay_small(tmp_path):
    out = tmp_path / "rec"
    server = LiveProcess("--fast", cache_dir=tmp_path / "cache", out=out)
    try:
        huge = "n" * 3_000_000
        with server.client() as client:
            assert client.call("spawn", name=huge, description="mobot")["result"] == "NAME_INVALID"
            assert client.call("delete", name=huge)["result"] == "INVALID_REQUEST"
            assert client.call("cmd", name={"a": [huge[:1000]] * 100})["result"] == "INVALID_REQUEST"
            client.stop()
        assert server.wait() == 0
    finally:
        server.kill()
    lines = (out / "history.jsonl").read_text().splitlines()
    assert len(lines) == 3 and all(len(line) < 4000 for line in lines), [len(line) for line in lines]
    first = json.loads(lines[0])
    assert first["name"] == "n" * 256 + "...[cut: 3000000 chars]" and first["result"] == "NAME_INVALID"
    squeezed = json.loads(lines[2])["name"]  # 100 long items: the field is a cut piece of its JSON
    # 32 items of 256 + markers
    assert squeezed.startswith('{"a": ["nnnn') and squeezed.endswith("...[cut: 8987 chars]")


def test_the_spawned_description_cache_keeps_the_most_recently_used(tmp_path, monkeypatch):
    monkeypatch.setenv("MOBOT_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(cache, "CACHE_MAX_FILES", 3)
    paths = []
    for i in range(5):
        paths.append(urdf_file.urdf_path(f"<robot name='r{i}'/>", folder="spawned"))
        past = time.time() - 100 + i
        os.utime(paths[-1], (past, past))
    urdf_file.urdf_path("<robot name='r0'/>", folder="spawned")  # used again: the most recent
    urdf_file.urdf_path("<robot name='r5'/>", folder="spawned")
    left = sorted(p.name for p in (tmp_path / "spawned").iterdir())
    assert len(left) == 3 and paths[0].name in left and paths[4].name in left and paths[1].name not in left


def test_the_cache_is_bounded_by_size_too(tmp_path):
    for i, size in enumerate((100, 100, 100, 5000)):
        (tmp_path / f"{i}.urdf").write_text("x" * size)
        os.utime(tmp_path / f"{i}.urdf", (1000 + i, 1000 + i))
    assert cache.prune(tmp_path, max_files=10, max_bytes=5150) == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["2.urdf", "3.urdf"]
    assert cache.prune(tmp_path, max_files=10, max_bytes=10) == 1  # the newest always stays
    assert [p.name for p in tmp_path.iterdir()] == ["3.urdf"]
