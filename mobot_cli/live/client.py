"""A small client of the live world; the CLI uses it, and so can any Python program.

    from mobot_cli.live.client import Client
    with Client() as world:                      # $MOBOT_ENDPOINT or the default IPC socket
        world.spawn("r1", description="mobot", pose={"x": 1.0, "y": 2.0})
        world.cmd("r1", linear=0.2, for_=2.0, wait=True)
        print(world.odom("r1")["odom"]["x"])

Every method returns the reply document and raises RequestRefused when the world refuses
(``reply["result"]`` names why) or LiveWorldError when nothing answers within ``timeout``.
Over ``tcp://`` the client authenticates with CURVE (keys.py): this user's client key, and
the server's public key from ``server_key``, $MOBOT_SERVER_KEY or the key folder's server.key.
"""

from __future__ import annotations

import itertools
import os
import time
from typing import Any

import zmq

from mobot_cli.errors import LiveWorldError, RequestRefused
from mobot_cli.live import endpoint as endpoints
from mobot_cli.live import keys, protocol
from mobot_cli.live.protocol import HARD_LIMIT_BYTES, Refusal, decode_reply, encode_request

START_HINT = "Start one with `mobot serve` (in another terminal), or point --endpoint / MOBOT_ENDPOINT at it."
TCP_HINT = ("A tcp:// live world answers only clients it has authorised, and the client must hold the "
            "server's public key: see `mobot serve`'s message or the README's Security section.")


