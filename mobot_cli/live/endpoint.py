"""Where the live world listens: a private IPC socket by default, TCP on loopback if asked.

Only ``ipc://`` and ``tcp://`` endpoints are accepted. A TCP endpoint must name a loopback
address unless the server is started with ``--bind-any``: a live world accepts spawns of
any file the server can read, so it must not be reachable from the network by accident.
"""

from __future__ import annotations

import ipaddress
import os
import stat
import tempfile
from pathlib import Path
from typing import Callable

from mobot_cli.errors import Location, UsageError

ENV = "MOBOT_ENDPOINT"
SOCKET_NAME = "mobot.sock"
# sun_path holds 108 bytes on Linux, including the terminating NUL.
MAX_IPC_PATH = 107
LOOPBACK_NAMES = ("localhost", "ip6-localhost")


def runtime_dir(create: bool = False) -> Path:
    """$XDG_RUNTIME_DIR/mobot, else a per-user folder under the temp dir (mode 0700)."""
    xdg = os.environ.get("XDG_RUNTIME_DIR")
    folder = Path(xdg) / "mobot" if xdg else Path(tempfile.gettempdir()) / f"mobot-{os.getuid()}"
    if create:
        private_dir(folder)
    return folder


def private_dir(folder: Path) -> None:
    """Create ``folder`` with mode 0700, or refuse one that another user owns or can write."""
    folder.mkdir(mode=0o700, parents=True, exist_ok=True)
    info = folder.stat()
    if info.st_uid != os.getuid():
        raise UsageError(f"{folder} belongs to another user; it cannot hold a private socket",
                         hint="Pass --endpoint with a folder of your own, or set XDG_RUNTIME_DIR.")
    if info.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        raise UsageError(f"{folder} is writable by other users; it cannot hold a private socket",
                         hint=f"Run `chmod 700 {folder}`, or pass --endpoint elsewhere.")


def default_endpoint() -> str:
    """$MOBOT_ENDPOINT, else the IPC socket in the user's runtime folder."""
    return os.environ.get(ENV) or f"ipc://{runtime_dir() / SOCKET_NAME}"


def ipc_path(endpoint: str) -> Path | None:
    """The socket file of an ipc:// endpoint; None for TCP."""
    return Path(endpoint[len("ipc://"):]) if endpoint.startswith("ipc://") else None


def check(endpoint: str, bind_any: bool = False) -> str:
    """A usable endpoint, or a UsageError saying what is wrong with it."""
    endpoint = endpoint.strip()
    path = ipc_path(endpoint)
    if path is not None:
        if not str(path) or str(path).startswith("@"):
            raise UsageError(f"endpoint '{endpoint}' needs a socket file path", hint="Use e.g. ipc:///tmp/mobot.sock.")
        if len(os.fsencode(str(path))) > MAX_IPC_PATH:
            raise UsageError(f"the socket path of '{endpoint}' is longer than {MAX_IPC_PATH} bytes",
                             hint="Unix sockets need short paths: pick a shorter folder.")
        return endpoint
    if not endpoint.startswith("tcp://"):
        raise UsageError(f"endpoint '{endpoint}' is neither ipc:// nor tcp://",
                         hint="Use e.g. ipc:///tmp/mobot.sock or tcp://127.0.0.1:5555.")
    host, sep, port = endpoint[len("tcp://"):].rpartition(":")
    if not sep or not host or not (port.isdigit() or port == "*"):
        raise UsageError(f"endpoint '{endpoint}' is not tcp://HOST:PORT", hint="Use e.g. tcp://127.0.0.1:5555.")
    if not bind_any and not is_loopback(host):
        raise UsageError(f"endpoint '{endpoint}' is not a loopback address: the live world would be "
                         "reachable from the network", hint="Use tcp://127.0.0.1:PORT, or pass --bind-any "
                         "if you really mean to serve other machines.")
    return endpoint


def is_loopback(host: str) -> bool:
    """True for 127.0.0.0/8, ::1 and localhost."""
    host = host.strip("[]")
    if host in LOOPBACK_NAMES:
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def claim_socket_file(endpoint: str, path: Path, server_pid: Callable[[str], int | None]) -> None:
    """Refuse to take over a live server's socket or any file that is not a socket; remove a stale one.

    ``server_pid(endpoint)`` asks whoever answers there for its pid, None when nobody does."""
    if path.parent == runtime_dir() or not path.parent.exists():
        private_dir(path.parent)  # made 0700, or checked to be the user's own
    try:
        info = os.lstat(path)
    except FileNotFoundError:
        return
    except OSError as exc:
        raise UsageError(f"cannot use {endpoint}: {exc.strerror}", location=Location(file=path),
                         hint="Pick another --endpoint.") from None
    if not stat.S_ISSOCK(info.st_mode):
        kind = "a symbolic link" if stat.S_ISLNK(info.st_mode) else (
            "a folder" if stat.S_ISDIR(info.st_mode) else "a file that is not a socket")
        raise UsageError(f"endpoint {endpoint} names {kind}; mobot serve only replaces a stale socket "
                         "and leaves it untouched", location=Location(file=path),
                         hint="Pick a path that does not exist yet, e.g. ipc:///tmp/mobot-$USER/mobot.sock.")
    pid = server_pid(endpoint)
    if pid is None:
        os.unlink(path)  # nobody answers: a server that died without cleaning up
        return
    raise UsageError(f"a live world (pid {pid}) already serves at {endpoint}",
                     hint=f"Stop it with `mobot stop --endpoint {endpoint}`, or pick another --endpoint.")


def bind(endpoint: str, server_pid: Callable[[str], int | None]):
    """The server's ROUTER socket listening at ``endpoint``: (socket, CURVE authenticator or None,
    the endpoint as bound). An ipc socket file is claimed first and born 0600; a TCP endpoint only
    lets clients with an authorised key through the handshake, and ``:*`` reports the port it got."""
    import zmq

    from mobot_cli.live import keys
    from mobot_cli.live.protocol import HARD_LIMIT_BYTES

    path = ipc_path(endpoint)
    if path is not None:
        claim_socket_file(endpoint, path, server_pid)
    socket = zmq.Context.instance().socket(zmq.ROUTER)
    socket.setsockopt(zmq.LINGER, 0)
    socket.setsockopt(zmq.MAXMSGSIZE, HARD_LIMIT_BYTES)  # larger: the peer is dropped
    authenticator = None
    try:
        if path is None:
            authenticator = keys.secure_server(socket)
        old = os.umask(0o177)  # the socket file is born 0600: no window with looser rights
        try:
            socket.bind(endpoint)
        except zmq.ZMQError as exc:
            raise UsageError(f"cannot listen at {endpoint}: {exc}",
                             hint="Pick another --endpoint (is another server using it?).") from None
        finally:
            os.umask(old)
    except BaseException:
        if authenticator is not None:
            authenticator.stop()
        socket.close()
        raise
    if path is not None:
        os.chmod(path, 0o600)
        return socket, authenticator, endpoint
    return socket, authenticator, socket.getsockopt_string(zmq.LAST_ENDPOINT)
