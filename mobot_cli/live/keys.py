"""CURVE keys for TCP endpoints: who may talk to a live world over the network, ZeroMQ's own way.

Everything lives in one private folder (mode 0700): ``$MOBOT_KEYS_DIR``, else
``$XDG_CONFIG_HOME/mobot/keys``, else ``~/.config/mobot/keys``:

    server.key, server.key_secret   the server's key pair (made by the first `mobot serve` on TCP)
    client.key, client.key_secret   this user's client key pair (made on first use); always authorised
    authorized/NAME.key             public keys of other clients the server accepts

Secret files are 0600. A client finds the server's public key in ``$MOBOT_SERVER_KEY`` (a file),
else in ``server.key`` of its own folder (the same machine). The server re-reads ``authorized/``
whenever a client connects, so authorising a machine needs no restart.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

import zmq

from mobot_cli.errors import LiveWorldError, Location, UsageError

ENV_DIR = "MOBOT_KEYS_DIR"
ENV_SERVER_KEY = "MOBOT_SERVER_KEY"
AUTHORIZED = "authorized"


def keys_dir() -> Path:
    """The key folder (not created)."""
    explicit = os.environ.get(ENV_DIR)
    if explicit:
        return Path(explicit).expanduser()
    xdg = os.environ.get("XDG_CONFIG_HOME")
    return (Path(xdg).expanduser() if xdg else Path.home() / ".config") / "mobot" / "keys"


def server_pair() -> tuple[bytes, bytes]:
    """The server's (public, secret) key, made on first use."""
    return _pair("server")


def client_pair() -> tuple[bytes, bytes]:
    """This user's client (public, secret) key, made on first use."""
    return _pair("client")


def server_public(path: str | os.PathLike | None = None) -> bytes:
    """The public key a client expects the server to have: ``path``, $MOBOT_SERVER_KEY or server.key."""
    from zmq.auth import load_certificate

    file = Path(path or os.environ.get(ENV_SERVER_KEY) or keys_dir() / "server.key").expanduser()
    try:
        public, _ = load_certificate(file)
    except (OSError, ValueError):
        raise LiveWorldError(f"no live world known: no server public key at {file} (a tcp:// live world "
                             "only answers clients that hold its key)",
                             hint="Start one with `mobot serve` on this machine (a tcp:// one makes the key), "
                                  f"or copy server.key from the server's key folder "
                                  f"({_shown(keys_dir())} there) to {file}, or point {ENV_SERVER_KEY} at it.") from None
    return public


def authorized_keys() -> set[bytes]:
    """Public keys (Z85) the server accepts: this user's client key and every authorized/*.key."""
    from zmq.auth import load_certificate

    keys = {client_pair()[0]}
    folder = keys_dir() / AUTHORIZED
    for file in sorted(folder.glob("*.key")) if folder.is_dir() else ():
        try:
            keys.add(load_certificate(file)[0])
        except (OSError, ValueError):
            continue  # not a key file: it authorises nobody
    return keys


class _Authorized:
    """The credentials provider zmq.auth asks about each connecting client."""

    def callback(self, domain: str, key: bytes) -> bool:
        return key in authorized_keys()


def secure_server(socket: zmq.Socket):
    """Make ``socket`` a CURVE server that only authorised clients get through; returns the authenticator."""
    from zmq.auth.thread import ThreadAuthenticator

    public, secret = server_pair()
    client_pair()  # the user's own client key exists (and is authorised) from the start
    _private(keys_dir() / AUTHORIZED)
    authenticator = ThreadAuthenticator(socket.context)
    authenticator.start()
    authenticator.configure_curve_callback(domain="*", credentials_provider=_Authorized())
    socket.curve_secretkey, socket.curve_publickey = secret, public
    socket.curve_server = True
    return authenticator


def secure_client(socket: zmq.Socket, server_key: str | os.PathLike | None = None) -> None:
    """Make ``socket`` a CURVE client with this user's key, expecting the server's public key."""
    server = server_public(server_key)
    public, secret = client_pair()
    socket.curve_secretkey, socket.curve_publickey, socket.curve_serverkey = secret, public, server


def authorise_hint() -> str:
    """How to let another machine in, for `mobot serve` to print."""
    folder = _shown(keys_dir())
    return (f"Clients need a key: this user's are authorised. To authorise another machine, copy its "
            f"~/.config/mobot/keys/client.key here to {folder}/{AUTHORIZED}/NAME.key, and copy "
            f"{folder}/server.key there to ~/.config/mobot/keys/server.key (or set {ENV_SERVER_KEY}).")


def _pair(name: str) -> tuple[bytes, bytes]:
    from zmq.auth import create_certificates, load_certificate

    folder = keys_dir()
    _private(folder)
    secret_file = folder / f"{name}.key_secret"
    if not secret_file.exists():
        old = os.umask(0o077)  # born private: no window in which others could read the secret
        try:
            create_certificates(folder, name)
        finally:
            os.umask(old)
    info = secret_file.stat()
    if info.st_uid != os.getuid() or info.st_mode & (stat.S_IRWXG | stat.S_IRWXO):
        raise UsageError(f"{secret_file} can be read by other users (or is not yours)",
                         location=Location(file=secret_file),
                         hint=f"Run `chmod 600 {secret_file}`, or delete it to make a new key pair.")
    public, secret = load_certificate(secret_file)
    if secret is None:
        raise UsageError(f"{secret_file} holds no secret key", location=Location(file=secret_file),
                         hint="Delete it (and its .key) to make a new key pair.")
    return public, secret


def _private(folder: Path) -> None:
    """The folder exists, is ours and only we can write it (else anyone could authorise a key)."""
    try:
        folder.mkdir(mode=0o700, parents=True, exist_ok=True)
        info = folder.stat()
    except OSError as exc:
        raise UsageError(f"cannot make the key folder {folder}: {exc.strerror}", location=Location(file=folder),
                         hint=f"Set {ENV_DIR} to a folder of your own.") from None
    if info.st_uid != os.getuid():
        raise UsageError(f"{folder} belongs to another user; it cannot hold your keys",
                         location=Location(file=folder), hint=f"Set {ENV_DIR} to a folder of your own.")
    if info.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        raise UsageError(f"{folder} is writable by other users, who could authorise their own keys",
                         location=Location(file=folder), hint=f"Run `chmod 700 {folder}`.")


def _shown(path: Path) -> str:
    home = str(Path.home())
    text = str(path)
    return "~" + text[len(home):] if text.startswith(home + os.sep) else text