class Client:
    """One connection to a live world; requests are answered in order, one at a time."""

    def __init__(self, endpoint: str | None = None, timeout: float = 5.0, server_key: str | None = None):
        self.endpoint = endpoints.check(endpoint or endpoints.default_endpoint(), bind_any=True)
        self.timeout = timeout
        self.server_key = server_key  # tcp://: the server's public key file
        self._ids = itertools.count(1)
        self._context = zmq.Context.instance()
        self._socket: zmq.Socket | None = None

    def _connect(self) -> zmq.Socket:
        if self._socket is None:
            path = endpoints.ipc_path(self.endpoint)
            if path is not None and not os.path.exists(path):
                raise LiveWorldError(f"no live world at {self.endpoint} (no socket file)", hint=START_HINT)
            # DEALER with an empty delimiter frame: the server sees what a REQ socket sends,
            # but a late reply to a timed-out request cannot wedge the socket.
            socket = self._context.socket(zmq.DEALER)
            socket.setsockopt(zmq.LINGER, 0)
            socket.setsockopt(zmq.MAXMSGSIZE, HARD_LIMIT_BYTES)
            if path is None:
                try:
                    keys.secure_client(socket, self.server_key)
                except BaseException:
                    socket.close()
                    raise
            socket.connect(self.endpoint)
            self._socket = socket
        return self._socket

    def request(self, op: str, timeout: float | None = None, **fields: Any) -> dict[str, Any]:
        """Send one request and wait for its reply; RequestRefused unless it is OK."""
        reply = self.call(op, timeout=timeout, **fields)
        if not reply.get("ok"):
            raise RequestRefused(str(reply.get("result")), str(reply.get("message")))
        return reply

    def call(self, op: str, timeout: float | None = None, **fields: Any) -> dict[str, Any]:
        """Send one request and return its reply, refused or not; LiveWorldError on silence."""
        socket = self._connect()
        request_id = next(self._ids)
        try:  # the world would refuse it without its id (or never get it): no reply would come
            frame = encode_request({"op": op, "id": request_id, **fields})
        except Refusal as exc:
            return protocol.reply(request_id, exc.result, exc.message)
        socket.send_multipart([b"", frame])
        limit = self.timeout if timeout is None else timeout
        deadline = time.monotonic() + limit
        while socket.poll(max(0, int(1000 * (deadline - time.monotonic())))):
            reply = decode_reply(socket.recv_multipart()[-1])
            if reply is not None and reply.get("id") == request_id:
                return reply
            # Otherwise a late reply to an earlier request that timed out: skip it.
        self.close()  # drop the unanswered request so a later one does not read its reply
        hint = START_HINT if endpoints.ipc_path(self.endpoint) is not None else f"{START_HINT} {TCP_HINT}"
        raise LiveWorldError(f"no live world answered at {self.endpoint} within {limit:g} s", hint=hint)

    def ping(self) -> dict[str, Any]:
        """World name, step, sim time, robot count, pace."""
        return self.request("ping")

    def spawn(self, name: str, *, description: str | None = None, urdf: str | None = None,
              timeout: float | None = None, **fields: Any) -> dict[str, Any]:
        """Spawn a robot; the reply carries its final name, namespace and pose."""
        body = {k: v for k, v in {"description": description, "urdf": urdf, **fields}.items()
                if v is not None}
        return self.request("spawn", timeout=timeout, name=name, **body)

    def delete(self, name: str) -> dict[str, Any]:
        """Remove a robot."""
        return self.request("delete", name=name)

    def spawn_mover(self, name: str, **fields: Any) -> dict[str, Any]:
        """Add a mover now; ``fields`` as a scenario's movers: item (docs/movers.md)."""
        return self.request("spawn_mover", mover={"name": name, **fields})

    def delete_mover(self, name: str) -> dict[str, Any]:
        """Remove a mover (or a world's actor)."""
        return self.request("delete_mover", name=name)

    def list(self) -> list[dict[str, Any]]:
        """The robots in the world, in spawn order."""
        return self.request("list")["robots"]

    def cmd(self, name: str, linear: float = 0.0, angular: float = 0.0, for_: float | None = None,
            wait: bool = False, timeout: float | None = None, linear_y: float = 0.0) -> dict[str, Any]:
        """Command a body twist (``linear_y``: sideways, holonomic robots only); with ``for_`` it
        ends with a stop, with ``wait`` the reply waits for it."""
        fields: dict[str, Any] = {"name": name, "linear": linear, "angular": angular}
        if linear_y:
            fields["linear_y"] = linear_y
        if for_ is not None:
            fields["for"] = for_
            fields["wait"] = wait
        return self.request("cmd", timeout=timeout, **fields)

    def goto(self, name: str, x: float, y: float, yaw: float | None = None, wait: bool = False,
             timeout: float | None = None, **settings: Any) -> dict[str, Any]:
        """Drive to (x, y) (then ``yaw``); ``settings``: tolerance, timeout_s, localization,
        max_linear, max_angular. With ``wait`` the reply says how the goal ended."""
        fields = {"name": name, "x": x, "y": y, "yaw": yaw, "wait": wait,
                  **{("timeout" if k == "timeout_s" else k): v for k, v in settings.items()}}
        return self.request("goto", timeout=timeout, **{k: v for k, v in fields.items() if v is not None})

    def odom(self, name: str) -> dict[str, Any]:
        """The robot's odometry, ground truth and command now."""
        return self.request("odom", name=name)

    def scan(self, name: str, sensor: str | None = None) -> dict[str, Any]:
        """The latest reading of a robot's sensor (default: its first lidar)."""
        return self.request("scan", name=name, **({"sensor": sensor} if sensor else {}))

    def pause(self) -> dict[str, Any]:
        """Pause the world (idempotent); the reply's ``state`` is 'paused'."""
        return self.request("pause")

    def resume(self) -> dict[str, Any]:
        """Let the world play on (idempotent); the reply's ``state`` is 'playing'."""
        return self.request("resume")

    def step(self, steps: int | None = None, seconds: float | None = None, states: bool = True,
             timeout: float | None = None) -> dict[str, Any]:
        """Advance a paused world exactly ``steps`` (default 1) or ``seconds``; the reply comes when
        done, with every robot's pose and twist unless ``states`` is False."""
        fields: dict[str, Any] = {"states": states}
        if steps is not None:
            fields["steps"] = steps
        if seconds is not None:
            fields["seconds"] = seconds
        return self.request("step", timeout=timeout, **fields)

    def reset(self) -> dict[str, Any]:
        """Back to the scenario's start at t = 0."""
        return self.request("reset")

    def get_state(self, name: str, reference_frame: str | None = None) -> dict[str, Any]:
        """A robot's pose and twist, in the world or another robot's frame."""
        return self.request("get_state", name=name, **({"reference_frame": reference_frame} if reference_frame else {}))

    def set_state(self, name: str, pose: dict[str, Any], twist: dict[str, Any] | None = None,
                  reference_frame: str | None = None) -> dict[str, Any]:
        """Teleport a robot (checked like a spawn); ``twist`` {linear: {x, y, z}, angular: {...}}."""
        fields: dict[str, Any] = {"name": name, "pose": pose}
        if twist is not None:
            fields["twist"] = twist
        if reference_frame:
            fields["reference_frame"] = reference_frame
        return self.request("set_state", **fields)

    def features(self) -> dict[str, Any]:
        """What the server supports, as simulation_interfaces' SimulatorFeatures."""
        return self.request("features")

    def stop(self) -> dict[str, Any]:
        """Shut the world down cleanly (it writes its record first)."""
        return self.request("stop")

    def close(self) -> None:
        """Close the connection (the next request opens a new one)."""
        if self._socket is not None:
            self._socket.close(linger=0)
            self._socket = None

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
